"""The loop's fast path (built-in trajectory tracker on a gantry, compiled ticks) against the
reference path (the same tracker seen through the public tracker protocol), and the progress
kernel against :meth:`Seam.closest_near`: the same numbers, to the last bit."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from seamtrack.control.trajectory import TrajectoryTracker
from seamtrack.geometry.seam import Seam
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.loop import run
from seamtrack.simulation.progress import DOT_NORM, NEAR_WINDOW_MM, ProgressTracker, progress_near
from seamtrack.simulation.scene import load_scene

#: The paper's curve, 25 mm of it: about 5 s simulated, with a corner envelope and an end.
SHORT: dict[str, Any] = {"seam.length_mm": 25.0, "tracker.name": "trajectory"}


class Delegating:
    """A user's tracker as the loop sees one: the built-in tracker behind the protocol only."""

    def __init__(self, inner: Any):
        self.inner = inner

    def reset(self, context: Any) -> None:
        self.inner.reset(context)

    def update(self, measurement: Any) -> None:
        self.inner.update(measurement)

    def command(self, t_s: float, tcp_world: Any, tcp_velocity_world: Any) -> Any:
        return self.inner.command(t_s, tcp_world, tcp_velocity_world)

    @property
    def stop_cause(self) -> str:
        return str(self.inner.stop_cause)


def _both(overrides: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> tuple[Any, Any]:
    parts = build_parts(load_scene("paper-verification", {**SHORT, **overrides}))
    assert type(parts.tracker) is TrajectoryTracker
    reference = run(dataclasses.replace(parts, tracker=Delegating(parts.tracker)))
    with monkeypatch.context() as patch:
        # The fast path never builds a Command: calling command() would be the slow path.
        patch.setattr(TrajectoryTracker, "command", None)
        fast = run(parts)
    return reference, fast


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"robot.servo_gain_1_s": 40.0, "robot.interpolation_period_s": 0.004},
        {"sensor.latency_s": 0.03, "tracker.params.use_capture_pose": False},
        # The set-point bridges past the seam's end (the program's end ignored) into the x end
        # stop: a limit violation.
        {"robot.position_max_mm": [126.0, 150.0, 150.0], "tracker.params.end_zone_mm": 0.0},
    ],
    ids=["ideal-axes", "servo", "latency-naive-pose", "end-stop"],
)
def test_fast_path_gives_the_reference_paths_numbers(
    overrides: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    reference, fast = _both(overrides, monkeypatch)
    for name in ("tcp_world", "target_world", "error_mm", "arc_length_mm", "welding"):
        np.testing.assert_array_equal(getattr(fast.trace, name), getattr(reference.trace, name))
    for key in ("t_capture_s", "found", "point_world"):
        np.testing.assert_array_equal(fast.trace.frames[key], reference.trace.frames[key])
    timing = {"wall_time_s", "sense_wall_time_s"}
    expected = {k: v for k, v in reference.summary.items() if k not in timing}
    got = {k: v for k, v in fast.summary.items() if k not in timing}
    assert got.keys() == expected.keys()
    for key, value in expected.items():
        if isinstance(value, float) and np.isnan(value):
            assert np.isnan(got[key]), key
        else:
            assert got[key] == value, key
    expected_status = "limit_violation" if "robot.position_max_mm" in overrides else "completed"
    assert reference.summary["status"] == expected_status


def _hairpin() -> Seam:
    points = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 0.5, 0.0], [0.0, 0.5, 0.0]]
    return Seam.from_points(np.array(points))


@pytest.mark.parametrize(
    "seam",
    [Seam.from_paper(2.0, 405.0), Seam.from_paper(0.25, 30.0), _hairpin()],
    ids=["paper-2mm", "paper-0.25mm", "hairpin"],
)
def test_progress_kernel_is_seam_closest_near(seam: Seam) -> None:
    rng = np.random.default_rng(14)
    kernel = ProgressTracker(seam)
    for _ in range(400):
        s = rng.uniform(-1.0, seam.length_mm + 1.0)
        point = seam.interpolate([s])[0] + rng.normal(size=3) * 10.0 ** rng.uniform(-6, 1)
        hint = float(np.clip(s + 3.0 * rng.normal(), 0.0, seam.length_mm))
        if rng.random() < 0.1:  # on a knot, or at an end: the window's cut ends
            hint = float(rng.choice(seam.arc_length_mm))
        assert kernel.closest_near(point.tolist(), hint) == seam.closest_near(point, hint)
        args = (kernel.points, kernel.knots, kernel.columns, point, hint, seam.length_mm)
        compiled = progress_near(*args, NEAR_WINDOW_MM, DOT_NORM)
        assert compiled == seam.closest_near(point, hint)  # the loop's checks, compiled


@pytest.mark.parametrize(
    "overrides", [{}, {"robot.servo_gain_1_s": 40.0, "robot.interpolation_period_s": 0.004}],
    ids=["ideal-axes", "servo"],
)  # fmt: skip
def test_kernels_compiled_before_the_first_frame_are_the_ones_the_run_calls(
    overrides: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The loop compiles the ticks' and the tracker's kernels before its first frame (a first
    # run does it while the warming child compiles the extractor): for the very types the run
    # then calls them with, else the run compiles them again after all.
    import seamtrack.control.path_kernels as path_kernels
    import seamtrack.simulation.ticks as ticks
    from seamtrack.jit import compile_for

    compiled: list[tuple[Any, tuple[Any, ...]]] = []

    def recording(kernel: Any, *args: Any) -> None:
        compile_for(kernel, *args)
        compiled.append((kernel, tuple(kernel.typeof_pyval(a) for a in args)))

    monkeypatch.setattr(ticks, "compile_for", recording)
    monkeypatch.setattr(path_kernels, "compile_for", recording)
    kernels = (ticks.gantry_ticks, path_kernels.take_point)
    before = {kernel: set(kernel.overloads) for kernel in kernels}
    run(build_parts(load_scene("paper-verification", {**SHORT, **overrides})))
    assert {kernel for kernel, _ in compiled} == set(kernels)
    for kernel in kernels:
        ahead = {types for k, types in compiled if k is kernel}
        assert ahead <= set(kernel.overloads)
        assert set(kernel.overloads) - before[kernel] <= ahead
