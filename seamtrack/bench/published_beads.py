"""seamtrack's bead on a flat plate against a published bead-on-plate table.

seamtrack sizes a bead from mass conservation (its area, :func:`~seamtrack.workpiece.beads.
bead_area_mm2`) and a fixed shape (:class:`~seamtrack.workpiece.beads.BeadShape`: a parabola
of width-to-height 3 in the shipped scenes), so ``w`` and ``h`` both grow as
``sqrt(v_wire / v_travel)`` whatever the voltage or the travel speed itself. This module sets
that against single beads measured at several wire feeds and travel speeds.

The source
----------
Li R., Ma H., Bai X., Xue B., Li C., Zeng K., Fu Y., Liu Y., Zhang Y. (2025). Explainable
prediction of bead geometry in laser-arc hybrid additive manufacturing of Al-Cu alloy using a
particle swarm optimization-based ensemble model. *Materials Science in Additive
Manufacturing* 4(3), doi:10.36922/MSAM025220036. Table 5 (design matrix and measured bead
width ``W`` and height ``H``), read at :data:`SOURCE_URL`; the factor levels are its Table 4
(wire feed 6/7/8 m/min, welding speed 500/600/700 mm/min, arc-length correction 5/10/15 %,
pulse correction 0/1/2 %, laser power 1/2/3 kW): laser + CMT beads of ER2319 wire on 2219-T6
plate. :data:`PUBLISHED_BEADS` quotes the eight of its 46 runs that sit at the design's centre
for everything but wire feed and travel speed (arc length 10 %, pulse 1 %, laser 2 kW): four
replicates at 7 m/min and 600 mm/min and the four corners 6/8 m/min x 500/700 mm/min.

What is compared
----------------
The wire diameter could not be read from the source (the page that would give it was not
retrievable), so the model's one scale, the effective wire area ``K = eta pi d^2 / 4``, is
calibrated on the four centre replicates (:data:`CALIBRATION_RUNS`: their mean ``c W H`` is the
model's area there, ``c`` the shape's area factor) and the four corners are held out. The
calibrated ``K`` gives an effective diameter ``sqrt(4 K / pi)``: a check that the rows are
consistent with mass conservation from a common wire, not a fact from the source.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, NamedTuple

from seamtrack.bench.common import markdown_table
from seamtrack.workpiece.beads import BeadShape, bead_area_mm2

__all__ = [
    "CALIBRATION_RUNS",
    "PUBLISHED_BEADS",
    "SHIPPED_SHAPE",
    "SOURCE",
    "SOURCE_URL",
    "BeadComparison",
    "PublishedBead",
    "beads_table",
    "bench_beads",
    "compare",
    "comparison_rows",
    "effective_wire_diameter_mm",
    "worst_held_out",
]

SOURCE = (
    "Li et al. 2025, Materials Science in Additive Manufacturing 4(3), "
    "doi:10.36922/MSAM025220036, Table 5"
)
SOURCE_URL = (
    "https://article.accscience.com/read-online/full-issue/MSAM/4-3/files/basic-html/page63.html"
)


class PublishedBead(NamedTuple):
    """One measured bead on a flat plate (a row of the source's Table 5)."""

    run: int
    wire_feed_m_min: float
    travel_speed_mm_min: float
    width_mm: float
    height_mm: float

    @property
    def feed_ratio(self) -> float:
        """``v_wire / v_travel`` (dimensionless)."""
        return self.wire_feed_m_min * 1000.0 / self.travel_speed_mm_min


#: Table 5 runs at arc-length correction 10 %, pulse correction 1 %, laser power 2 kW.
PUBLISHED_BEADS: tuple[PublishedBead, ...] = (
    PublishedBead(2, 7.0, 600.0, 8.49, 2.69),
    PublishedBead(5, 7.0, 600.0, 7.85, 2.60),
    PublishedBead(17, 7.0, 600.0, 8.36, 2.52),
    PublishedBead(45, 7.0, 600.0, 8.49, 2.59),
    PublishedBead(4, 8.0, 700.0, 7.14, 2.54),
    PublishedBead(21, 6.0, 700.0, 7.25, 2.54),
    PublishedBead(23, 6.0, 500.0, 7.79, 2.56),
    PublishedBead(43, 8.0, 500.0, 10.17, 3.02),
)
#: The centre replicates (7 m/min, 600 mm/min) that calibrate the effective wire area.
CALIBRATION_RUNS = (2, 5, 17, 45)
#: The bead shape of every shipped multi-pass scene.
SHIPPED_SHAPE = BeadShape("parabola", 3.0)


class BeadComparison(NamedTuple):
    """A published bead and seamtrack's flat-plate bead at the same wire feed and travel speed.

    ``width_error``/``height_error`` are relative, (model - measured) / measured;
    ``area_ratio`` is the measured bead's ``c W H`` over the model's mass-conservation area
    (1 where the bead's size follows ``v_wire / v_travel`` exactly).
    """

    bead: PublishedBead
    held_out: bool
    width_mm: float
    height_mm: float
    width_error: float
    height_error: float
    area_ratio: float


def _effective_wire_area_mm2(
    shape: BeadShape, beads: tuple[PublishedBead, ...], calibration: tuple[int, ...]
) -> float:
    """``eta pi d^2 / 4`` that makes the model's area the calibration beads' mean ``c W H``."""
    chosen = [b for b in beads if b.run in calibration]
    if not chosen:
        raise ValueError(f"no bead of runs {calibration} in the table")
    return sum(shape.area_factor * b.width_mm * b.height_mm / b.feed_ratio for b in chosen) / len(
        chosen
    )


def effective_wire_diameter_mm(
    shape: BeadShape = SHIPPED_SHAPE,
    beads: tuple[PublishedBead, ...] = PUBLISHED_BEADS,
    calibration: tuple[int, ...] = CALIBRATION_RUNS,
) -> float:
    """The wire diameter (at deposition efficiency 1) that the calibration gives (mm)."""
    return math.sqrt(4.0 * _effective_wire_area_mm2(shape, beads, calibration) / math.pi)


def compare(
    shape: BeadShape = SHIPPED_SHAPE,
    beads: tuple[PublishedBead, ...] = PUBLISHED_BEADS,
    calibration: tuple[int, ...] = CALIBRATION_RUNS,
) -> list[BeadComparison]:
    """seamtrack's bead (mass conservation, then ``shape`` on a flat plate) at each bead's
    wire feed and travel speed, the wire's effective diameter calibrated on ``calibration``.
    """
    d_eff = effective_wire_diameter_mm(shape, beads, calibration)
    rows = []
    for b in beads:
        wire_mm_s, travel_mm_s = b.wire_feed_m_min * 1000.0 / 60.0, b.travel_speed_mm_min / 60.0
        area = float(bead_area_mm2(d_eff, wire_mm_s, travel_mm_s, 1.0))
        w, h = shape.flat_size(area)
        width, height = float(w), float(h)
        rows.append(
            BeadComparison(
                bead=b,
                held_out=b.run not in calibration,
                width_mm=width,
                height_mm=height,
                width_error=width / b.width_mm - 1.0,
                height_error=height / b.height_mm - 1.0,
                area_ratio=shape.area_factor * b.width_mm * b.height_mm / area,
            )
        )
    return rows


def worst_held_out(rows: list[BeadComparison]) -> tuple[float, float]:
    """The largest relative width and height errors (absolute) over the held-out beads."""
    held = [r for r in rows if r.held_out]
    return max(abs(r.width_error) for r in held), max(abs(r.height_error) for r in held)


def comparison_rows(rows: list[BeadComparison]) -> list[dict[str, Any]]:
    """The comparison as JSON records (lengths in mm, errors relative)."""
    return [
        {
            "run": r.bead.run,
            "wire_feed_m_min": r.bead.wire_feed_m_min,
            "travel_speed_mm_min": r.bead.travel_speed_mm_min,
            "width_measured_mm": r.bead.width_mm,
            "width_model_mm": round(r.width_mm, 6),
            "width_error": round(r.width_error, 6),
            "height_measured_mm": r.bead.height_mm,
            "height_model_mm": round(r.height_mm, 6),
            "height_error": round(r.height_error, 6),
            "area_ratio": round(r.area_ratio, 6),
            "held_out": r.held_out,
        }
        for r in rows
    ]


def beads_table(data: dict[str, Any]) -> str:
    """The comparison of :func:`bench_beads`'s JSON as a markdown table, one line per bead."""
    header = [
        "run",
        "wire feed (m/min)",
        "travel (mm/min)",
        "W measured (mm)",
        "W model (mm)",
        "W error",
        "H measured (mm)",
        "H model (mm)",
        "H error",
        "W/H measured",
        "c W H / mass balance",
        "use",
    ]
    body = [
        [
            str(r["run"]),
            f"{r['wire_feed_m_min']:g}",
            f"{r['travel_speed_mm_min']:g}",
            f"{r['width_measured_mm']:.2f}",
            f"{r['width_model_mm']:.2f}",
            f"{100 * r['width_error']:+.1f} %",
            f"{r['height_measured_mm']:.2f}",
            f"{r['height_model_mm']:.2f}",
            f"{100 * r['height_error']:+.1f} %",
            f"{r['width_measured_mm'] / r['height_measured_mm']:.2f}",
            f"{r['area_ratio']:.2f}",
            "held out" if r["held_out"] else "calibration",
        ]
        for r in data["rows"]
    ]
    return "\n".join(markdown_table(header, body, right=[True] * 11 + [False])) + "\n"


def bench_beads(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """The shipped bead against :data:`PUBLISHED_BEADS`: writes ``beads.json`` and ``beads.md``.

    ``quick`` changes nothing (the comparison takes a millisecond); it is there for the
    dispatcher.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = compare()
    held = [r for r in rows if r.held_out]
    width, height = worst_held_out(rows)
    result: dict[str, Any] = {
        "source": SOURCE,
        "source_url": SOURCE_URL,
        "model": {
            "shape": SHIPPED_SHAPE.kind,
            "width_to_height": SHIPPED_SHAPE.width_to_height,
            "calibration_runs": list(CALIBRATION_RUNS),
            "effective_wire_diameter_mm": round(effective_wire_diameter_mm(), 6),
        },
        "held_out": {
            "max_width_error": round(width, 6),
            "max_height_error": round(height, 6),
            "rms_width_error": round(math.sqrt(sum(r.width_error**2 for r in held) / len(held)), 6),
            "rms_height_error": round(
                math.sqrt(sum(r.height_error**2 for r in held) / len(held)), 6
            ),
        },
        "rows": comparison_rows(rows),
    }
    (out / "beads.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "beads.md").write_text(beads_table(result))
    return result
