"""The axis servo: a position loop with gain K_v per axis behind the controller's interpolator.

Industrial controllers interpolate the path every *interpolation cycle* (the IPO cycle: 1-12 ms
on common controllers) and hand each axis drive a position set-point; the drive closes a
position loop whose proportional gain K_v (1/s, the "K_v factor" of machine-tool axes) makes
the axis follow with a lag. Without velocity feed-forward an axis moving at a steady speed v
trails its set-point by v / K_v (the *following error*); a step settles with the time constant
1 / K_v.

Model, per axis, at the control period dt: the set-point is sampled every interpolation cycle
and held in between; the axis velocity is ``K_v (held set-point - position)``, capped at the
axis' velocity limit and changed by at most its acceleration limit times dt; the position
integrates it. ``K_v dt`` must stay below 1 (the discrete loop would ring), which the scene
checks. Servo off (no gain) is the ideal axis of the paper's model: the axis is at its
set-point on every tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import SceneError
from seamtrack.jit import KERNEL

#: Largest K_v dt allowed: beyond it the discrete position loop overshoots.
MAX_GAIN_PERIOD = 0.5


@numba.njit(**KERNEL)
def loops_step(
    q: NDArray[np.float64], v: NDArray[np.float64], held: NDArray[np.float64],
    table: NDArray[np.float64], dt: float,
) -> None:  # fmt: skip
    """One control period of the axes' position loops (``q``, ``v`` in place) after the held
    set-point: K_v times the following error, within the velocity and acceleration limits
    (``table`` rows: gain, velocity limit, acceleration limit, per axis)."""
    for i in range(q.shape[0]):
        vmax = table[1, i]
        dv = table[2, i] * dt
        want = table[0, i] * (held[i] - q[i])
        want = min(max(want, -vmax), vmax)
        vi = v[i] + min(max(want - v[i], -dv), dv)
        v[i] = vi
        q[i] += vi * dt


@dataclass(frozen=True)
class Servo:
    """The servo description (frozen); its moving state is a :class:`ServoState`.

    Parameters
    ----------
    gain_1_s : tuple of float
        K_v per axis, 1/s.
    interpolation_period_s : float
        The interpolator's cycle: the set-point changes only this often.
    control_period_s : float
        The drive's cycle dt (the simulation's control period).
    velocity_max, acceleration_max : tuple of float
        Axis limits (mm/s and mm/s^2 for linear axes, rad/s and rad/s^2 for joints).
    """

    gain_1_s: tuple[float, ...]
    interpolation_period_s: float
    control_period_s: float
    velocity_max: tuple[float, ...]
    acceleration_max: tuple[float, ...]
    #: Rows gain, velocity limit, acceleration limit, per axis (:func:`loops_step`).
    _table: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = len(self.velocity_max)
        gains = tuple(float(g) for g in self.gain_1_s)
        if len(gains) == 1:
            gains = gains * n
        if len(gains) != n or not all(math.isfinite(g) and g > 0 for g in gains):
            raise SceneError(
                f"needs one gain > 0 or one per axis ({n}), got {list(self.gain_1_s)}",
                field="robot.servo_gain_1_s",
                fix="give K_v in 1/s, e.g. 30, or [30, 30, ...] per axis",
            )
        dt = self.control_period_s
        worst = max(gains) * dt
        if worst > MAX_GAIN_PERIOD:
            raise SceneError(
                f"K_v = {max(gains):g} 1/s at a control period of {dt:g} s gives K_v dt = "
                f"{worst:.3g}: the discrete position loop would ring",
                field="robot.servo_gain_1_s",
                fix=f"use K_v <= {MAX_GAIN_PERIOD / dt:.4g} 1/s, or a shorter "
                "robot.control_period_s",
            )
        if not (self.interpolation_period_s >= dt * (1 - 1e-9)):
            raise SceneError(
                f"interpolation period {self.interpolation_period_s:g} s is shorter than the "
                f"control period {dt:g} s",
                field="robot.interpolation_period_s",
                fix="use a whole multiple of robot.control_period_s",
            )
        object.__setattr__(self, "gain_1_s", gains)
        table = np.array([gains, self.velocity_max, self.acceleration_max], dtype=np.float64)
        object.__setattr__(self, "_table", table)

    @property
    def ipo_ticks(self) -> int:
        """Control ticks per interpolation cycle."""
        return max(1, round(self.interpolation_period_s / self.control_period_s))

    def lag_mm(self, speed: float, axis: int = 0) -> float:
        """Steady following error v / K_v of an axis moving at ``speed``."""
        return speed / self.gain_1_s[axis]

    def new_state(self, position: list[float]) -> ServoState:
        """At rest on ``position``."""
        return ServoState(list(position), [0.0] * len(position), list(position), 0)

    def follow(self, state: ServoState, setpoint: list[float]) -> None:
        """One control period: sample the set-point on an interpolation tick, then move each
        axis under its position loop and limits (in place)."""
        if state.tick % self.ipo_ticks == 0:
            state.held[:] = setpoint
        state.tick += 1
        q, v = np.array(state.q), np.array(state.v)
        loops_step(q, v, np.array(state.held), self._table, self.control_period_s)
        state.q[:], state.v[:] = q.tolist(), v.tolist()


@dataclass
class ServoState:
    """Axis positions and velocities (the servo's output), the held set-point, the tick."""

    q: list[float]
    v: list[float]
    held: list[float]
    tick: int
