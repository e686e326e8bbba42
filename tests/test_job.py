"""The multi-pass job's pieces without a closed loop: the scene sections and their checks, the
process formulas, the pass's true path, the measured groove from frames, the arc's start and
end, and the fusion margin. The job itself runs in tests/test_job_run.py."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from seamtrack.control.planner import PassPlan
from seamtrack.errors import PluginError, PluginRuntimeError, SceneError
from seamtrack.multipass import job, steering, summary
from seamtrack.sensing.profiles import Feature
from seamtrack.simulation.process import (
    arc_width_to_height,
    check_passes,
    heat_input_kj_mm,
    overridden,
    process_of,
)
from seamtrack.simulation.scene import SceneErrorList, validate
from seamtrack.workpiece.beads import BeadShape, bead_area_mm2
from seamtrack.workpiece.fill import FillState

TAN30 = math.tan(math.radians(30))


def v_state(length: float = 10.0, thickness: float = 20.0, gap: float = 2.0) -> FillState:
    """A straight seam along +X (torch normal +Z) with an analytic V on a backing."""
    s = np.arange(0.0, length + 1e-9, 0.5)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-25.0, 25.0 + 1e-9, 0.05)
    z = np.clip((np.abs(y) - gap / 2) / TAN30, 0.0, thickness)
    return FillState.from_profiles(s, frames, y, np.repeat(z[None, :], len(s), axis=0))


def job_scene(**sections) -> dict:
    data = {
        "sensor": {"mode": "mesh"},
        "workpiece": {"script": "v_groove"},
        "tracker": {"name": "trajectory"},
        "extractor": {"name": "groove"},
        "passes": {"count": "auto"},
    }
    data.update(sections)
    return data


# --------------------------------------------------------------------------- the scene
def test_process_edge_units_and_formulas() -> None:
    c = validate(job_scene(process={"wire_feed_m_min": 9.0, "voltage_v": 30.0,
                                    "current_a": 280.0}))  # fmt: skip
    p = process_of(c)
    assert p.wire_feed_mm_s == pytest.approx(150.0)  # 9 m/min
    # mass conservation, the same in the planner and in the beads module
    assert p.bead_area_mm2(6.0) == pytest.approx(bead_area_mm2(1.2, 150.0, 6.0, 0.97))
    assert p.bead_area_mm2(6.0) == pytest.approx(0.97 * math.pi * 0.36 * 150.0 / 6.0)
    # heat input k U I / v * 1e-3, k = 0.8 for MIG/MAG
    assert heat_input_kj_mm(c, 6.0) == pytest.approx(0.8 * 30.0 * 280.0 / 6.0 * 1e-3)


def test_arc_wetting_angle_sets_width_to_height() -> None:
    c = validate(job_scene(process={"bead": {"model": "arc", "wetting_angle_deg": 60.0}}))
    assert process_of(c).width_to_height == pytest.approx(
        BeadShape("arc", wetting_angle_rad=math.radians(60.0)).ratio
    )
    assert arc_width_to_height(math.radians(90.0)) == pytest.approx(2.0)  # a half circle


@pytest.mark.parametrize(
    ("section", "field"),
    [
        ({"process": {"wire_feed_m_min": 0.0}}, "process.wire_feed_m_min"),
        ({"process": {"wire_feed_m_min": -3.0}}, "process.wire_feed_m_min"),
        ({"process": {"deposition_efficiency": 1.2}}, "process.deposition_efficiency"),
        ({"process": {"bead": {"model": "gauss"}}}, "process.bead.model"),
        ({"passes": {"count": 0}}, "passes.count"),
        ({"passes": {"count": "many"}}, "passes.count"),
        ({"passes": {"overrides": [{"offset_mm": 1.0}]}}, "passes.overrides.0.number"),
        ({"planner": {"nme": "fixed"}}, "planner.nme"),
    ],
)
def test_schema_refuses_in_one_line(section: dict, field: str) -> None:
    with pytest.raises(SceneErrorList) as info:
        validate(job_scene(**section))
    assert info.value.fields == [field]
    assert len(str(info.value).splitlines()) == 1


@pytest.mark.parametrize(
    ("section", "field"),
    [
        ({"passes": {"overrides": [{"number": 1, "work_angle_deg": 5.0}]}},
         "passes.overrides.0.work_angle_deg"),
        ({"passes": {"overrides": [{"number": 2}, {"number": 2}]}}, "passes.overrides.1.number"),
        ({"passes": {"count": 3, "overrides": [{"number": 4}]}}, "passes.overrides.0.number"),
        ({"process": {"travel_speed_min_mm_s": 9.0, "travel_speed_max_mm_s": 8.0}},
         "process.travel_speed_min_mm_s"),
        ({"simulation": {"welding_speed_mm_s": 20.0}}, "simulation.welding_speed_mm_s"),
        ({"process": {"bead": {"wetting_angle_deg": 50.0}}}, "process.bead.wetting_angle_deg"),
        ({"tracker": {"name": "convergence-radius"}}, "tracker.name"),
        ({"extractor": {"name": "v-groove"}}, "extractor.name"),
        ({"sensor": {"mode": "seam"}}, "passes"),
        ({"planner": {"name": "no_such_planner"}}, "planner.name"),
    ],
)  # fmt: skip
def test_job_checks_refuse(section: dict, field: str) -> None:
    with pytest.raises((SceneError, PluginError)) as info:
        check_passes(validate(job_scene(**section)))
    assert info.value.field == field


def test_a_planner_without_passes_is_refused() -> None:
    data = job_scene(planner={"name": "fixed"})
    del data["passes"]
    with pytest.raises(SceneError) as info:
        check_passes(validate(data))
    assert info.value.field == "planner"


def test_overrides_replace_the_plan() -> None:
    c = validate(job_scene(passes={"overrides": [
        {"number": 2, "reference": "left", "offset_mm": 1.5, "travel_speed_mm_s": 7.0,
         "wire_feed_m_min": 6.0}]}))  # fmt: skip
    plan = PassPlan("centre", 0.0, 0.0, 5.0, 100.0, 0, 1, 2, False, np.array([0.0, 10.0]),
                    np.array([4.0, 6.0]), np.array([0.3, 0.4]))  # fmt: skip
    assert overridden(plan, c.passes, 0) is plan  # pass 1: untouched
    new = overridden(plan, c.passes, 1)
    assert (new.reference, new.offset_mm, new.wire_feed_mm_s) == ("left", 1.5, 100.0)
    assert new.speed_at(5.0) == 7.0 and new.offset_at(5.0) == 1.5


# --------------------------------------------------------------------------- the pass
def test_pass_path_is_the_reference_point_moved_by_the_offset() -> None:
    fill = v_state()
    s = fill.s_mm
    plan = PassPlan("centre", 0.0, 0.0, 5.0, 100.0, 0, 0, 1, False, s, np.full(len(s), 5.0),
                    0.1 * s)  # fmt: skip
    path = job.pass_path(fill, "centre", plan)
    # the empty V's middle bottom point: y = 0 on the backing (z = 0), the seam along +X
    assert np.allclose(path.points[:, 0], s)
    assert np.allclose(path.points[:, 1], 0.1 * s)
    assert np.allclose(path.points[:, 2], 0.0)
    left = job.pass_path(fill, "left", None)
    assert np.allclose(left.points[:, 1], -1.0, atol=0.06)  # the wall's foot at the gap's edge


def test_measured_groove_in_station_frames_left_to_right() -> None:
    """Frames of a sensor above the seam, its laser y against the stations' y (a flipped
    mount): the measured 7 points come back in station coordinates, y ascending."""
    fill = v_state()
    seam = job.Seam.from_points(fill.T_world_station[:, :3, 3])
    truth = fill.groove_points(4)
    frames = []
    for x in (2.0, 2.1, 7.0):
        T = np.eye(4)  # sensor frame: x along the seam, y_L = -y, z_L = -z (looking down)
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])
        T[:3, 3] = (x, 0.0, 100.0)
        laser = np.column_stack([-truth[:, 0], 100.0 - truth[:, 1]])[::-1]  # left = -y_L
        frames.append((Feature(point_laser=laser[3], point_world=np.array([x, 0, 0.0]),
                               edges_laser=laser, area_mm2=50.0), T))  # fmt: skip
    frames.append((Feature.failed("nothing"), np.eye(4)))
    groove = job.measured_groove(frames, fill, seam)
    assert groove is not None
    assert np.allclose(groove.s_mm, [2.0, 7.0])
    assert np.allclose(groove.points, truth[None], atol=1e-9)
    assert np.allclose(groove.area_mm2, 50.0)
    assert job.measured_groove(frames[-1:], fill, seam) is None


def test_ramped_start_and_crater_keep_the_planned_area() -> None:
    planned = np.full(7, 5.0)
    speed = np.array([0.5, 2.0, 5.0, 3.0, 5.0, 1.0, 0.2])
    out = job.ramped(speed, planned)
    # the slow middle (a tracking slowdown) stays: a fatter bead; the ramps take the plan's
    assert out.tolist() == [5.0, 5.0, 5.0, 3.0, 5.0, 5.0, 5.0]


def test_the_braking_on_to_the_end_is_the_crater() -> None:
    """At the seam's end the torch slows on to the last point its sensor saw at a fifth or so
    under the plan, then to rest: all of that is the crater, where the wire follows the
    travel speed and the bead keeps the planned area (mass conservation with a synchronised
    feed: area * speed = efficiency * wire area * feed * speed / planned speed); a dip
    between two stretches at the plan stays a fatter bead. Counted at its actual speed, the
    braking laid a bead up to a third fatter at every pass's end, and the bumps grew."""
    planned = np.full(9, 5.0)
    speed = np.array([1.0, 5.0, 4.0, 5.0, 4.9, 4.1, 4.4, 4.0, 0.5])
    out = job.ramped(speed, planned)
    assert out.tolist() == [5.0, 5.0, 4.0, 5.0, 4.9, 5.0, 5.0, 5.0, 5.0]
    area = bead_area_mm2(1.2, 100.0, out, 0.97)
    assert np.allclose(area[5:], 0.97 * math.pi * 0.36 * 100.0 / 5.0)


def test_path_runs_off_the_ends_within_the_margin() -> None:
    seam = job.Seam.from_points([[0.0, 0, 0], [30.0, 0, 0]])
    path = np.column_stack([np.linspace(1.0, 28.5, 10), np.full(10, 0.2), np.zeros(10)])
    area = np.arange(10.0)
    out, a = job.to_the_ends(path, area, seam)
    assert np.allclose(out[0], [0.0, 0.2, 0.0]) and np.allclose(out[-1], [30.0, 0.2, 0.0])
    assert a[0] == 0.0 and a[-1] == 9.0 and len(a) == 12
    far = path[2:-2]  # 4.1 mm from the start: beyond the margin, left as it is
    out, a = job.to_the_ends(far, area[2:-2], seam)
    assert len(out) == len(far)


def test_fusion_margin_counts_the_wall_beads_only() -> None:
    fill = v_state()
    line = np.column_stack([np.linspace(-1, 11, 50), np.zeros(50), np.full(50, 10.0)])
    area = np.full(50, 20.0)
    shape = BeadShape()
    fill = fill.deposit(line + [0, -1.4, 0], area, shape)  # beside the left wall's foot
    fill = fill.deposit(line + [0, 0.0, 0], area, shape)  # in the middle

    def rec(bead: int, n: int, cap: bool = False) -> SimpleNamespace:
        return SimpleNamespace(plan=PassPlan("centre", 0.0, 0.0, 5.0, 100.0, 0, bead, n, cap))

    # a cap bead, and the third of three (the middle, laid after both walls): no wall bead
    assert np.all(np.isinf(summary.fusion_margin_mm(fill, [rec(0, 3, cap=True), rec(2, 3)])))
    margin = summary.fusion_margin_mm(fill, [rec(0, 3), rec(2, 3)])
    expected = -np.nanmin(fill.beads[0].margin_mm, axis=1)
    assert np.allclose(margin, expected)
    assert summary.is_wall_bead(PassPlan("left", 1.0, 0.0, 5.0, 100.0, 0, 2, 3))
    assert summary.is_wall_bead(PassPlan("centre", 0.0, 0.0, 5.0, 100.0, 0, 0, 1))


def test_a_planners_adapt_is_checked() -> None:
    plan = PassPlan("centre", 0.0, 0.0, 5.0, 100.0, 0, 0)
    ahead = None
    assert np.isnan(steering.adapted_answer(lambda g, p: None, ahead, plan, "p", 0.0)).all()
    assert steering.adapted_answer(lambda g, p: (4.0, 0.5), ahead, plan, "p", 0.0) == (4.0, 0.5)
    for garbage in [(0.0, 1.0), (4.0, float("nan")), "fast", (1.0,)]:
        with pytest.raises(PluginRuntimeError) as info:
            steering.adapted_answer(lambda g, p, answer=garbage: answer, ahead, plan, "p", 1.0)
        assert info.value.field == "planner.name"

    def raises(g, p):
        raise ValueError("bug")

    with pytest.raises(PluginRuntimeError) as info:
        steering.adapted_answer(raises, ahead, plan, "p", 1.0)
    assert info.value.field == "planner.name"


def test_a_frame_below_the_last_fill_is_no_groove() -> None:
    """The fill only grows: a frame whose fill surface lies more than FILL_DROP_MM below what
    the pass before measured there is a bogus answer (e.g. the backing seen under the beads)."""
    fill = v_state()
    seam = job.Seam.from_points(fill.T_world_station[:, :3, 3])
    truth = fill.groove_points(4)
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (2.0, 0.0, 100.0)
    laser = np.column_stack([-truth[:, 0], 100.0 - truth[:, 1]])[::-1]
    frame = (Feature(point_laser=laser[3], point_world=np.array([2.0, 0, 0.0]),
                     edges_laser=laser, area_mm2=50.0), T)  # fmt: skip
    previous = job.measured_groove([frame], fill, seam)
    assert previous is not None
    assert not steering.below_the_fill(frame, fill, seam, previous)
    higher = job.MeasuredGroove(previous.s_mm, previous.points + [0.0, steering.FILL_DROP_MM + 0.1],
                                previous.area_mm2)  # fmt: skip
    assert steering.below_the_fill(frame, fill, seam, higher)


def test_the_pass_befores_groove_is_settled_along_the_seam() -> None:
    """At a part's end the last station's frames saw the stripe leave the part: a groove 0.8
    mm wide at the root where the fill lies 7 mm up (multipass-v-groove in 12 passes). The
    pass before's median there was as wrong, so the next pass's frame passed the fill check
    and its torch dived 20 mm. Checked against the running median along the seam (cut short
    at the ends), the last station keeps its neighbours' fill, which such a frame lies 13 mm
    below (more than FILL_DROP_MM: refused)."""
    from seamtrack.multipass.paths import settled

    s = np.arange(20) * 0.5
    points = np.tile(np.array([[-12.0, 20.0], [-7.0, 11.0], [-4.0, 13.0], [-1.0, 13.5],
                               [2.0, 12.0], [5.0, 8.5], [12.0, 20.0]]), (20, 1, 1))  # fmt: skip
    points = points + np.random.default_rng(3).normal(0.0, 0.02, points.shape)
    points[-1] = [[-12.0, 20.0], [-0.41, 0.0], [-0.2, 0.0], [0.0, 0.0], [0.2, 0.0],
                  [0.42, 0.0], [12.0, 20.0]]  # fmt: skip
    groove = job.MeasuredGroove(s, points, np.full(20, 50.0))
    floor = settled(groove)
    assert floor.points[-1, 3, 1] == pytest.approx(13.5, abs=0.05)
    assert floor.points[-1, 3, 1] - points[-1, 3, 1] > steering.FILL_DROP_MM
    for i in range(20):  # the median of the stations within 4 of it, as many as there are
        window = points[max(i - 4, 0) : i + 5]
        np.testing.assert_allclose(floor.points[i], np.median(window, axis=0), rtol=0, atol=1e-12)
    assert floor.points.shape == points.shape


def test_a_planned_frame_aims_a_top_corner_bead_at_the_fill_under_it() -> None:
    """Before a pass's sensor first measures the groove, a frame gives the plan's point from
    the pass before's 7 points. It now carries all 7 (edges_laser), so a fill bead offset 9 mm
    in from a top corner aims at the fill surface under that place (the 7 points' polyline
    there), as from a measured frame, not at the corner's height, 9 mm higher on the 12-pass
    plan. Oracle: the analytic V's 7 points at the station, carried through the frames."""
    from seamtrack.geometry.groove_points import POINT_INDEX
    from seamtrack.multipass.aim import aim_point, planned_feature
    from seamtrack.multipass.paths import measured_groove

    fill = v_state()
    seam = job.Seam.from_points(fill.T_world_station[:, :3, 3])
    truth = np.stack([fill.groove_points(i) for i in range(len(fill.s_mm))])
    previous = job.MeasuredGroove(fill.s_mm, truth, np.full(len(fill.s_mm), 80.0))
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (2.0, 0.0, 100.0)  # the laser plane through station 4 (s = 2 mm)
    plan = PassPlan("right_top", -9.0, 0.0, 5.0, 100.0, 1, 1, 2, False)
    failed = job.Feature(confidence=0.0, reason="below the fill", stripe_points=500)
    planned = planned_feature(failed, T, fill, plan, previous, 0.5)
    assert planned and planned.edges_laser.shape == (7, 2)
    np.testing.assert_allclose(planned.point_world, [2.0, *truth[4, 6]], atol=1e-9)
    got = measured_groove([(planned, T)], fill, seam)
    np.testing.assert_allclose(got.points[0], truth[4], atol=1e-9)
    y, z = aim_point(got.points, POINT_INDEX["right_top"], -9.0)[0]
    assert y == pytest.approx(truth[4, 6, 0] - 9.0)
    z_fill = np.interp(y, truth[4, :, 0], truth[4, :, 1])
    assert z == pytest.approx(z_fill, abs=1e-9)
    assert truth[4, 6, 1] - z > 5.0  # the corner's height, which the torch aimed at before


# --------------------------------------------------------------- issue 43: refusals and status
def _config(**sets):
    from seamtrack.simulation.scene import load_scene

    return load_scene("multipass-v-groove", sets).config


@pytest.mark.parametrize(
    "key", ["process.wire_feed_m_min", "process.wire_diameter_mm", "passes.overrides"]
)
def test_tiny_process_values_are_refused_naming_the_field(key: str) -> None:
    """1e-300 m/min of wire (or mm of it) is no GMAW process: refused at load naming the field
    (it reached the planner as an OverflowError / ZeroDivisionError blamed on a plugin)."""
    from seamtrack.simulation.scene import load_scene

    value = "[{number = 1, wire_feed_m_min = 1e-300}]" if key == "passes.overrides" else "1e-300"
    with pytest.raises(SceneError) as info:
        load_scene("multipass-v-groove", [f"{key}={value}"])
    assert info.value.field.startswith(key)


def test_a_built_in_planner_is_no_plugin() -> None:
    from seamtrack.control.planner import AdaptivePlanner, FixedPlanner, is_builtin

    class Mine(AdaptivePlanner):
        pass

    assert is_builtin("adaptive") and is_builtin(FixedPlanner()) and is_builtin(AdaptivePlanner())
    assert not is_builtin("my_planner:Mine") and not is_builtin(Mine())


def test_the_plan_on_the_cad_groove_and_its_refusals() -> None:
    """The passes the plan lays, as check prints them, and the plans that cannot fill the
    groove, refused before the run. Oracle: the analytic V's area (gap t + t^2 tan 30 deg on a
    20 mm plate, 2 mm gap: 270.9 mm^2) against the largest bead, mass conservation at the
    slowest speed (0.97 pi 0.6^2 133.3 / 2 = 73.1 mm^2): 3 beads cannot hold it, 4 can."""
    fill = v_state()
    area = 2.0 * 20.0 + 20.0**2 * TAN30
    assert float(np.median(fill.remaining_area_mm2())) == pytest.approx(area, rel=2e-3)
    plan = job.planned_layout(fill, _config())
    assert plan is not None and plan.passes == sum(plan.beads_per_layer)
    largest = 0.97 * math.pi * 0.36 * (8000.0 / 60.0) / 2.0
    assert 3 * largest < area < 4 * largest
    with pytest.raises(SceneError) as info:
        job.planned_layout(fill, _config(**{"passes.count": 3}))
    assert info.value.field == "passes.count" and "at least 4 passes" in info.value.fix
    assert job.planned_layout(fill, _config(**{"passes.count": 4})).passes == 4
    # 1 m/min of 0.5 mm wire: 0.63 mm^2 beads at 5 mm/s, ~400 of them; a job lays <= 200
    with pytest.raises(SceneError) as info:
        job.planned_layout(fill, _config(**{"process.wire_feed_m_min": 1.0,
                                            "process.wire_diameter_mm": 0.5}))  # fmt: skip
    assert info.value.field == "process.wire_feed_m_min"
    # an override of a pass beyond the plan
    overrides = [{"number": plan.passes + 1, "offset_mm": 0.0}]
    with pytest.raises(SceneError) as info:
        job.planned_layout(fill, _config(**{"passes.overrides": overrides}))
    assert info.value.field == "passes.overrides.0.number"
    plugin = SimpleNamespace(planner=SimpleNamespace(name="my_planner:Mine"))
    assert job.planned_layout(fill, plugin) is None  # a plugin's plan: only its run knows


def test_an_override_laid_by_no_pass_is_refused() -> None:
    passes = SimpleNamespace(overrides=[SimpleNamespace(number=2), SimpleNamespace(number=99)])
    job._check_overrides_laid(SimpleNamespace(overrides=passes.overrides[:1]), 2, "p")
    with pytest.raises(SceneError) as info:
        job._check_overrides_laid(passes, 2, "p")
    assert info.value.field == "passes.overrides.1.number"


@pytest.mark.parametrize(
    ("speed", "field"),
    [
        (1000.0, "passes.overrides.0.travel_speed_mm_s"),
        (1.0, "passes.overrides.0.travel_speed_mm_s"),
    ],
)
def test_an_override_keeps_the_speed_window(speed: float, field: str) -> None:
    """An override's travel speed is checked like the scene's: inside the process window
    (2-15 mm/s) and within the axes' reach."""
    from seamtrack.simulation.scene import load_scene

    with pytest.raises(SceneError) as info:
        load_scene("multipass-v-groove",
                   [f"passes.overrides=[{{number = 1, travel_speed_mm_s = {speed}}}]"])  # fmt: skip
    assert info.value.field == field
    load_scene("multipass-v-groove", ["passes.overrides=[{number = 1, travel_speed_mm_s = 9.0}]"])
    with pytest.raises(SceneError) as info:  # the window widened past what the axes reach
        load_scene("multipass-v-groove", ["process.travel_speed_max_mm_s=2000.0",
                                          "passes.overrides=[{number = 1, travel_speed_mm_s = "
                                          "1500.0}]"])  # fmt: skip
    assert info.value.field == field and "axes" in info.value.message


@pytest.mark.parametrize(
    ("stopped", "statuses", "lowest", "status"),
    [
        ("", ["completed"] * 3, [0.2, -0.4, 0.1], "completed"),
        ("", ["completed"] * 3, [0.2, -1.2, 0.1], "underfilled"),
        ("", ["completed", "lost_seam"], [0.2, 0.3], "incomplete"),
        ("why", ["completed"], [-5.0], "stopped"),
    ],
)
def test_a_job_that_leaves_the_groove_unfilled_is_not_completed(stopped, statuses, lowest, status):
    """A fill surface more than UNDERFILL_LIMIT_MM (1 mm, ISO 5817 level C) under the plates'
    top line at a station every pass welded: ``underfilled``, with the station named."""
    from seamtrack.multipass.summary import UNDERFILL_LIMIT_MM, job_status

    got, reason = job_status(stopped, statuses, np.array(lowest), np.arange(len(lowest)) * 0.5)
    assert got == status
    if status == "underfilled":
        assert UNDERFILL_LIMIT_MM == 1.0 and "1.2 mm at s = 0.5 mm" in reason


def test_a_call_over_its_wall_time_budget_is_left_and_reported() -> None:
    """within_budget: the answer, the call's own error, or TimeoutError once the budget is
    spent (the call, blocked for good, is left in its daemon thread)."""
    import threading

    assert job.within_budget(lambda: 42, 5.0) == 42
    with pytest.raises(ValueError):
        job.within_budget(lambda: int("x"), 5.0)
    never = threading.Event()
    with pytest.raises(TimeoutError):
        job.within_budget(never.wait, 0.05)
    never.set()


def test_the_frame_check_refuses_a_foot_inside_the_last_fill() -> None:
    """The fill surface only widens up a V's walls: a frame whose left (right) foot lies more
    than 2 FILL_DROP_MM inside the one the pass before measured there is no groove, 1.9 mm
    is."""
    fill = v_state()
    seam = job.Seam.from_points(fill.T_world_station[:, :3, 3])
    truth = fill.groove_points(4)
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (2.0, 0.0, 100.0)
    laser = np.column_stack([-truth[:, 0], 100.0 - truth[:, 1]])[::-1]
    frame = (Feature(point_laser=laser[3], point_world=np.array([2.0, 0, 0.0]),
                     edges_laser=laser, area_mm2=50.0), T)  # fmt: skip
    previous = job.measured_groove([frame], fill, seam)
    assert previous is not None
    for row, sign in ((1, -1.0), (5, 1.0)):  # the left foot further left, the right further right
        for shift, below in (
            (2 * steering.FILL_DROP_MM + 0.1, True),
            (2 * steering.FILL_DROP_MM - 0.1, False),
        ):
            points = previous.points.copy()
            points[:, row, 0] += sign * shift
            wider = job.MeasuredGroove(previous.s_mm, points, previous.area_mm2)
            assert steering.below_the_fill(frame, fill, seam, wider) is below, (row, shift)


def test_a_groove_wider_than_the_old_probe_window_is_cut() -> None:
    """A 130 mm wide slot between two plates on a backing (its top corners at +-65 mm, beyond
    the +-60 mm the probe sections reached, which refused it with "widen half_width_mm", no
    scene key): the fill finds its top corners where the plates' edges are."""
    import trimesh

    plates = [trimesh.creation.box(bounds=[[0, lo, 0], [20, hi, 20]])
              for lo, hi in ((-115.0, -65.0), (65.0, 115.0))]  # fmt: skip
    backing = trimesh.creation.box(bounds=[[0, -115, -5], [20, 115, 0]])
    mesh = trimesh.util.concatenate([*plates, backing])
    seam = job.Seam.from_points([[0.0, 0.0, 0.0], [20.0, 0.0, 0.0]], normals=[[0, 0, 1]] * 2)
    fill = FillState.from_mesh(mesh, seam)
    corners = np.tile([-65.0, 65.0], (len(fill.s_mm), 1))
    np.testing.assert_allclose(fill.top_corners[:, :, 0], corners, atol=0.1)


def test_a_pass_error_plot_says_which_pass_it_shows() -> None:
    from seamtrack.cli.jobs import pass_title

    result = SimpleNamespace(status="completed")
    cap = PassPlan("left_top", 1.0, 0.0, 5.0, 100.0, 5, 1, 6, True)
    assert pass_title("mp", SimpleNamespace(name="pass_12", plan=cap, result=result)) == (
        "mp pass_12: layer 6 (cap), bead 2 of 6 (from left_top); status: completed"
    )
    scan = SimpleNamespace(name="pass_00_scan", plan=None, result=result)
    assert "scan-only" in pass_title("mp", scan)


def test_the_catalogue_holds_issue_43s_multipass_reproducers() -> None:
    """Each bad input of issue 43's multi-pass items is an entry of the bad-input catalogue
    (found by its command line), naming the field the issue says."""
    from seamtrack.bench.failures import CATALOGUE

    def field_of(*needles: str) -> str:
        for entry in CATALOGUE:
            if all(n in " ".join(entry.args) for n in needles):
                return entry.field
        return ""

    assert field_of("process.wire_feed_m_min=1e-300") == "process.wire_feed_m_min"
    assert field_of("process.wire_diameter_mm=1e-300") == "process.wire_diameter_mm"
    assert field_of("process.wire_feed_m_min=0.01") == "process.wire_feed_m_min"
    assert field_of("multipass-v-groove", "passes.count=3") == "passes.count"
    assert field_of("travel_speed_mm_s = 1000.0") == "passes.overrides.0.travel_speed_mm_s"
    assert field_of("number = 99", "passes.count=2") == "passes.overrides.0.number"
    assert field_of("bad_planners:NeverReturns") == "planner.name"  # a plan() that never returns


def test_the_handover_from_the_approach_is_the_start_ramp() -> None:
    """The torch reaches the plan on its approach, then slows for a while as the tracker takes
    over (the handover, path indices 3..6): that slowdown is the start (planned area); a dip
    after the handover stays a fatter bead."""
    planned = np.full(10, 5.0)
    speed = np.array([1.0, 5.0, 5.0, 5.0, 3.5, 4.0, 5.0, 5.0, 3.0, 5.0])
    assert job.ramped(speed, planned).tolist() == [5.0, 5, 5, 5, 3.5, 4.0, 5, 5, 3.0, 5]
    out = job.ramped(speed, planned, handover=(3, 6))
    assert out.tolist() == [5.0, 5, 5, 5, 5, 5, 5, 5, 3.0, 5]


def _trapezoid(bottom_z: float, half_gap: float = 1.0, top_z: float = 20.0) -> np.ndarray:
    """A 60 deg V's 7 points (y, z) with a flat fill surface at bottom_z (walls 30 deg off
    vertical), the top corners at top_z."""
    t = math.tan(math.radians(30))
    foot = half_gap + bottom_z * t
    top = half_gap + top_z * t
    ys = np.linspace(-foot, foot, 5)
    return np.array([[-top, top_z], *[[y, bottom_z] for y in ys], [top, top_z]])


def test_after_bead_lifts_the_fill_surface_by_the_bead_area() -> None:
    """The groove measured before a bead with that bead added is the V filled to the height
    that holds the bead's area: on a 60 deg V (w = 2 + 2 z tan 30) the trapezoid between the
    old and new fill surfaces has the bead's area (analytic), the feet on the walls, the top
    corners where they were."""
    from seamtrack.control.fill_layout import after_bead
    from seamtrack.control.planner import MeasuredGroove

    before = _trapezoid(8.0)[None]
    groove = MeasuredGroove(np.array([0.0]), before, np.array([100.0]))
    out = after_bead(groove, np.array([30.0]))
    z1 = float(out.points[0, 3, 1])
    width = lambda z: 2.0 + 2.0 * z * math.tan(math.radians(30))  # noqa: E731
    assert 0.5 * (width(8.0) + width(z1)) * (z1 - 8.0) == pytest.approx(30.0, rel=1e-9)
    np.testing.assert_allclose(out.points[0], _trapezoid(z1), atol=1e-9)
    assert out.area_mm2[0] == pytest.approx(70.0)
    assert after_bead(groove, None) is groove


@pytest.mark.parametrize("count", [10, 12, 14])
def test_a_layer_over_a_single_bead_is_placed_on_the_groove_after_it(count: int) -> None:
    """The job's planner gets the groove measured before the last bead. Over a single-bead
    layer (the third of the 10- to 14-pass plans) that groove is a bead lower
    and narrower than the one the next layer lies on; the planner adds the bead
    (``after_bead``) before it places the layer's first bead. Oracle: the same planner given
    the true groove after that bead (``dry_run`` unlagged: the first three beads, centred at
    the same speed, are the same in both). ``after_bead`` lifts a flat fill surface, the bead
    is crowned: its feet stand 0.2-0.4 mm further out than the true ones (0.23-0.38 mm
    measured); placed on the groove before the bead the wall bead landed 0.47-0.63 mm
    inward (the slot of a narrower layer)."""
    from seamtrack.control.planner import AdaptivePlanner, JobState, Process
    from seamtrack.workpiece.beads import BeadShape
    from seamtrack.workpiece.fill import FillState

    s = np.arange(0.0, 10.0 + 1e-9, 0.5)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-26.0, 26.0 + 1e-9, 0.05)
    wall = 1.0 + (np.abs(y) - 1.0) / math.tan(math.radians(30))
    z = np.where(np.abs(y) < 1.0, 0.0, np.clip(wall, 1.0, 20.0))
    empty = FillState.from_profiles(s, frames, y, np.tile(z, (len(s), 1)))

    def fourth(lagged: bool) -> np.ndarray:
        state = JobState(Process(nominal_speed_mm_s=5.0), count=count, reinforcement_mm=2.0)
        _, plans = job.dry_run(empty, AdaptivePlanner(), state, BeadShape(), max_passes=4,
                               lagged=lagged)  # fmt: skip
        assert [p.beads_in_layer for p in plans] == [1, 1, 1, 2]
        return np.asarray(plans[3].offset_profile_mm)

    assert np.all(np.abs(fourth(True) - fourth(False)) <= 0.4)
