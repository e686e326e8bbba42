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
from dataclasses import dataclass

from seamtrack.errors import SceneError

#: Largest K_v dt allowed: beyond it the discrete position loop overshoots.
MAX_GAIN_PERIOD = 0.5


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
        dt = self.control_period_s
        q, v, held = state.q, state.v, state.held
        for i in range(len(q)):
            vmax = self.velocity_max[i]
            dv = self.acceleration_max[i] * dt
            want = self.gain_1_s[i] * (held[i] - q[i])
            want = min(max(want, -vmax), vmax)
            vi = v[i] + min(max(want - v[i], -dv), dv)
            v[i] = vi
            q[i] += vi * dt


@dataclass
class ServoState:
    """Axis positions and velocities (the servo's output), the held set-point, the tick."""

    q: list[float]
    v: list[float]
    held: list[float]
    tick: int
