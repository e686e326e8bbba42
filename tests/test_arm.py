"""Articulated arms: kinematics against the published DH tables, IK round trips, joint limits
never exceeded, the servo's following error, torch angles, and refusals before the run."""

from __future__ import annotations

import math

import numpy as np
import pytest
from arm_oracles import UR10E_DH, dh
from hypothesis import given, settings
from hypothesis import strategies as st_h

import seamtrack as st
from seamtrack.control.arm import ArticulatedRobot
from seamtrack.control.kinematics import ArmKinematics
from seamtrack.control.robot import CartesianRobot, MoveCommand
from seamtrack.control.servo import Servo
from seamtrack.errors import ReachError, SceneError
from seamtrack.geometry.torch import torch_angles, torch_axis

TOOL = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 300.0], [0, 0, 0, 1.0]])


def test_ur10e_forward_kinematics_matches_the_published_dh_table() -> None:
    kin = ArmKinematics.named("ur10e")
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.uniform(-math.pi, math.pi, 6)
        T = np.eye(4)
        for qi, (d, a, alpha) in zip(q, UR10E_DH, strict=True):
            T = T @ dh(qi, d, a, alpha)
        assert np.allclose(kin.fk(q), T, atol=1e-9)


def test_kr16_reach_to_the_wrist_point_is_the_data_sheets_1611_mm() -> None:
    kin = ArmKinematics.named("kr16")
    # Stretched forward (A2 = A3 = 0): wrist point 260 + 680 + 670 ahead, 675 + 35 high.
    flange = kin.fk(np.zeros(6))[:3, 3]
    assert np.allclose(flange, [260 + 680 + 670 + 115, 0, 675 + 35], atol=1e-9)
    assert 260 + 680 + math.hypot(670, 35) == pytest.approx(1611, abs=0.5)


@pytest.mark.parametrize("name", ["ur10e", "kr16"])
def test_fk_ik_round_trip_to_1e9_mm_on_seeded_random_poses(name: str) -> None:
    kin = ArmKinematics.named(name, TOOL)
    data = kin.new_data()
    rng = np.random.default_rng(7)
    lo = np.maximum(kin.lower_rad, -math.pi)
    hi = np.minimum(kin.upper_rad, math.pi)
    for _ in range(100):
        q = rng.uniform(lo, hi)
        if kin.wrist_angle(q, data) < math.radians(5):
            continue
        T = kin.fk(q, data)
        result = kin.ik(T, q + rng.normal(0.0, 0.05, 6), data)
        assert result
        T2 = kin.fk(result.q, data)
        assert np.linalg.norm(T2[:3, 3] - T[:3, 3]) <= 1e-9
        assert np.allclose(T2[:3, :3], T[:3, :3], atol=1e-12)


def _arm(servo_gain: float | None = None) -> ArticulatedRobot:
    kin = ArmKinematics.named("ur10e", TOOL)
    servo = None
    if servo_gain is not None:
        servo = Servo((servo_gain,), 0.004, 1e-3, tuple(kin.velocity_max_rad_s),
                      tuple(kin.acceleration_max_rad_s2))  # fmt: skip
    return ArticulatedRobot(kinematics=kin, servo=servo)


@settings(max_examples=25, deadline=None)
@given(
    dx=st_h.floats(-600, 600),
    dy=st_h.floats(-600, 600),
    dz=st_h.floats(-400, 400),
    turn=st_h.floats(-math.pi, math.pi),
    speed=st_h.floats(1.0, 250.0),
    servo_gain=st_h.sampled_from([None, 20.0, 100.0]),
)
def test_joint_limits_are_never_exceeded(dx, dy, dz, turn, speed, servo_gain) -> None:
    """Any move, reachable or not, at any speed, with ideal joints or behind a servo:
    positions, velocities and accelerations of the joints stay within their limits on every
    tick."""
    robot = _arm(servo_gain)
    kin = robot.kinematics
    state = robot.state_at_joints(kin.home_rad)
    c, s = math.cos(turn), math.sin(turn)
    rotation = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) @ state.R
    target = (state.q[0] + dx, state.q[1] + dy, state.q[2] + dz)
    move = MoveCommand(target, speed, rotation=rotation)
    dt = robot.control_period_s
    q_prev, qd_prev = state.joints.copy(), np.zeros(6)
    for _ in range(1500):
        robot.step(state, move)
        qd = (state.joints - q_prev) / dt
        assert (state.joints >= kin.lower_rad - 1e-12).all()
        assert (state.joints <= kin.upper_rad + 1e-12).all()
        assert (np.abs(qd) <= kin.velocity_max_rad_s * (1 + 1e-9)).all()
        assert (np.abs(qd - qd_prev) <= kin.acceleration_max_rad_s2 * dt * (1 + 1e-6)).all()
        q_prev, qd_prev = state.joints.copy(), qd


def test_arm_follows_a_straight_move_with_its_tool_held() -> None:
    robot = _arm()
    state = robot.state_at_joints(robot.kinematics.home_rad)
    R0 = state.R.copy()
    target = (state.q[0] + 20.0, state.q[1], state.q[2])
    for _ in range(3000):
        robot.step(state, MoveCommand(target, 10.0, stop_at_target=True))
    assert np.allclose(state.q, target, atol=1e-6)
    assert np.allclose(state.R, R0, atol=1e-9)


def test_servo_lags_by_v_over_kv_at_steady_speed() -> None:
    """A gantry axis at 5 mm/s behind a position loop of K_v = 20 1/s trails by 0.25 mm."""
    kv = 20.0
    servo = Servo((kv,), 1e-3, 1e-3, (20.0, 10.0, 10.0), (30.0, 15.0, 15.0))
    robot = CartesianRobot(servo=servo)
    state = robot.state_at([10.0, 75.0, 75.0])
    move = MoveCommand((700.0, 75.0, 75.0), 5.0)
    for _ in range(4000):
        robot.step(state, move)
    assert state.setpoint is not None
    lag = state.setpoint.q[0] - state.q[0]
    # v = K_v (set-point - position before the tick); the position then moves v dt: measured
    # after the tick, the discrete loop trails by v / K_v - v dt.
    assert lag == pytest.approx(5.0 / kv - 5.0 * 1e-3, rel=1e-9)
    assert state.v[0] == pytest.approx(5.0, rel=1e-6)


def test_servo_off_is_the_ideal_axis() -> None:
    """No servo: no set-point is held, and once the commanded speed is reached (a few ticks
    of the acceleration limit) the axis moves exactly v dt each tick, with no following lag;
    the other axes stay where they were."""
    robot = CartesianRobot()
    state = robot.state_at([10.0, 75.0, 75.0])
    dt = robot.control_period_s
    ramp = math.ceil(5.0 / robot.acceleration_max_mm_s2[0] / dt)  # ticks to reach 5 mm/s
    x = []
    for _ in range(ramp + 100):
        robot.step(state, MoveCommand((700.0, 75.0, 75.0), 5.0))
        x.append(state.q[0])
    assert state.setpoint is None and state.servo is None
    assert np.diff(x[ramp:]) == pytest.approx(5.0 * dt, rel=1e-9)
    assert list(state.v) == pytest.approx([5.0, 0.0, 0.0], abs=1e-9)
    assert list(state.q[1:]) == [75.0, 75.0]


def test_torch_angles_round_trip() -> None:
    rng = np.random.default_rng(3)
    t = np.array([1.0, 0, 0])
    n = np.array([0, 0, 1.0])
    for _ in range(20):
        work, travel = rng.uniform(-1.2, 1.2, 2)
        a = torch_axis(t, n, work, travel)
        assert np.allclose(torch_angles(a, t, n)[0], [work, travel], atol=1e-12)
    # Push: the torch points ahead, its top leans back.
    assert torch_axis(t, n, 0.0, 0.3)[0] < 0


def test_unknown_robot_model_is_refused_with_the_known_ones() -> None:
    with pytest.raises(SceneError, match="robot.model.*unknown robot model 'ur10'.*ur10e"):
        st.load_scene("paper-verification", overrides={"robot.model": "ur10"})


def test_unparsable_urdf_is_refused(tmp_path) -> None:
    bad = tmp_path / "arm.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'>")
    with pytest.raises(SceneError, match="robot.urdf.*does not parse"):
        ArmKinematics.from_urdf(bad)


def test_seam_out_of_reach_names_the_first_point_and_the_fix() -> None:
    scene = st.load_scene(
        "paper-verification",
        overrides={
            "robot.model": "ur10e",
            "tracker.name": "trajectory",
            "robot.base_origin_mm": [-1400.0, -700.0, 0.0],
        },
    )
    from seamtrack.simulation.assemble import build_parts

    with pytest.raises(ReachError, match=r"seam: seam point \d+ at world .*no joint solution.*fix"):
        build_parts(scene)


def test_arm_tracks_the_paper_curve_and_keeps_the_torch_on_the_normal() -> None:
    scene = st.load_scene(
        "paper-verification",
        overrides={
            "robot.model": "ur10e",
            "tracker.name": "trajectory",
            "robot.base_origin_mm": [200.0, -700.0, 0.0],
            "sensor.frame_rate_hz": 50.0,
            "simulation.welding_speed_mm_s": 10.0,
            "seam.length_mm": 60.0,
        },
    )
    s = st.simulate(scene).summary
    gantry = st.simulate(
        st.load_scene("paper-verification", overrides={"seam.length_mm": 60.0})
    ).summary
    assert s["status"] == "completed"
    assert s["max_error_mm"] < 0.1
    # The gantry's vertical torch leans by the curve's slope (up to 9 deg): its fixed angle, not
    # an error; the arm's does not lean.
    assert gantry["max_fixed_torch_travel_angle_deg"] > 5.0
    assert s["max_travel_angle_error_deg"] < 1.0
    # A gantry commands no orientation: no orientation *error* keys, the fixed torch's angles;
    # the arm keeps its errors.
    assert not [k for k in gantry if "angle_error" in k]
    for stat in ("max", "rms", "p95"):
        for angle in ("work_angle", "travel_angle"):
            assert f"{stat}_fixed_torch_{angle}_deg" in gantry
            assert f"{stat}_{angle}_error_deg" in s
            assert f"{stat}_fixed_torch_{angle}_deg" not in s
    assert s["joint_limited_ticks"] == 0
    assert s["min_wrist_angle_deg"] > 5.0


def test_program_turns_at_v_over_r_round_a_girth() -> None:
    """A tool kept looking ahead along a horizontal circle of radius r turns about the
    vertical at v / r (counter-clockwise travel: +z)."""
    from seamtrack.control.orientation import ToolProgram
    from seamtrack.geometry.seam import Seam

    radius, speed = 50.0, 10.0
    angle = np.linspace(0.0, 2 * math.pi, 721)
    points = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(721)])
    points[-1] = points[0]
    program = ToolProgram(Seam.from_points(points), look_ahead_mm=10.0)
    for s in (5.0, 100.0, 300.0):
        omega = program.angular_velocity(s, speed)
        assert np.allclose(omega, [0.0, 0.0, speed / radius], rtol=1e-3, atol=1e-5)


@pytest.mark.parametrize("feed_forward", [False, True])
def test_orientation_feed_forward_removes_the_turning_lag(feed_forward: bool) -> None:
    """The tool must keep turning about its axis at omega. Without feed-forward the set-point
    trails the goal by omega^2 / (2 alpha), the error from which braking at the angular
    acceleration limit alpha stops in time, plus up to omega times the refresh period (the goal
    it chases is held between refreshes); with it, by less than 0.01 deg."""
    from seamtrack.control.arm import ArmMove

    robot = _arm()
    state = robot.state_at_joints(robot.kinematics.home_rad)
    omega, dt = 0.2, robot.control_period_s
    alpha = robot.angular_acceleration_max_rad_s2
    R0, target = state.R.copy(), tuple(state.q)

    def about_z(t: float) -> np.ndarray:
        c, s = math.cos(omega * t), math.sin(omega * t)
        return R0 @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])

    rate = R0[:, 2] * omega if feed_forward else None  # about the tool's z, base axes
    move = None
    lags = []
    for tick in range(3000):
        if tick % 10 == 0:  # the tracker refreshes the orientation every 10 ms
            move = ArmMove(target, 1.0, rotation=about_z(tick * dt), angular_velocity=rate)
        robot.step(state, move)
        goal = about_z((tick + 1) * dt)
        cos = (np.trace(goal.T @ state.R) - 1.0) / 2.0
        lags.append(math.acos(min(1.0, cos)))
    steady = max(lags[-1000:])
    if feed_forward:
        assert steady < math.radians(0.01)
    else:
        assert steady == pytest.approx(omega**2 / (2 * alpha) + omega * 10 * dt, rel=0.05)
    assert state.limited_ticks == 0


def test_a_trackers_non_finite_angular_velocity_is_refused_naming_the_tracker() -> None:
    import dataclasses

    from seamtrack.control.tracking import Command
    from seamtrack.errors import PluginRuntimeError
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run

    class Spinning:
        def reset(self, context):  # type: ignore[no-untyped-def]
            self.start = np.asarray(context.tcp_start_world)

        def update(self, measurement):  # type: ignore[no-untyped-def]
            pass

        def command(self, t_s, tcp_world, tcp_velocity_world):  # type: ignore[no-untyped-def]
            return Command(self.start, 1.0, rotation_world=np.eye(3),
                           angular_velocity_world=np.array([math.nan, 0.0, 0.0]))  # fmt: skip

    scene = st.load_scene(
        "paper-verification",
        overrides={
            "robot.model": "ur10e",
            "tracker.name": "trajectory",
            "robot.base_origin_mm": [200.0, -700.0, 0.0],
            "seam.length_mm": 20.0,
        },
    )
    parts = dataclasses.replace(build_parts(scene), tracker=Spinning())
    with pytest.raises(PluginRuntimeError, match="tracker.name.*angular velocity.*rad/s"):
        run(parts)
