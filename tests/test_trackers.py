"""Trackers: the paper's algorithms I and II, and loading a user's tracker."""

from __future__ import annotations

import sys
import textwrap

import numpy as np
import pytest

from seamtrack.control.registry import tracker, tracker_class
from seamtrack.control.trackers import ConvergenceRadius, PointToPoint
from seamtrack.control.tracking import Measurement, TrackerContext
from seamtrack.errors import PluginError
from seamtrack.sensing.profiles import Feature


def context() -> TrackerContext:
    return TrackerContext(
        welding_speed_mm_s=5.0,
        control_period_s=1e-3,
        frame_period_s=1.0,
        latency_s=0.0,
        look_ahead_mm=10.0,
        sensor_resolution_mm=0.01,
        tcp_start_world=np.zeros(3),
        velocity_max_world=np.ones(3),
        acceleration_max_world=np.ones(3),
    )


def measured(point) -> Measurement:
    f = Feature(point_laser=np.zeros(2), point_world=np.asarray(point, float))
    return Measurement(f, 0.0, 0.0, np.eye(4), np.zeros(3))


def test_algorithm_ii_switches_inside_the_radius() -> None:
    t = ConvergenceRadius(radius_mm=1.0)
    t.reset(context())
    for x in (5.0, 10.0, 15.0):
        t.update(measured([x, 0, 0]))
    v = np.zeros(3)
    assert np.allclose(t.command(0, np.array([0.0, 0, 0]), v).target_world, [5, 0, 0])
    assert np.allclose(t.command(0, np.array([4.1, 0, 0]), v).target_world, [10, 0, 0])
    last = t.command(0, np.array([9.5, 0, 0]), v)
    # The last known point is kept (approached with a finishing move), never dropped.
    assert np.allclose(last.target_world, [15, 0, 0]) and last.stop_at_target


def test_algorithm_i_waits_for_rest_within_tolerance() -> None:
    t = PointToPoint()
    t.reset(context())
    t.update(measured([5, 0, 0]))
    t.update(measured([10, 0, 0]))
    moving = np.array([5.0, 0, 0])
    at = np.array([5.0, 0, 0.005])
    assert np.allclose(t.command(0, at, moving).target_world, [5, 0, 0])  # not at rest
    assert np.allclose(t.command(0, at, np.zeros(3)).target_world, [10, 0, 0])
    assert t.command(0, at, np.zeros(3)).stop_at_target is False  # keeps the welding speed


def test_repeated_measurements_add_nothing() -> None:
    t = ConvergenceRadius()
    t.reset(context())
    for _ in range(5):
        t.update(measured([5, 0, 0.001]))
    assert len(t.queue) == 1


def test_a_falsy_measurement_is_ignored() -> None:
    t = ConvergenceRadius()
    t.reset(context())
    t.update(Measurement(Feature.failed("nothing"), 0, 0, np.eye(4), np.zeros(3)))
    assert t.command(0, np.zeros(3), np.zeros(3)) is None


def test_names_and_aliases() -> None:
    assert tracker_class("I") is PointToPoint and tracker_class("II") is ConvergenceRadius
    assert isinstance(tracker("convergence-radius", radius_mm=0.5), ConvergenceRadius)


@pytest.fixture()
def user_module(tmp_path, monkeypatch):
    (tmp_path / "my_trackers.py").write_text(
        textwrap.dedent("""
        class Hold:
            def __init__(self, speed_scale=1.0):
                self.speed_scale = speed_scale
            def reset(self, context): pass
            def update(self, measurement): pass
            def command(self, t_s, tcp_world, tcp_velocity_world): return None

        class Broken:
            def reset(self, context): pass
    """)
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "my_trackers"
    sys.modules.pop("my_trackers", None)


def test_user_tracker_loads_with_its_parameters(user_module: str) -> None:
    t = tracker(f"{user_module}:Hold", speed_scale=0.5)
    assert t.speed_scale == 0.5  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    "name, params, message",
    [
        ("no_such_module_xyz:Thing", {}, "cannot import"),
        ("my_trackers:Missing", {}, "has no"),
        ("my_trackers:Broken", {}, "lacks the tracker method"),
        ("my_trackers:Hold", {"bogus": 1}, "takes no parameter"),
        ("nonsense", {}, "unknown tracker"),
    ],
)
def test_bad_trackers_are_refused_with_a_fix(user_module, name, params, message) -> None:
    with pytest.raises(PluginError, match=message) as info:
        tracker(name, **params)
    assert info.value.fix and info.value.field.startswith("tracker.")
