"""Multi-pass jobs run whole (short seams): every pass a closed loop on the part and the beads
before it, tracked within 0.5 mm, the groove filled (reinforcement 0-3 mm at every station),
and ``seamtrack run`` writing one folder a pass and job.json.

Needs the groove extractor (``seamtrack.features.groove.extractor``, issue 25's ``groove``
branch)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("seamtrack.features.groove.extractor")

from seamtrack.cli.main import main
from seamtrack.control.planner import CAP_OVERLAP_MM
from seamtrack.simulation.job import run_job
from seamtrack.simulation.scene import load_scene

pytestmark = [pytest.mark.cad, pytest.mark.embree]

#: multipass-v-groove on a 12 mm plate and a 20 mm seam, 6 m/min of wire: a few passes.
SHORT = {
    "workpiece.params.seam_length_mm": 20.0,
    "workpiece.params.plate_thickness_mm": 12.0,
    "process.wire_feed_m_min": 6.0,
}


@pytest.fixture(scope="module")
def short_job():
    return run_job(load_scene("multipass-v-groove", SHORT))


def test_a_short_job_fills_the_groove(short_job) -> None:
    s = short_job.summary
    assert s["status"] == "completed", s["stop_reason"]
    welded = [r for r in short_job.passes if r.plan is not None]
    assert s["passes"] == len(welded) >= 2
    assert sum(s["beads_per_layer"]) == s["passes"]
    for r in welded:  # every pass tracked on its own reference
        assert r.result.summary["status"] == "completed", r.name
        assert r.result.summary["max_error_mm"] <= 0.5, r.name
    # at every station every pass welded: neither under- nor overfilled
    reinforcement = short_job.fill.reinforcement_mm()
    keep = (short_job.fill.s_mm >= s["stations_from_mm"]) & (
        short_job.fill.s_mm <= s["stations_to_mm"]
    )
    assert s["stations_to_mm"] - s["stations_from_mm"] >= 15.0
    assert np.all(reinforcement[keep, 0] >= 0.0)
    assert np.all(reinforcement[keep, 1] <= 3.0)
    assert s["underfilled_stations"] == 0


def test_each_bead_holds_the_wire_the_torch_melted(short_job) -> None:
    """Mass conservation over the whole pass: the metal laid (area integrated along the seam)
    is the wire the torch melted times the deposition efficiency, within the ends (the
    run-off). The wire is fed at the plan's rate, and, where the torch runs slower than the
    plan (it speeds up from rest at the seam's start and brakes to rest at its end), at the
    rate times the ratio of the speeds (the controller's synchronised arc start and crater;
    at rest no wire): integrated over the pass's trace."""
    scene = load_scene("multipass-v-groove", SHORT)
    assert scene.config.process is not None
    eta = scene.config.process.deposition_efficiency
    wire_area = np.pi * (scene.config.process.wire_diameter_mm / 2) ** 2
    fill = short_job.fill
    tangent = fill.T_world_station[:, :3, 0]
    assert np.allclose(tangent, tangent[0])  # a straight seam: arc length along its tangent
    origin = fill.T_world_station[0, :3, 3]
    welded = [r for r in short_job.passes if r.plan is not None]
    for bead, r in zip(fill.beads, welded, strict=True):
        volume = np.trapezoid(bead.area_mm2, fill.s_mm)
        trace = r.result.trace
        step = np.linalg.norm(np.diff(trace.tcp_world, axis=0), axis=1)
        dt = np.diff(trace.t_s)
        s = fill.s_mm[0] + (trace.tcp_world[:-1] - origin) @ tangent[0]
        planned = r.plan.speed_at(s)
        feed = r.plan.wire_feed_mm_s * np.minimum(1.0, step / dt / planned)
        melted = eta * wire_area * np.sum(feed * dt)
        assert volume == pytest.approx(melted, rel=0.2), r.name


def test_the_cap_beads_lie_side_to_side_across_the_bevels_top_edges(short_job) -> None:
    """The cap's n beads at their places in closed loop, as the V's geometry puts them: the
    top corners at y = +-(gap / 2 + (plate - root face) tan 30 deg), the cap over the top
    width and CAP_OVERLAP_MM beyond each corner, the k-th bead's centre in the k-th of n
    equal slots. Each cap bead but the first buries a part of the fill surface the bead
    before changed (its toe spilled over the plate moves the fill's edge, and the middle, a
    millimetre), so a bead offset from the fill surface, as planned a pass earlier, lands
    that far off its slot (1.2 mm for the second bead); one offset from the bevel's top edge
    no cap bead has reached does not."""
    p = load_scene("multipass-v-groove", SHORT).config.workpiece.params
    corner = p["root_gap_mm"] / 2 + (p["plate_thickness_mm"] - p["root_face_mm"]) * math.tan(
        math.radians(p["groove_angle_deg"] / 2)
    )
    fill = short_job.fill
    assert fill.top_corners[:, 1, 0] == pytest.approx(corner, abs=0.05)  # the CAD's, as drawn
    s = short_job.summary
    keep = (fill.s_mm >= s["stations_from_mm"]) & (fill.s_mm <= s["stations_to_mm"])
    caps = [bead for bead, r in zip(fill.beads, (r for r in short_job.passes if r.plan),
                                   strict=True) if r.plan.cap]  # fmt: skip
    n = len(caps)
    assert n == s["beads_per_layer"][-1] >= 2
    width = 2 * corner + 2 * CAP_OVERLAP_MM
    for k, bead in enumerate(caps):
        slot = -corner - CAP_OVERLAP_MM + (k + 0.5) * width / n
        assert np.max(np.abs(bead.y_centre_mm[keep] - slot)) <= 0.3, k


def test_the_adaptive_speed_follows_the_measured_area(short_job) -> None:
    """Where the groove holds more metal the torch goes slower: the pass's speed profile is
    the mass-conservation speed for the area left there (within the process window)."""
    for r in short_job.passes:
        if r.plan is None or r.plan.speed_profile_mm_s is None:
            continue
        assert np.all(r.plan.speed_profile_mm_s >= 2.0 - 1e-9)
        assert np.all(r.plan.speed_profile_mm_s <= 15.0 + 1e-9)


def test_seamtrack_run_writes_a_folder_a_pass_and_the_job(tmp_path: Path, capsys) -> None:
    out = tmp_path / "job"
    args = ["run", "multipass-v-groove", "--out", str(out), "--no-plot", "--quiet"]
    for key, value in SHORT.items():
        args += ["--set", f"{key}={value}"]
    args += ["--set", "passes.count=2"]
    assert main(args) == 0
    summary = json.loads((out / "job.json").read_text())
    assert summary["passes"] == 2
    names = sorted(p.name for p in out.iterdir() if p.is_dir())
    assert names == ["pass_00_scan", "pass_01", "pass_02"]
    for name in names:
        assert {"summary.json", "trace.csv", "frames.csv", "scene.toml"} <= {
            p.name for p in (out / name).iterdir()
        }
    assert [row["heat_input_kj_mm"] for row in summary["per_pass"][1:]] == pytest.approx(
        [0.8 * 28.0 * 250.0 / row["mean_speed_mm_s"] * 1e-3 for row in summary["per_pass"][1:]]
    )


@pytest.mark.parametrize("flag", ["--weldx", "--render", "--record"])
def test_a_job_refuses_a_single_run_export(tmp_path: Path, capsys, flag: str) -> None:
    """A job writes one folder a pass: --weldx, --render and --record (one run's exports) are
    refused with one line naming the flag, exit 2, before anything is run or written."""
    out = tmp_path / "job"
    target = {"--weldx": "run.wx", "--render": "", "--record": "run.mcap"}[flag]
    args = ["run", "multipass-v-groove", "--out", str(out), "--no-plot", "--quiet", flag]
    args += [str(tmp_path / target)] if target else []
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag in err and "fix:" in err
    assert not out.exists()
    assert not target or not (tmp_path / target).exists()
