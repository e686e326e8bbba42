"""Per-joint vectors of the right length on the built-in arms run; a wrong length is refused
with the arm's joint count (the catalogue, seamtrack.bench.failure_inputs_arms, has the rest)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import seamtrack as st
from seamtrack.errors import SceneError
from seamtrack.simulation.assemble import build_parts

UR10E = {
    "robot.model": "ur10e",
    "tracker.name": "trajectory",
    "robot.base_origin_mm": [200.0, -700.0, 0.0],
    "seam.length_mm": 10.0,
}
KR16 = {**UR10E, "robot.model": "kr16", "robot.base_origin_mm": [-700.0, 0.0, -300.0]}


def test_six_joint_accelerations_and_gains_on_a_ur10e_run() -> None:
    accel_deg = [60.0, 70.0, 80.0, 90.0, 100.0, 110.0]
    scene = st.load_scene(
        "paper-verification",
        overrides={
            **UR10E,
            "seam.length_mm": 30.0,  # longer than the look-ahead (10 mm) and the end tolerance
            "robot.joint_acceleration_max_deg_s2": accel_deg,
            "robot.servo_gain_1_s": [40.0, 40.0, 45.0, 50.0, 50.0, 50.0],
        },
    )
    robot = build_parts(scene).robot
    np.testing.assert_allclose(robot.kinematics.acceleration_max_rad_s2, np.radians(accel_deg))
    s = st.simulate(scene).summary
    assert s["status"] == "completed"


@pytest.mark.parametrize("count", [2, 5, 7])
def test_a_vector_of_another_length_is_refused_naming_the_joint_count(count: int) -> None:
    for key in ("robot.joint_acceleration_max_deg_s2", "robot.servo_gain_1_s"):
        scene = st.load_scene("paper-verification", overrides={**KR16, key: [50.0] * count})
        with pytest.raises(SceneError, match=rf"{key}: {count} .* of 6 joints"):
            build_parts(scene)


def test_one_value_for_every_joint_is_kept_on_a_kr16() -> None:
    scene = st.load_scene(
        "paper-verification", overrides={**KR16, "robot.joint_acceleration_max_deg_s2": 90.0}
    )
    kin = build_parts(scene).robot.kinematics
    np.testing.assert_allclose(kin.acceleration_max_rad_s2, [math.radians(90.0)] * 6)
