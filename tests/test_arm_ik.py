"""Closed-form inverse kinematics and the compiled arm tick: every branch back on its pose by
Pinocchio's forward kinematics (an independent oracle), the compiled chain against Pinocchio, the
fallback where a URDF breaks a family's assumptions, the loop's compiled arm ticks against the
tracker protocol to the last bit, and the closed-form tick against Newton steps."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from seamtrack.control.arm import ArticulatedRobot
from seamtrack.control.closed_form import KIND_NONE, KIND_UR, KIND_WRIST
from seamtrack.control.kinematics import ArmKinematics
from seamtrack.control.robot import MoveCommand
from seamtrack.control.trajectory import TrajectoryTracker
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.loop import run
from seamtrack.simulation.scene import load_scene

TOOL = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 300.0], [0, 0, 0, 1.0]])
ARMS = {"ur10e": KIND_UR, "kr16": KIND_WRIST}


def _random_joints(kin: ArmKinematics, rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(np.maximum(kin.lower_rad, -math.pi), np.minimum(kin.upper_rad, math.pi))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_every_branch_is_back_on_the_pose_by_pinocchio(name: str) -> None:
    kin = ArmKinematics.named(name, TOOL)
    assert kin.solver == ARMS[name]
    data = kin.new_data()
    rng = np.random.default_rng(28)
    branches_seen = 0
    for _ in range(200):
        q = _random_joints(kin, rng)
        T = kin.fk(q, data)  # Pinocchio, mm
        branches = kin.ik_branches(T, q)
        assert 1 <= len(branches) <= 8
        branches_seen += len(branches)
        for b in branches:
            T2 = kin.fk(b, data)
            assert np.linalg.norm(T2[:3, 3] - T[:3, 3]) <= 1e-9
            assert np.allclose(T2[:3, :3], T[:3, :3], atol=1e-12, rtol=0)
        # The drawn joints are one of the branches (each turned to the nearest of q).
        assert np.abs(branches - q).max(axis=1).min() < 1e-7
    assert branches_seen >= 4 * 200  # most poses of a 6R arm have 8 solutions, none fewer than 1


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_ticks_nearest_branch_is_the_nearest_of_all_branches(name: str) -> None:
    """ik_nearest (the tick's IK: on the UR most branches are never worked out) against every
    branch and nearest_branch's choice: the same joints to the last bit, near the pose (a
    tick's set-point), far from it, at the wrist singularity (joint 5 at 0) and at a pose
    drawn exactly (a tie of two branches is possible there)."""
    from seamtrack.control.closed_form import ik_branches
    from seamtrack.control.closed_form_nearest import ik_nearest, nearest_branch

    kin = ArmKinematics.named(name, TOOL)
    rng = np.random.default_rng(2028)
    all_rows, row = np.empty((8, 6)), np.empty(6)
    checked = 0
    for i in range(300):
        q = _random_joints(kin, rng)
        if i % 10 == 0:
            q[4] = 0.0  # wrist singular
        T = kin.chain_fk(q)  # metres, the tick's units
        for near in (q, q + rng.normal(0.0, 1e-6, 6), q + rng.normal(0.0, 0.5, 6),
                     _random_joints(kin, rng)):  # fmt: skip
            count = ik_branches(kin.solver, kin.geometry, T, near, all_rows)
            b = nearest_branch(all_rows, count, near)
            found = ik_nearest(kin.solver, kin.geometry, T, near, row)
            assert found == (b >= 0)
            if found:
                assert np.array_equal(row, all_rows[b])
                checked += 1
    assert checked >= 1000


@pytest.mark.parametrize("name", sorted(ARMS))
def test_branches_are_distinct_configurations(name: str) -> None:
    kin = ArmKinematics.named(name, TOOL)
    q = np.radians([20.0, -70.0, 80.0, -40.0, 60.0, 30.0])
    q = np.clip(q, kin.lower_rad, kin.upper_rad)
    branches = kin.ik_branches(kin.fk(q), q)
    # The UR reaches this pose in all 8 ways; the KR 16's shoulder sits 260 mm ahead of axis
    # 1, so reaching over its back (joint 1 turned half a turn) is 520 mm further: 4 ways.
    assert len(branches) == (8 if name == "ur10e" else 4)
    wrapped = (branches + math.pi) % (2 * math.pi)
    for i in range(len(branches)):
        for j in range(i):
            assert np.abs(wrapped[i] - wrapped[j]).max() > 1e-6


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_compiled_chain_is_pinocchios(name: str) -> None:
    kin = ArmKinematics.named(name, TOOL)
    data = kin.new_data()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = _random_joints(kin, rng)
        T_pin = kin.fk(q, data)
        T = kin.chain_fk(q)
        assert np.allclose(T[:3, 3] * 1e3, T_pin[:3, 3], atol=1e-9, rtol=0)
        assert np.allclose(T[:3, :3], T_pin[:3, :3], atol=1e-14, rtol=0)
    wrist, sigma = kin.wrist_and_sigma(np.array([q]))
    assert wrist[0] == pytest.approx(kin.wrist_angle(q, data), abs=1e-10)
    assert sigma[0] == pytest.approx(kin.sigma_min(q, data), abs=1e-12)


def _urdf(tmp_path: Path, name: str, old: str, new: str) -> Path:
    from importlib import resources

    text = resources.files("seamtrack.control").joinpath("arms", f"{name}.urdf").read_text()
    assert old in text
    path = tmp_path / f"{name}_changed.urdf"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("name", "old", "new"),
    [
        # UR: wrist 3's twist 5 deg off the right angle the closed form assumes.
        ("ur10e", 'xyz="0 0 0.11985" rpy="-1.5707963267948966 0 0"',
         'xyz="0 0 0.11985" rpy="-1.48352986 0 0"'),
        # KR 16: axis 5 moved 10 mm off axis 4 (the wrist no longer meets in one point).
        ("kr16", '<origin xyz="0.670 0 0" rpy="0 0 0"/>',
         '<origin xyz="0.670 0.01 0" rpy="0 0 0"/>'),
    ],
)  # fmt: skip
def test_a_urdf_off_the_familys_assumptions_falls_back_to_newton_steps(
    tmp_path: Path, name: str, old: str, new: str
) -> None:
    kin = ArmKinematics.from_urdf(_urdf(tmp_path, name, old, new), TOOL)
    assert kin.solver == KIND_NONE
    assert len(kin.ik_branches(kin.fk(kin.home_rad), kin.home_rad)) == 0
    assert kin.solver_name == "iterative"
    # The arm still follows a move with Newton steps: the torch on the target, tool held.
    robot = ArticulatedRobot(kinematics=kin)
    start = np.radians([10.0, -80.0, 70.0, -80.0, -60.0, 20.0])
    assert kin.sigma_min(start) > 0.05  # well away from a singularity
    state = robot.state_at_joints(start)
    R0 = state.R
    target = tuple(np.array(state.q) + [30.0, -20.0, 10.0])
    for _ in range(4000):
        robot.step(state, MoveCommand(target, 20.0, stop_at_target=True))
    assert np.allclose(state.q, target, atol=1e-6)
    assert np.allclose(state.R, R0, atol=1e-9)


def test_plan_picks_the_branch_nearest_the_last_joints() -> None:
    kin = ArmKinematics.named("ur10e", TOOL)
    robot = ArticulatedRobot(kinematics=kin)
    q = np.radians([10.0, -80.0, 70.0, -80.0, -90.0, 20.0])
    T = kin.fk(q)
    # A pose reached from nearby joints comes back as those joints, not another branch.
    joints = robot.plan(T[None], "pose", "seam", start=q + 0.05)
    assert np.allclose(joints[0], q, atol=1e-9)
    # The iterative solver from the same start agrees.
    assert np.allclose(kin.ik(T, q + 0.05).q, joints[0], atol=1e-9)


class _Protocol:
    """The built-in tracker behind the tracker protocol (and its hint): the loop's reference
    path, one Python tick at a time."""

    def __init__(self, inner: Any):
        self.inner = inner

    def reset(self, context: Any) -> None:
        self.inner.reset(context)

    def update(self, measurement: Any) -> None:
        self.inner.update(measurement)

    def command(self, t_s: float, tcp_world: Any, tcp_velocity_world: Any) -> Any:
        return self.inner.command(t_s, tcp_world, tcp_velocity_world)

    def hint(self, T_world_sensor: Any) -> Any:
        return self.inner.hint(T_world_sensor)

    @property
    def stop_cause(self) -> str:
        return str(self.inner.stop_cause)


SHORT_ARM: dict[str, Any] = {
    "seam.length_mm": 20.0,
    "tracker.name": "trajectory",
    "sensor.frame_rate_hz": 50.0,
}


@pytest.mark.parametrize(
    "overrides",
    [
        {"robot.model": "ur10e", "robot.base_origin_mm": [200.0, -700.0, 0.0]},
        {"robot.model": "kr16", "robot.base_origin_mm": [-900.0, 0.0, -400.0],
         "robot.servo_gain_1_s": 40.0, "robot.interpolation_period_s": 0.004},
    ],
)  # fmt: skip
def test_the_compiled_arm_ticks_are_the_protocols(
    overrides: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    parts = build_parts(load_scene("paper-verification", {**SHORT_ARM, **overrides}))
    reference = run(dataclasses.replace(parts, tracker=_Protocol(parts.tracker)))
    parts = build_parts(load_scene("paper-verification", {**SHORT_ARM, **overrides}))
    with monkeypatch.context() as patch:
        patch.setattr(TrajectoryTracker, "command", None)  # the compiled path never calls it
        fast = run(parts)
    assert fast.summary["status"] == reference.summary["status"] == "completed"
    assert fast.summary["joint_limited_ticks"] == reference.summary["joint_limited_ticks"]
    # The same arithmetic, compiled in two contexts (the tick alone, and inlined into the
    # stretch of ticks): equal to the last bit or to rounding.
    for name in ("tcp_world", "target_world", "joints_rad", "work_angle_error_rad"):
        a, b = getattr(fast.trace, name), getattr(reference.trace, name)
        assert a.shape == b.shape
        assert np.allclose(a, b, atol=1e-11, rtol=0, equal_nan=True), name


@pytest.mark.parametrize(
    "overrides",
    [
        {"robot.model": "ur10e", "robot.base_origin_mm": [200.0, -700.0, 0.0]},
        {"robot.model": "kr16", "robot.base_origin_mm": [-900.0, 0.0, -400.0]},
    ],
)
def test_the_closed_form_tick_keeps_the_newton_ticks_status_and_error(
    overrides: dict[str, Any],
) -> None:
    parts = build_parts(load_scene("paper-verification", {**SHORT_ARM, **overrides}))
    exact = run(parts).summary
    newton = run(dataclasses.replace(parts, robot=parts.robot.with_iterative_ik())).summary
    assert exact["status"] == newton["status"] == "completed"
    # The Newton tick's residual (<~1e-5 mm) is far below the depth resolution.
    moved = abs(exact["max_error_mm"] - newton["max_error_mm"])
    assert moved < 0.1 * parts.sensor_resolution_mm


def test_the_hints_compiled_plane_crossings_and_medians_are_numpys() -> None:
    from seamtrack.control.path_kernels import column_medians, plane_crossings
    from seamtrack.geometry.seam import Seam
    from seamtrack.sensing.scan import laser_plane_crossings

    rng = np.random.default_rng(11)
    # A helix (crosses a plane many times) with a vertex exactly on the plane at its end.
    u = np.linspace(0.0, 6 * math.pi, 400)
    points = np.column_stack([30 * np.cos(u), 30 * np.sin(u), 2.0 * u])
    points[-1, 0] = 0.0
    seam = Seam.from_points(points)
    crossings = 0
    for _ in range(100):
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        R[:, 0] *= np.sign(np.linalg.det(R))
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, rng.normal(size=3) * 20
        a, b = laser_plane_crossings(seam, T), plane_crossings(seam.points, T)
        assert a.shape == b.shape
        assert np.allclose(a, b, atol=1e-12, rtol=0)
        crossings += len(a)
    T = np.eye(4)  # the laser plane x = 0 through the last vertex
    assert np.allclose(laser_plane_crossings(seam, T), plane_crossings(seam.points, T), atol=1e-12)
    assert crossings > 100
    for m in (1, 2, 7, 100):
        x = rng.normal(size=(m, 3))
        assert np.array_equal(column_medians(x), np.median(x, axis=0))
