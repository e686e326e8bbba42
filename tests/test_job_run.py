"""Multi-pass jobs run whole (short seams): every pass a closed loop on the part and the beads
before it, tracked within 0.5 mm, the groove filled (reinforcement 0-3 mm at every station),
and ``seamtrack run`` writing one folder a pass and job.json."""

from __future__ import annotations

import json
import math
import re
import shlex
import sys
from pathlib import Path

import numpy as np
import pytest

import seamtrack.features.groove.extractor  # noqa: F401 (the jobs' extractor: an ImportError fails here)
from seamtrack.cli.main import main
from seamtrack.control.fill_layout import CAP_OVERLAP_MM, cap_area_mm2
from seamtrack.control.planner import AdaptivePlanner
from seamtrack.multipass.job import run_job
from seamtrack.simulation.scene import load_scene

pytestmark = [pytest.mark.cad, pytest.mark.embree]

#: multipass-v-groove on a 12 mm plate and a 20 mm seam, 6 m/min of wire: a few passes.
SHORT = {
    "workpiece.params.seam_length_mm": 20.0,
    "workpiece.params.plate_thickness_mm": 12.0,
    "process.wire_feed_m_min": 6.0,
}


class Recording(AdaptivePlanner):
    """The built-in planner, keeping what each plan() was given: the measured groove and the
    last bead's area at its stations."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[tuple[object, np.ndarray | None]] = []

    def plan(self, groove, pass_index, state):
        last = None if state.last_bead_area_mm2 is None else state.last_bead_area_mm2.copy()
        self.seen.append((groove, last))
        return super().plan(groove, pass_index, state)


@pytest.fixture(scope="module")
def recorder():
    return Recording()


@pytest.fixture(scope="module")
def short_job(recorder):
    return run_job(load_scene("multipass-v-groove", SHORT), planner_override=recorder)


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


def test_every_beads_area_is_mass_conservation_at_every_station(short_job) -> None:
    """Issue 42 item 4: at every station each pass's bead (the area between the fill surface
    after it and before it, integrated across the seam on the fill's grid) is within 5 % of
    mass conservation from the process parameters and the plan: eta pi d^2 / 4 v_wire / v(s),
    v(s) the plan's travel speed there. The torch's own speed, which the bead follows, differs
    from the plan by the tracker's corrections (3-4 % on this job)."""
    scene = load_scene("multipass-v-groove", SHORT)
    p = scene.config.process
    assert p is not None
    fill = short_job.fill
    welded = [r for r in short_job.passes if r.plan is not None]
    assert len(welded) == len(fill.beads) >= 2
    for bead, r in zip(fill.beads, welded, strict=True):
        wire_mm_s = p.wire_feed_m_min * 1000.0 / 60.0  # the scene's wire feed, 6 m/min
        assert r.plan.wire_feed_mm_s == pytest.approx(wire_mm_s)
        speed = r.plan.speed_at(fill.s_mm)
        formula = p.deposition_efficiency * math.pi * p.wire_diameter_mm**2 / 4 * wire_mm_s / speed
        laid = np.trapezoid(bead.z_after - bead.z_before, fill.y_mm, axis=1)
        assert np.all(np.isfinite(laid)) and len(laid) == len(fill.s_mm)
        np.testing.assert_allclose(laid, formula, rtol=0.05, err_msg=r.name)


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


def test_the_adaptive_speed_follows_the_measured_area(short_job, recorder) -> None:
    """Where the groove holds more metal the torch goes slower: each fill pass's speed at a
    station is the mass-conservation speed (0.97 pi (d/2)^2 v_wire / v = area) for the area
    the sensor measured left there, less the last bead (laid after it was measured) and the
    cap's band, over the fill beads left, within the process window."""
    scene = load_scene("multipass-v-groove", SHORT)
    p = scene.config.process
    deposit = p.deposition_efficiency * math.pi * (p.wire_diameter_mm / 2) ** 2
    deposit *= p.wire_feed_m_min * 1000.0 / 60.0  # mm^3/s of metal
    lay = recorder.layout
    fill_beads = sum(lay.beads_per_layer[:-1])
    welded = [r for r in short_job.passes if r.plan is not None]
    checked = 0
    for index, (r, (groove, last)) in enumerate(zip(welded, recorder.seen, strict=False)):
        if r.plan.cap:
            continue
        band = lay.beads_per_layer[-1] * lay.cap_bead_area_mm2 - cap_area_mm2(
            groove.top_width_mm, 2.0
        )
        left_area = groove.area_mm2 - (0.0 if last is None else last)
        area = np.maximum(np.maximum(left_area - band, 0.0) / (fill_beads - index),
                          0.05 * lay.fill_bead_area_mm2)  # fmt: skip
        expected = np.clip(deposit / area, 2.0, 15.0)
        speed = r.plan.speed_at(groove.s_mm)
        np.testing.assert_allclose(speed, expected, rtol=1e-9)
        checked += int(np.count_nonzero((expected > 2.0) & (expected < 15.0)))
    assert checked > 20  # stations where the speed is the area's, not the window's edge


def test_the_docs_planner_example_runs_as_written(tmp_path: Path, monkeypatch) -> None:
    """docs/multipass.md's own planner (my_planner.py, three beads on the middle) and its
    command, run from the folder the file is in, with no PYTHONPATH (the seamtrack command
    does not put the current folder on sys.path; the planner is looked for there), on a 20 mm
    seam. Three 34 mm^2 beads (0.97 pi 0.6^2 133 / 5) in a 248 mm^2 groove: the job ends
    ``underfilled``, not ``completed``."""
    doc = (Path(__file__).parent.parent / "docs" / "multipass.md").read_text()
    code = re.search(r"```python\n(# my_planner.py\n.*?)```", doc, re.S)
    command = re.search(r"^\$ (seamtrack run multipass-v-groove --set planner\.name=.*)$", doc,
                        re.M)  # fmt: skip
    assert code and command
    (tmp_path / "my_planner.py").write_text(code.group(1))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    monkeypatch.delitem(sys.modules, "my_planner", raising=False)
    args = shlex.split(command.group(1))[1:]
    args += ["--out", "mp", "--quiet", "--no-plot", "--set", "workpiece.params.seam_length_mm=20.0"]
    assert main(args) == 0
    summary = json.loads((tmp_path / "mp" / "job.json").read_text())
    assert summary["passes"] == 3
    assert summary["status"] == "underfilled" and "did not fill" in summary["stop_reason"]
    sys.modules.pop("my_planner", None)


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


def test_the_job_is_judged_by_iso_5817(short_job) -> None:
    """job.json's quality level, by hand: on the 12 mm plate's 60 deg V with its 2 mm gap and
    1 mm root face, the weld is 2 + 2 * 11 tan(30 deg) = 14.7 mm wide, so level B allows
    1 + 0.1 b = 2.47 mm of excess weld metal and no underfill."""
    s = short_job.summary
    b = 2.0 + 2.0 * 11.0 * math.tan(math.radians(30.0))
    excess = s["inspection"]["excess_weld_metal"]
    assert s["inspection"]["thickness_mm"] == 12.0
    assert excess["worst_mm"] == pytest.approx(s["reinforcement_max_mm"], abs=1e-4)
    by_hand = next(
        (lv for lv, k, cap in (("B", 0.1, 5), ("C", 0.15, 7), ("D", 0.25, 10))
         if s["reinforcement_max_mm"] <= min(1 + k * b, cap) - 0.05),
        "",
    )  # fmt: skip
    if by_hand:  # (0.05 mm from a limit: the corners' width may differ a little from b)
        assert excess["level"] == by_hand
    filled = s["inspection"]["incompletely_filled_groove"]
    assert (filled["level"] == "B") == (s["underfilled_stations"] == 0)
    assert s["quality_level"] in ("B", "C", "D", "none")


def test_the_job_folder_shows_its_weld(short_job, tmp_path: Path) -> None:
    """weld.png, inspection.png and fill.png: the cross-sections at the start, middle, end and
    worst station (worst: where the worst imperfection is), ISO along the seam, the part in 3D."""
    from seamtrack.multipass.summary import inspect_job
    from seamtrack.viz.fill import weld_stations
    from seamtrack.viz.job import write_job_pictures

    scene = load_scene("multipass-v-groove", SHORT)
    written = write_job_pictures(short_job, scene, tmp_path)
    assert [p.name for p in written] == ["weld.png", "inspection.png", "fill.png"]
    for path in written:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    weld = inspect_job(scene, short_job.fill, [r for r in short_job.passes if r.plan])
    assert weld is not None
    at = weld_stations(short_job.fill, weld)
    s = short_job.fill.s_mm
    assert s[at["start"]] == weld.s_mm[0] and s[at["end"]] == weld.s_mm[-1]
    assert at["start"] < at["middle"] < at["end"]
    rank = {"B": 0, "C": 1, "D": 2, "": 3}
    worst = max(weld.imperfections, key=lambda i: (rank[i.level], i.worst_mm > 0))
    assert s[at["worst"]] == pytest.approx(worst.worst_s_mm)


def test_the_docs_show_what_check_and_init_print(capsys) -> None:
    """docs/multipass.md's ``init --list`` line is the scene's description, and the passes it
    shows ``check`` printing are the ones check prints (laid out on the CAD groove)."""
    doc = (Path(__file__).parent.parent / "docs" / "multipass.md").read_text()
    listed = re.search(r"^multipass-v-groove +(.*)$", doc, re.M)
    assert listed and listed.group(1) == load_scene("multipass-v-groove").config.description
    shown = re.search(r"^ +(passes the plan lays \(CAD groove\)) +(.*)$", doc, re.M)
    assert shown
    assert main(["check", "multipass-v-groove"]) == 0
    printed = re.search(r"passes the plan lays \(CAD groove\) +(.*)$", capsys.readouterr().out,
                        re.M)  # fmt: skip
    assert printed and printed.group(1).strip() == shown.group(2).strip()


@pytest.mark.slow
def test_the_varying_gap_ends_over_the_plates_line_in_closed_loop() -> None:
    """``multipass-varying-gap`` as shipped (300 mm, the adaptive planner, closed loop): every
    station of the final fill at or above the plates' top line (its surface between the top
    corners, measured on the fill state, not the summary), and the weld at ISO 5817 level B.
    Before the cap's beads were sized by what lies under them and placed on the first cap
    pass's stations, 137 stations ended up to 0.15 mm under the line (0.10 mm over it at the
    least since). A minute or two of CPU: the whole job."""
    job = run_job(load_scene("multipass-varying-gap"))
    assert job.status == "completed"
    assert np.all(job.fill.reinforcement_mm()[:, 0] >= 0.0)
    assert job.summary["underfilled_stations"] == 0
    assert job.summary["quality_level"] == "B"
