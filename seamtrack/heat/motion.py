"""The joint moving while it is welded: where the seam of a butt joint of two plates is, at
each station along it and each instant, cheap enough to ask every sensor frame.

Each plate is a rigid body hinged at the weld and pinned at its outer edge (``plate_width_mm``
off the weld line, by the fixture); one plate may be clamped in its plane (``fixed_plate``),
the other is held to it only by the weld behind the arc and by the tacks and clamps ahead.
At a station ``xi`` mm ahead of the arc (negative behind it) the seam moves:

- **up or down** (along the torch normal), by ``W * beta`` with ``W`` the plate's width and
  ``beta`` its angle: the transient angle near the arc from the temperature difference through
  the thickness (:func:`~seamtrack.heat.distortion.transient_angle_rad`, positive: the weld
  line rises towards the torch), less half the permanent angular distortion
  (:func:`~seamtrack.heat.distortion.permanent_angle_rad`) times the fraction of the seam
  whose weld has locked it in (the plate is one rigid body: the angle turns all of it, the
  unwelded part ahead too);
- **across**, by half the gap's change when one plate is clamped in its plane: the transverse
  shrinkage behind the arc closes the gap (Okerblom,
  :func:`~seamtrack.heat.distortion.transverse_shrinkage_mm`), and ahead of it the free plate
  turns in its plane about the arc by ``gap_rotation_rad`` (the rotational distortion of a butt
  joint's unwelded gap: it closes at low speed and opens at high speed; K. Masubuchi,
  *Analysis of Welded Structures*, Pergamon 1980, section 7.2), unless a tack or a clamp ahead
  holds it. A tack holds until the force it takes, that of bending the free plate in its plane
  as a cantilever from the arc (``3 E I delta / l^3``, ``I = t W^3 / 12``), exceeds its
  strength (:class:`~seamtrack.heat.constraints.Tack`); then it is broken for the rest of the
  weld.

The permanent part builds up with the fraction of the weld's stiffness regained: 0 while the
weld's centre line is hotter than ``stiff_below_c`` (the temperature above which steel carries
no stress, about 600 degC for mild steel: the "mechanical melting temperature" of D. Radaj,
*Heat Effects of Welding*, Springer 1992), ``1 - rise / (stiff_below_c - ambient)`` below it,
with the centre line's temperature from Rosenthal's thin plate.

Units mm, s, W, rad. The arc is at ``speed * t`` along the seam from t = 0 (it keeps moving
past the end, where the weld goes on cooling).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.heat.constraints import Clamp, Tack, check_constraints
from seamtrack.heat.distortion import (
    permanent_angle_rad,
    transient_angle_rad,
    transverse_shrinkage_mm,
)
from seamtrack.heat.materials import ThermalMaterial
from seamtrack.heat.rosenthal import rosenthal_temperature

FloatArray = NDArray[np.float64]

#: Young's modulus of carbon steel at room temperature, MPa (ASM Handbook Vol. 1, 1990:
#: 200-210 GPa for plain carbon steels). For the tacks' load only.
STEEL_MODULUS_MPA = 207_000.0
#: Stations of the transient table behind and ahead of the arc, mm (past them: 0 ahead, the
#: value at the table's end behind).
TRANSIENT_BEHIND_MM = 120.0
TRANSIENT_AHEAD_MM = 20.0
TRANSIENT_SAMPLES = 57
#: The permanent distortion is locked in over this length behind the station where the weld
#: regains its stiffness, mm (a ramp, so that the seam does not step between two frames).
LOCK_RAMP_MM = 5.0


@dataclass(frozen=True)
class JointMotion:
    """The joint's motion (see the module's text). Build it with :func:`joint_motion`."""

    speed_mm_s: float
    seam_length_mm: float
    plate_width_mm: float
    shrinkage_mm: float  # transverse shrinkage once cold
    permanent_rad: float  # the joint's permanent angular distortion (both plates) once cold
    gap_rotation_rad: float
    side: float  # +1: the free plate on the left (looking along the travel), -1 right, 0 none
    xi_mm: FloatArray  # the transient table's stations
    transient_rad: FloatArray
    developed: FloatArray  # the fraction of the permanent distortion built up at each station
    lock_mm: float = 0.0  # how far behind the arc the weld locks its distortion in
    constraints: tuple[Tack | Clamp, ...] = ()
    release_mm: FloatArray = field(default_factory=lambda: np.zeros(0))  # arc position
    #: the angle earlier passes locked in (a multi-pass job: the angles add up), both plates
    prior_rad: float = 0.0

    def shift_mm(self, s_mm: ArrayLike, t_s: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """The seam's move at stations ``s_mm`` at times ``t_s`` (broadcast): across (mm, + to
        the left looking along the travel) and along the torch normal (mm, + towards the
        torch)."""
        s, t = np.broadcast_arrays(
            np.asarray(s_mm, dtype=float), np.asarray(t_s, dtype=float)
        )  # fmt: skip
        arc = self.speed_mm_s * t
        xi = s - arc
        beta = np.interp(xi, self.xi_mm, self.transient_rad, left=self.transient_rad[0], right=0.0)
        f = np.interp(xi, self.xi_mm, self.developed, left=self.developed[0], right=0.0)
        behind = xi < 0
        f = np.where(behind, f, 0.0)
        # Each plate is one rigid body: the angle locked into the weld behind the arc turns
        # all of it, ahead of the arc too, in proportion to the length locked in.
        locked = np.clip(arc - self.lock_mm, 0.0, self.seam_length_mm) / self.seam_length_mm
        sink = 0.5 * self.permanent_rad * locked
        if self.prior_rad:  # a multi-pass job: the passes before's angle, all along the seam
            sink = sink + 0.5 * self.prior_rad
        vertical = self.plate_width_mm * (beta - sink)
        gap = -self.shrinkage_mm * f  # behind: closed by the shrinkage
        if self.gap_rotation_rad and self.side:
            turning = np.where(self.held(arc), 0.0, self.gap_rotation_rad)
            ahead = np.clip(xi, 0.0, np.maximum(self.seam_length_mm - arc, 0.0))
            gap = gap + np.where(behind, 0.0, turning * ahead)
        lateral = 0.5 * self.side * gap
        return np.asarray(lateral, dtype=float), np.asarray(vertical, dtype=float)

    def held(self, arc_mm: ArrayLike) -> NDArray[np.bool_]:
        """Whether a constraint ahead of the arc (at ``arc_mm``) holds the gap."""
        arc = np.asarray(arc_mm, dtype=float)
        out = np.zeros(arc.shape, dtype=bool)
        for c, release in zip(self.constraints, self.release_mm, strict=True):
            out |= (arc < c.position_mm) & (arc < release)
        return out

    def broken(self) -> list[bool]:
        """Each constraint: whether it breaks before the arc reaches it."""
        return [
            isinstance(c, Tack) and bool(r < c.position_mm - c.length_mm / 2)
            for c, r in zip(self.constraints, self.release_mm, strict=True)
        ]


def joint_motion(
    *,
    power_w: float,
    speed_mm_s: float,
    material: ThermalMaterial,
    thickness_mm: float,
    plate_width_mm: float,
    seam_length_mm: float,
    angle_peak_rad: float,
    angle_peak_q_per_h2: float,
    shrinkage_coefficient: float = 1.0,
    gap_rotation_rad: float = 0.0,
    fixed_plate: Literal["left", "right", "none"] = "left",
    constraints: Sequence[Tack | Clamp] = (),
    stiff_below_c: float = 600.0,
    ambient_c: float = 20.0,
    transient: bool = True,
    field_prefix: str = "distortion",
) -> JointMotion:
    """Everything :class:`JointMotion` needs, computed once before the run."""
    check_constraints(constraints, seam_length_mm, field=f"{field_prefix}.constraints")
    constraints = tuple(sorted(constraints, key=lambda c: c.position_mm))
    q = power_w / speed_mm_s if speed_mm_s > 0 else -1.0
    if not speed_mm_s > 0:
        raise SeamtrackError(
            f"a travel speed of {speed_mm_s:g} mm/s", field="simulation.welding_speed_mm_s",
            fix="give a speed > 0 mm/s",
        )  # fmt: skip
    shrink = transverse_shrinkage_mm(
        q, thickness_mm=thickness_mm, material=material, coefficient=shrinkage_coefficient
    )
    permanent = permanent_angle_rad(
        q, thickness_mm=thickness_mm, peak_rad=angle_peak_rad, peak_q_per_h2=angle_peak_q_per_h2
    )
    xi = np.linspace(-TRANSIENT_BEHIND_MM, TRANSIENT_AHEAD_MM, TRANSIENT_SAMPLES)
    xi = xi[np.abs(xi) > 1e-9]
    if transient and power_w > 0:
        start = max(thickness_mm, 1.0)  # outside the zone that yields next to the pool
        beta = np.array([
            transient_angle_rad(
                float(x), power_w=power_w, speed_mm_s=speed_mm_s, material=material,
                thickness_mm=thickness_mm, from_mm=start, to_mm=max(plate_width_mm, 2 * start),
            )
            for x in xi
        ])  # fmt: skip
    else:
        beta = np.zeros_like(xi)
    lock = (
        stiffening_distance_mm(
            power_w, speed_mm_s, material, thickness_mm, stiff_below_c - ambient_c
        )
        if stiff_below_c > ambient_c
        else 0.0
    )
    grid = np.unique(np.concatenate([xi, [-lock, -lock - LOCK_RAMP_MM]]))
    beta = np.interp(grid, xi, beta, left=beta[0], right=0.0)
    xi = grid
    developed = _developed(
        xi, power_w, speed_mm_s, material, thickness_mm, stiff_below_c, ambient_c
    )
    side = {"left": -1.0, "right": 1.0, "none": 0.0}[fixed_plate]
    release = _release(constraints, gap_rotation_rad, thickness_mm, plate_width_mm, seam_length_mm)
    return JointMotion(
        speed_mm_s=speed_mm_s, seam_length_mm=seam_length_mm, plate_width_mm=plate_width_mm,
        shrinkage_mm=shrink, permanent_rad=permanent, gap_rotation_rad=gap_rotation_rad,
        side=side, xi_mm=xi, transient_rad=beta, developed=developed,
        lock_mm=lock + LOCK_RAMP_MM / 2, constraints=constraints, release_mm=release,
    )  # fmt: skip


def _developed(
    xi: FloatArray,
    power_w: float,
    speed_mm_s: float,
    material: ThermalMaterial,
    thickness_mm: float,
    stiff_below_c: float,
    ambient_c: float,
) -> FloatArray:
    """The fraction of the permanent distortion locked in at stations ``xi`` behind the arc:
    0 while the weld's centre line is hotter than ``stiff_below_c``, 1 from
    :data:`LOCK_RAMP_MM` behind the station where it cools below it (Rosenthal's thin plate)."""
    span = stiff_below_c - ambient_c
    if not span > 0:
        raise SeamtrackError(
            f"stiff_below_c {stiff_below_c:g} degC is not above the ambient {ambient_c:g} degC",
            field="distortion.stiff_below_c",
            fix="give the temperature below which the weld carries stress (~600 degC, steel)",
        )
    lock = stiffening_distance_mm(power_w, speed_mm_s, material, thickness_mm, span)
    return np.where(xi < 0, np.clip((-xi - lock) / LOCK_RAMP_MM, 0.0, 1.0), 0.0)


def stiffening_distance_mm(
    power_w: float,
    speed_mm_s: float,
    material: ThermalMaterial,
    thickness_mm: float,
    rise_k: float,
) -> float:
    """How far behind the arc the weld's centre line has cooled to ``rise_k`` above ambient
    (Rosenthal's thin plate; 0 with no heat), by bisection (the rise falls monotonically)."""
    if power_w <= 0:
        return 0.0

    def rise(r: float) -> float:
        return float(rosenthal_temperature(
            np.array([[-r, 0.0]]), power_w=power_w, speed_mm_s=speed_mm_s,
            conductivity_w_per_mm_k=material.conductivity_w_per_mm_k,
            diffusivity_mm2_per_s=material.diffusivity_mm2_per_s,
            thickness_mm=thickness_mm, ambient_c=0.0,
        )[0])  # fmt: skip

    lo, hi = 1e-3, 1e6
    if rise(lo) <= rise_k:
        return 0.0
    for _ in range(80):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if rise(mid) > rise_k else (lo, mid)
    return hi


def _release(
    constraints: Sequence[Tack | Clamp],
    rotation_rad: float,
    thickness_mm: float,
    width_mm: float,
    seam_length_mm: float,
) -> FloatArray:
    """The arc position at which each constraint stops holding: where it breaks (a tack whose
    load, the free plate bent in its plane from the arc by the turn it prevents, exceeds its
    strength), or its own position (the arc reaches it and welds it in)."""
    stiffness = 3.0 * STEEL_MODULUS_MPA * thickness_mm * width_mm**3 / 12.0  # 3 E I, N mm^2
    out = []
    loaded_from = 0.0  # the constraint is loaded once those before it have let go
    for c in constraints:
        release = c.position_mm
        if isinstance(c, Tack) and rotation_rad:
            # load at arc a: 3 E I |phi| (p - a) / (p - a)^3 = 3 E I |phi| / (p - a)^2
            reach = math.sqrt(stiffness * abs(rotation_rad) / c.break_force_n)
            # the arc welds the tack in from its near end: it breaks only before that
            release = max(c.position_mm - reach, loaded_from)
            release = min(c.position_mm, release if release < c.position_mm - c.length_mm / 2
                          else c.position_mm)  # fmt: skip
        release = min(release, seam_length_mm)
        out.append(release)
        loaded_from = max(loaded_from, release)
    return np.asarray(out, dtype=float)
