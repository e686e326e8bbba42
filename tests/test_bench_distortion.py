"""``seamtrack bench distortion``'s cases and tables (the loop itself runs in the bench only)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from seamtrack.bench import distortion as bench
from seamtrack.bench.distortion import PUBLISHED, PublishedCase, case_rows, cases_table


def test_every_case_names_its_source_and_says_why_a_value_is_missing() -> None:
    kinds = " ".join(c.kind for c in PUBLISHED)
    # the issue's minimum: single-pass angle, transverse shrinkage, per-pass multi-pass angle
    assert len(PUBLISHED) >= 5
    assert "single-pass" in kinds and "shrinkage" in kinds and "each pass" in kinds
    assert any(c.doi == "10.3390/app10051848" for c in PUBLISHED)  # the multi-pass anchor
    for c in PUBLISHED:
        assert c.doi or c.note, c.source
        assert c.measured is not None or "not read" in c.note, c.source


@pytest.mark.parametrize(
    ("measured", "simulated", "scatter", "bound", "within"),
    [
        (2.0, 2.39, None, "", True),  # 19.5 % off: inside the issue's 20 %
        (2.0, 2.41, None, "", False),
        (2.0, 1.59, None, "", False),
        (2.0, 2.5, 0.3, "", True),  # the source's own scatter, 30 %
        (4.0, 3.3, None, "lower", True),  # a floor: 'more than 4 mm'
        (4.0, 3.1, None, "lower", False),
    ],
)
def test_the_verdict_is_the_issues_bar(
    monkeypatch: pytest.MonkeyPatch,
    measured: float,
    simulated: float,
    scatter: float | None,
    bound: str,
    within: bool,
) -> None:
    case = PublishedCase("a paper", "10.0/x", "an angle", "deg", measured, scatter, bound)
    monkeypatch.setattr(bench, "simulate_case", lambda c: simulated)
    (row,) = case_rows((case,))
    assert row["within"] is within
    assert row["simulated"] == simulated


def test_a_range_is_met_inside_it_and_shown_as_a_range() -> None:
    case = PublishedCase("TWI", "", "a shrinkage", "mm", 2.25, 0.75 / 2.25, "range")
    inside = case_rows((dataclasses.replace(case, simulate=lambda: 2.9),))
    outside = case_rows((dataclasses.replace(case, simulate=lambda: 3.1),))
    assert inside[0]["within"] is True and outside[0]["within"] is False
    assert "| 1.50-3.00 | 2.90 | mm | yes |" in cases_table({"cases": inside})


def test_the_v_groove_area_is_the_groove_polygons() -> None:
    # an independent oracle: the shoelace area of the groove's outline (20 mm, 60 deg V,
    # 2 mm gap, 1 mm root face)
    t, gap, face, half = 20.0, 2.0, 1.0, math.radians(30.0)
    top = gap / 2 + (t - face) * math.tan(half)
    outline = [(-gap / 2, 0.0), (gap / 2, 0.0), (gap / 2, face), (top, t), (-top, t),
               (-gap / 2, face)]  # fmt: skip
    edges = zip(outline, outline[1:] + outline[:1], strict=True)
    shoelace = 0.5 * abs(sum(y0 * z1 - y1 * z0 for (y0, z0), (y1, z1) in edges))
    assert bench.v_groove_area_mm2(t, 60.0, gap, face) == pytest.approx(shoelace, rel=1e-12)


def test_the_twi_shrinkage_case_runs_spraragen_and_ettinger_on_the_shipped_joint() -> None:
    (twi,) = [c for c in PUBLISHED if c.source.startswith("TWI")]
    area = bench.v_groove_area_mm2(20.0, 60.0, 2.0, 1.0)
    assert bench.simulate_case(twi) == pytest.approx(0.2 * area / 20.0 + 0.05 * 2.0)


def test_a_case_not_read_has_no_verdict_and_says_so() -> None:
    case = PublishedCase("a paper", "", "a shrinkage", "mm", note="value not read: no text")
    (row,) = case_rows((case,))
    assert row["measured"] is None and row["within"] is None
    table = cases_table({"cases": [row]})
    assert "| not read | - | mm | - |" in table
    read = case_rows((dataclasses.replace(case, measured=1.25),))
    assert "| 1.25 | - | mm | - |" in cases_table({"cases": read})


def test_the_multipass_table_has_a_row_per_pass_and_the_jobs_totals() -> None:
    rows = [
        {"pass": f"pass_0{i}", "reference": "centre", "cap": i == 2, "angle_deg": 0.5 * i,
         "accumulated_deg": 0.5 * i * (i + 1) / 2, "max_error_mm": 0.1 * i,
         "seam_shift_at_start_mm": 0.2 * i}
        for i in (1, 2)
    ]  # fmt: skip
    job = {"rows": rows, "status": "completed", "passes": 2, "underfilled_stations": 0,
           "angular_distortion_deg": 1.5, "worst_pass_error_mm": 0.2, "wall_s": 12.0,
           "load_1min": 3.0}  # fmt: skip
    data = {"multipass": job}
    table = bench.multipass_table(data)
    assert "| pass_02 | centre (cap) | 1.00 | 1.50 | 0.40 | 0.200 |" in table
    assert "turned 1.50 deg; worst pass 0.200 mm" in table
