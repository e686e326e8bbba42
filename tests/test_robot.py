"""The Cartesian robot's servo: limits are never exceeded, moves land exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from seamtrack.control.robot import CartesianRobot, MoveCommand
from seamtrack.errors import ReachError, SceneError

ROBOT = CartesianRobot()  # Table 2, 1 ms


def _check_limits(robot: CartesianRobot, qs: np.ndarray, vs: np.ndarray) -> None:
    lo, hi = np.array(robot.position_min_mm), np.array(robot.position_max_mm)
    assert np.all(qs >= lo - 1e-9) and np.all(qs <= hi + 1e-9)
    assert np.all(np.abs(vs) <= np.array(robot.velocity_max_mm_s) * (1 + 1e-12))
    dv = np.abs(np.diff(vs, axis=0)) / robot.control_period_s
    assert np.all(dv <= np.array(robot.acceleration_max_mm_s2) * (1 + 1e-9))


coords = hs.tuples(hs.floats(-200, 1000), hs.floats(-100, 250), hs.floats(-100, 250))


@settings(max_examples=25, deadline=None)
@given(
    start=hs.tuples(hs.floats(0, 800), hs.floats(0, 150), hs.floats(0, 150)),
    targets=hs.lists(
        hs.tuples(coords, hs.floats(0.1, 100), hs.booleans(), hs.integers(1, 300)),
        min_size=1,
        max_size=5,
    ),
)
def test_limits_are_never_exceeded(start, targets) -> None:
    """Random targets (also outside the travel), speeds and switch times: position, velocity
    and acceleration limits hold at every tick."""
    state = ROBOT.state_at(start)
    qs, vs = [list(state.q)], [list(state.v)]
    for target, speed, stop, ticks in targets:
        cmd = MoveCommand(target, speed, stop_at_target=stop)
        for _ in range(ticks):
            ROBOT.step(state, cmd)
            qs.append(list(state.q))
            vs.append(list(state.v))
    _check_limits(ROBOT, np.array(qs), np.array(vs))


def test_running_into_the_end_of_travel_stops_at_it() -> None:
    state = ROBOT.state_at([790.0, 75, 75])
    vs = []
    for _ in range(3000):
        ROBOT.step(state, MoveCommand((2000.0, 75, 75), 20.0))
        vs.append(list(state.v))
    assert state.q[0] == pytest.approx(800.0, abs=1e-9) and abs(state.v[0]) < 1e-9
    dv = np.abs(np.diff(np.array(vs)[:, 0])) / ROBOT.control_period_s
    assert dv.max() <= 30.0 * (1 + 1e-9)


def test_point_to_point_lands_exactly_at_rest() -> None:
    state = ROBOT.state_at([100.0, 50, 50])
    target = (130.0, 60.0, 45.0)
    for _ in range(20000):
        ROBOT.step(state, MoveCommand(target, 5.0, stop_at_target=True))
    assert np.allclose(state.q, target, atol=1e-9) and np.allclose(state.v, 0, atol=1e-12)


def test_trapezoid_time_matches_the_analytic_profile() -> None:
    """A 20 mm move along X at 5 mm/s with 30 mm/s^2: t = d/v + v/a = 4.1667 s."""
    state = ROBOT.state_at([100.0, 75, 75])
    ticks = 0
    while abs(state.q[0] - 120.0) > 1e-9 or abs(state.v[0]) > 0:
        ROBOT.step(state, MoveCommand((120.0, 75, 75), 5.0, stop_at_target=True))
        ticks += 1
    assert ticks * 1e-3 == pytest.approx(20 / 5 + 5 / 30, abs=5e-3)


def test_fly_by_keeps_speed_and_overshoots_by_v2_over_2a() -> None:
    """Without braking the torch arrives at speed and overshoots by about v^2 / (2 a)."""
    state = ROBOT.state_at([100.0, 75, 75])
    cmd = MoveCommand((110.0, 75, 75), 5.0, stop_at_target=False)
    peak = 0.0
    for _ in range(4000):
        ROBOT.step(state, cmd)
        peak = max(peak, state.q[0])
    assert peak - 110.0 == pytest.approx(5**2 / (2 * 30), rel=0.05)


def test_path_speed_is_capped_by_the_binding_axis() -> None:
    """Asked for 100 mm/s along (300, 130): X (20 mm/s) binds before Y (10 mm/s) does."""
    state = ROBOT.state_at([100.0, 10, 75])
    for _ in range(3000):
        ROBOT.step(state, MoveCommand((400.0, 140.0, 75), 100.0))
    vx, vy = state.v[0], state.v[1]
    assert vx == pytest.approx(20.0)
    assert vy / vx == pytest.approx((140 - state.q[1]) / (400 - state.q[0]), rel=1e-3)


def test_reach_error_names_the_point_and_the_fix() -> None:
    with pytest.raises(ReachError) as info:
        ROBOT.require_reachable([[10, 10, 10], [900, 10, 10]], "seam", field="seam")
    assert "point 1" in str(info.value) and info.value.fix


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(velocity_max_mm_s=(20, 0, 10)),
        dict(control_period_s=0.0),
        dict(position_min_mm=(0, 200, 0)),
    ],
)
def test_bad_limits_are_refused(kwargs) -> None:
    with pytest.raises(SceneError):
        CartesianRobot(**kwargs)


def test_sensor_pose_chain() -> None:
    T_tcp_sensor = np.eye(4)
    T_tcp_sensor[:3, 3] = [10, 0, 90]
    robot = CartesianRobot(
        T_world_base=np.array(
            [[1, 0, 0, -100], [0, 1, 0, -75], [0, 0, 1, -75], [0, 0, 0, 1]], float
        ),
        T_tcp_sensor=T_tcp_sensor,
    )
    T = robot.T_world_sensor([100, 75, 75])
    assert np.allclose(T[:3, 3], [10, 0, 90])
    assert np.allclose(robot.q_from_world([0, 0, 0]), [100, 75, 75])
    assert math.isclose(robot.tcp_world([100, 75, 75])[0], 0.0)


@settings(max_examples=300, deadline=None)
@given(
    v=hs.floats(0.1, 1000.0),
    a=hs.floats(0.1, 10000.0),
    dt=hs.floats(1e-4, 0.1),
)
def test_end_stops_cannot_limit_a_robot_farther_than_its_free_travel(
    v: float, a: float, dt: float
) -> None:
    """The servo skips the end-stop braking test beyond _free_travel: exact there."""
    from seamtrack.control.robot import stop_speed

    robot = CartesianRobot(
        velocity_max_mm_s=(v, v, v), acceleration_max_mm_s2=(a, a, a), control_period_s=dt
    )
    assert stop_speed(robot._free_travel[0], a, dt) >= v
