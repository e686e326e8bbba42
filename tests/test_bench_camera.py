"""``seamtrack bench camera`` runs and its accuracy numbers meet the must-shows (quick run; the
timings it writes are reported, never asserted)."""

from __future__ import annotations

import json

import pytest

from seamtrack.bench.camera import bench_camera

pytestmark = [pytest.mark.cad, pytest.mark.embree, pytest.mark.slow]


def test_bench_camera_quick_writes_its_tables_and_meets_the_must_shows(tmp_path) -> None:
    result = bench_camera(tmp_path, quick=True)
    assert json.loads((tmp_path / "camera.json").read_text())["quick"] is True
    text = (tmp_path / "camera.md").read_text()
    for heading in ("Ideal camera", "Speckle only", "False stripe", "Extractors", "Throughput",
                    "real-data bench", "Exposure"):  # fmt: skip
        assert heading in text
    assert max(r["rms_px"] for r in result["plane"]) < 0.05
    for row in result["speckle"]:
        assert row["centroid_ratio"] == pytest.approx(1.0, abs=0.3)
    # The sweep (issue 27 item 2): every quick case rendered; where the stripe spans several
    # pixels (512 x 1024, f/5.6 and slower) one column follows the line's speckle formula
    assert "Sweep over pixel pitch" in text
    sweep = result["speckle_sweep"]
    assert {(tuple(r["image_px"]), r["f_number"]) for r in sweep} >= {((512, 1024), 5.6)}
    for r in sweep:
        if r["image_px"] == [512, 1024] and r["f_number"] >= 5.6:
            assert r["vs_line_formula"] == pytest.approx(1.0, abs=0.3)
    assert all(r["max_error_mm"] <= 0.01 for r in result["false_stripe"])
    joints = {r["joint"] for r in result["extractors"]}
    assert joints == {"square-butt", "v-groove", "fillet", "lap", "outside-corner"}
    assert {r["profile"] for r in result["extractors"]} == {
        "geometry",
        "image, mill-scale steel",
        "image, bright aluminium",
    }
    assert all("frame_ms" in result["throughput"][k] for k in ("ideal", "full"))  # not timed

    # Section 6: the same image-mode profiles as labelled sets through the real-data bench.
    # Its oracle (the seam's crossing of the laser plane, in the plane) is independent of
    # section 4's (the distance to the seam polyline in space); where the scene runs the
    # family extractor with its defaults, both must count the same frames as detected.
    sets = {(r["family"], r["material"]): r for r in result["image_sets"]}
    assert set(sets) == {(f, m) for f in joints for m in ("mill-scale steel", "bright aluminium")}
    section4 = {(r["joint"], r["profile"].removeprefix("image, ")): r for r in result["extractors"]}
    for family in ("square-butt", "v-groove", "fillet", "outside-corner"):
        for material in ("mill-scale steel", "bright aluminium"):
            a, b = sets[family, material], section4[family, material]
            assert a["detection_rate"] == pytest.approx(b["detection_rate"])
            if a["detection_rate"] > 0:
                assert a["median_error_mm"] == pytest.approx(b["median_error_mm"], abs=2e-3)
    for row in result["image_sets"]:
        assert 0.0 <= row["false_joint_rate"] <= 1.0 and 0.0 <= row["classified_rate"] <= 1.0

    # Section 7 (issue 27.1): the default camera and detector find the stripe at every tilt,
    # within the speckle's error of the analytic plane, and keep aluminium below saturation.
    tilts = {(r["material"], r["axis"], r["tilt_deg"]) for r in result["exposure"]}
    assert {("mill-scale steel", "roll", 70.0), ("bright aluminium", "pitch", 70.0)} <= tilts
    for row in result["exposure"]:
        assert row["found"] >= 0.99 and row["p95_error_mm"] <= 0.5
        assert row["saturated"] <= 0.05
