"""The articulated-arm scenes end to end (mesh mode): the saddle, the girth seam, the 80 deg
corner; and what the paper's gantry does with the same parts."""

from __future__ import annotations

import pytest

import seamtrack as st
from seamtrack.errors import SceneError

pytestmark = [pytest.mark.slow, pytest.mark.cad, pytest.mark.embree]


def test_pipe_saddle_on_the_ur10e_completes_within_0_2_mm_with_angles_scored() -> None:
    s = st.simulate(st.load_scene("pipe-saddle")).summary
    assert s["status"] == "completed"
    assert s["max_error_mm"] <= 0.2
    for key in ("max", "rms", "p95"):
        assert s[f"{key}_work_angle_error_deg"] >= 0.0
        assert s[f"{key}_travel_angle_error_deg"] >= 0.0
    assert s["max_work_angle_error_deg"] < 2.0
    assert s["max_travel_angle_error_deg"] < 10.0
    # The tool keeps turning round the saddle: with the orientation feed-forward it keeps up
    # (RMS 0.3 deg; without it the set-point trailed by omega^2 / (2 alpha), RMS 2.8 deg).
    assert s["rms_travel_angle_error_deg"] < 1.0
    assert s["min_joint_limit_margin_deg"] > 0.0
    assert s["joint_clamped_ticks"] == 0


def test_pipe_saddle_on_the_gantry_is_refused_with_the_reason() -> None:
    scene = st.load_scene(
        "pipe-saddle",
        overrides={
            "robot.model": "cartesian",
            "robot.base_origin_mm": [-100.0, -75.0, 0.0],
            "robot.base_rotation_deg": [0.0, 0.0, 0.0],
        },
    )
    from seamtrack.simulation.assemble import build_parts

    with pytest.raises(SceneError, match="robot.model: the sensor's .* inside the part.*cannot"):
        build_parts(scene)


def test_pipe_on_plate_goes_all_the_way_round() -> None:
    s = st.simulate(st.load_scene("pipe-on-plate")).summary
    assert s["status"] == "completed"
    assert s["completed_fraction"] >= 0.99
    assert s["max_error_mm"] <= 0.2
    # The tool turned a full circle about the vertical: the base joint and wrist share it.
    assert s["joint_travel_deg"][0] + s["joint_travel_deg"][5] >= 300.0
    assert s["rms_travel_angle_error_deg"] < 1.0  # turning at v / r with its feed-forward


def test_80_deg_corner_completes_on_the_arm_where_the_gantry_loses_it() -> None:
    arm = st.simulate(st.load_scene("v-groove-corner-arm")).summary
    gantry = st.simulate(
        st.load_scene("v-groove-corner", overrides={"workpiece.params.corner_angle_deg": 80.0})
    ).summary
    assert arm["status"] == "completed"
    assert arm["completed_fraction"] == pytest.approx(1.0, abs=0.01)
    # The seam ends at the part's end: the arm stops there, not a bridge (10 mm) later.
    assert arm["stop_cause"] == "end_of_part"
    assert arm["overrun_mm"] <= 1.0
    assert gantry["status"] == "lost_seam"
    assert gantry["completed_fraction"] < 0.8
