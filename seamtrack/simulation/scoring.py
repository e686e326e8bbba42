"""Scoring the torch's orientation and an arm's joint space.

Orientation: the torch axis's work and travel angles in the seam frame at the closest true
seam point (:mod:`seamtrack.geometry.torch`), over the welding portion: max (of the absolute
value), RMS and 95th percentile, in degrees. A robot that commands the tool's orientation (an
arm) is scored on its *errors*, the angles less the scene's ``torch`` angles (summary keys
``*_work_angle_error_deg``, ``*_travel_angle_error_deg``). A 3-axis gantry cannot turn its
torch (it is its base's z on every tick), so it has no orientation error to report: its keys
give the fixed torch's angles against the seam instead (``*_fixed_torch_work_angle_deg``,
``*_fixed_torch_travel_angle_deg``), a property of the part's shape, not a tracking fault.

Joint space, for an arm: the fastest joint speed used (deg/s, and as a fraction of that joint's
limit), the closest approach to a joint limit (deg), to the wrist singularity (the angle between
the axes of joints 4 and 6, deg) and the smallest singular value of the TCP Jacobian, on the
trace's decimated ticks (``simulation.trace_period_s``); and the ticks on which a joint's
velocity or acceleration limit shaped the motion, or a position was clamped to its range.
"""

from __future__ import annotations

import dataclasses
import math
from array import array
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def torch_axes(robot: Any, axis_log: array | FloatArray) -> FloatArray:
    """(n, 3) torch axes of an arm's run, or the gantry's fixed (3,) axis."""
    if robot.turns_tool:
        return np.frombuffer(axis_log, dtype=np.float64).reshape(-1, 3).copy()
    return np.asarray(robot.T_world_base[:3, 2], dtype=np.float64)


def with_joints(trace: Any, joint_log: array | FloatArray, robot: Any) -> Any:
    """The trace with an arm's joint positions (n, k); the gantry's trace keeps (n, 0)."""
    if not robot.turns_tool:
        return dataclasses.replace(trace, joints_rad=np.zeros((len(trace.t_s), 0)))
    joints = np.frombuffer(joint_log, dtype=np.float64).reshape(len(trace.t_s), -1).copy()
    return dataclasses.replace(trace, joints_rad=joints)


def _stats(name: str, values_rad: FloatArray) -> dict[str, float]:
    a = np.degrees(np.abs(values_rad))
    if not a.size:
        nan = math.nan
        return {f"max_{name}_deg": nan, f"rms_{name}_deg": nan, f"p95_{name}_deg": nan}
    return {
        f"max_{name}_deg": float(a.max()),
        f"rms_{name}_deg": float(np.sqrt(np.mean(a**2))),
        f"p95_{name}_deg": float(np.percentile(a, 95)),
    }


def _wrap(angle: FloatArray) -> FloatArray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def orientation_summary(trace: Any, robot: Any, cfg: Any, state: Any) -> dict[str, Any]:
    """Summary keys for the torch orientation and (an arm's) joint space."""
    weld = trace.welding
    out: dict[str, Any] = {
        "robot": getattr(getattr(robot, "kinematics", None), "name", "cartesian"),
        "work_angle_deg": math.degrees(cfg.work_angle_rad),
        "travel_angle_deg": math.degrees(cfg.travel_angle_rad),
    }
    if robot.turns_tool:
        out.update(_stats("work_angle_error", trace.work_angle_error_rad[weld]))
        out.update(_stats("travel_angle_error", trace.travel_angle_error_rad[weld]))
    else:  # the torch's fixed angles against the seam: the error plus the scene's angle
        work = _wrap(trace.work_angle_error_rad[weld] + cfg.work_angle_rad)
        travel = _wrap(trace.travel_angle_error_rad[weld] + cfg.travel_angle_rad)
        out.update(_stats("fixed_torch_work_angle", work))
        out.update(_stats("fixed_torch_travel_angle", travel))
    if robot.turns_tool:
        out.update(joint_figures(robot, trace, cfg.trace_period_s))
        out["joint_limited_ticks"] = int(state.limited_ticks)
        out["joint_clamped_ticks"] = int(state.clamped_ticks)
    return out


def joint_figures(robot: Any, trace: Any, period_s: float) -> dict[str, Any]:
    """Joint-space figures of an arm's run (see the module docstring)."""
    kin = robot.kinematics
    joints = trace.joints_rad
    if len(joints) < 2:
        return {}
    dt = float(trace.t_s[1] - trace.t_s[0])
    speed = np.abs(np.diff(joints, axis=0)) / dt
    fraction = speed / kin.velocity_max_rad_s
    worst = np.unravel_index(int(np.argmax(fraction)), fraction.shape)
    margin = np.minimum(joints - kin.lower_rad, kin.upper_rad - joints)
    closest = np.unravel_index(int(np.argmin(margin)), margin.shape)
    idx = trace.decimated(period_s)
    wrist, sigma = kin.wrist_and_sigma(joints[idx])
    return {
        "max_joint_speed_deg_s": float(np.degrees(speed.max())),
        "max_joint_speed_fraction": float(fraction[worst]),
        "max_joint_speed_joint": int(worst[1]) + 1,
        "min_joint_limit_margin_deg": float(np.degrees(margin[closest])),
        "min_joint_limit_margin_joint": int(closest[1]) + 1,
        "min_wrist_angle_deg": float(np.degrees(wrist.min())),
        "min_jacobian_sigma": float(sigma.min()),
        "joint_travel_deg": np.round(np.degrees(np.ptp(joints, axis=0)), 3).tolist(),
    }
