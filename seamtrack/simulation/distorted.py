"""A run on a part that moves while it is welded (``[distortion]``, issue 39): the sensor sees
the part where it is at each frame, and the run is scored against the seam where it is.

The ray-cast scene is built once. At a frame the joint near the stripe has moved by ``d``
(:class:`seamtrack.heat.motion.JointMotion` at the station the stripe crosses): casting the
sensor's rays on the moved part is casting them from the sensor moved by ``-d`` on the part
as built, so the sensor's pose goes into the part's frame and the seam point it finds comes
back by ``+d`` (its laser-frame coordinates are the same in both). The two plates move as one
body there: the gap's own change (a few tenths of a millimetre) is not in the stripe.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.geometry.seam import Seam
from seamtrack.heat.constraints import Clamp, Tack
from seamtrack.heat.materials import thermal_material
from seamtrack.heat.motion import JointMotion, joint_motion
from seamtrack.heat.rosenthal import process_power_w

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class MovingSeam:
    """The seam of :attr:`motion`, in the world: its move at stations and times.

    ``joint``: the weld line the plates move about, when it is not :attr:`seam` itself (a
    multi-pass job's pass path, a bead's height over the root, whose local slope at a bead's
    crown or over the fill's end is no direction the plates move in): its stations and its
    frame (tangent, torch normal) give the move, the same rigid displacement for every point
    of the part's section at a station. ``None``: :attr:`seam` is the weld line."""

    seam: Seam
    motion: JointMotion
    joint: Seam | None = None

    @property
    def line(self) -> Seam:
        """The weld line the move is given along (:attr:`joint`, else :attr:`seam`)."""
        return self.seam if self.joint is None else self.joint

    def station_mm(self, points: FloatArray) -> FloatArray:
        """The weld line's stations (arc length, mm) nearest to world ``points`` (n, 3)."""
        return np.asarray(self.line.closest(points).arc_length_mm, dtype=float)

    def shift_world(self, s_mm: FloatArray, t_s: FloatArray) -> FloatArray:
        """(n, 3) world displacement of the part at the weld line's stations ``s_mm`` (arc
        length along :attr:`line`), times ``t_s``."""
        line = self.line
        s = np.atleast_1d(np.asarray(s_mm, dtype=float))
        lateral, vertical = self.motion.shift_mm(s, t_s)
        tangent = line.tangent_at(s)
        knots = line.arc_length_mm
        normal = np.column_stack(
            [np.interp(np.clip(s, 0, line.length_mm), knots, line.normals[:, k])
             for k in range(3)]
        )  # fmt: skip
        normal -= np.sum(normal * tangent, axis=1, keepdims=True) * tangent
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        left = np.cross(normal, tangent)
        return np.asarray(lateral[:, None] * left + vertical[:, None] * normal, dtype=float)

    def sense(self, inner: Callable[..., Any]) -> Callable[..., Any]:
        """``inner`` (a run's ``sense``) on the part as it is at the frame's time."""

        def sense(T_world_sensor: FloatArray, t_s: float, hint: Any = None) -> Any:
            s = self.station_mm(T_world_sensor[:3, 3])
            d = self.shift_world(s, np.array([t_s]))[0]
            T = np.array(T_world_sensor, dtype=float)
            T[:3, 3] -= d
            feature = inner(T, t_s, hint) if hint is not None else inner(T, t_s)
            if feature:
                feature = dataclasses.replace(feature, point_world=feature.point_world + d)
            return feature

        return sense

    def rescore(self, trace: Any) -> Any:
        """``trace`` scored against the seam where it is at each tick; with ``seam_shift_mm``
        (how far the seam has moved at the torch) and the taught path's error."""
        tcp = trace.tcp_world
        if not len(tcp):
            return dataclasses.replace(trace, seam_shift_mm=np.zeros(0))
        d = self.shift_world(self.station_mm(tcp), trace.t_s)
        near = self.seam.closest(tcp - d)  # the torch's station on the moved seam
        on_line = near.arc_length_mm if self.joint is None else self.station_mm(near.points)
        d = self.shift_world(on_line, trace.t_s)
        moved = near.points + d
        error_vec = tcp - moved
        tangent = self.seam.tangent_at(near.arc_length_mm)
        error_vec -= np.sum(error_vec * tangent, axis=1, keepdims=True) * tangent
        lateral_dir = np.cross(tangent, _normal_rows(self.seam, near.arc_length_mm, tangent))
        normal = np.cross(lateral_dir, tangent)
        return dataclasses.replace(
            trace,
            closest_world=moved,
            error_mm=np.linalg.norm(error_vec, axis=1),
            error_lateral_mm=np.sum(error_vec * lateral_dir, axis=1),
            error_vertical_mm=np.sum(error_vec * normal, axis=1),
            seam_shift_mm=np.linalg.norm(d, axis=1),
        )

    def summary(self, trace: Any, seam_samples: int = 201) -> dict[str, float]:
        """``max_seam_shift_mm`` (anywhere along the seam, over the run) and
        ``untracked_max_error_mm`` (the taught path, the seam as built, at the torch while
        welding: the seam's move there)."""
        weld = trace.welding
        untracked = float(np.max(trace.seam_shift_mm[weld])) if weld.any() else 0.0
        s = np.linspace(0.0, self.line.length_mm, seam_samples)
        t = trace.t_s[:: max(1, len(trace.t_s) // 200)] if len(trace.t_s) else np.zeros(1)
        lat, ver = self.motion.shift_mm(s[None, :], t[:, None])
        return {
            "max_seam_shift_mm": float(np.max(np.hypot(lat, ver))),
            "untracked_max_error_mm": untracked,
            "tacks_broken": float(sum(self.motion.broken())),
        }


def _normal_rows(seam: Seam, s: FloatArray, tangent: FloatArray) -> FloatArray:
    knots = seam.arc_length_mm
    n = np.column_stack(
        [np.interp(np.clip(s, 0, seam.length_mm), knots, seam.normals[:, k]) for k in range(3)]
    )
    n -= np.sum(n * tangent, axis=1, keepdims=True) * tangent
    return np.asarray(n / np.linalg.norm(n, axis=1, keepdims=True), dtype=float)


def moving_seam(config: Any, seam: Seam, joint: Seam | None = None) -> MovingSeam:
    """The scene's ``[distortion]`` on ``seam``, moving about the weld line ``joint`` (None:
    ``seam`` is the weld line; :class:`MovingSeam`)."""
    line = seam if joint is None else joint
    d = config.distortion
    if config.process is None:
        raise SeamtrackError(
            "[distortion] needs the arc's heat, and the scene has no [process]",
            field="process",
            fix="add a [process] section (voltage_v, current_a, thermal_efficiency)",
        )
    constraints: list[Tack | Clamp] = [
        Tack(t.position_mm, t.length_mm, t.throat_mm) for t in d.tacks
    ]
    for i, tack in enumerate(constraints):  # name the scene's own field on a bad position
        _on_seam(tack.position_mm, line.length_mm, f"distortion.tacks[{i}].position_mm")
    for i, c in enumerate(d.clamps):
        _on_seam(c.position_mm, line.length_mm, f"distortion.clamps[{i}].position_mm")
    constraints += [Clamp(c.position_mm) for c in d.clamps]
    motion = joint_motion(
        power_w=process_power_w(config.process),
        speed_mm_s=config.simulation.welding_speed_mm_s,
        material=thermal_material(d.material, field="distortion.material"),
        thickness_mm=d.thickness_mm,
        plate_width_mm=d.plate_width_mm,
        seam_length_mm=line.length_mm,
        angle_peak_rad=math.radians(d.angle_peak_deg),
        angle_peak_q_per_h2=d.angle_peak_q_per_h2_j_mm3,
        shrinkage_coefficient=d.shrinkage_coefficient,
        gap_rotation_rad=math.radians(d.gap_rotation_deg),
        fixed_plate=d.fixed_plate,
        constraints=constraints,
        stiff_below_c=d.stiff_below_c,
        transient=d.transient,
    )
    return MovingSeam(seam, motion, joint)


def _on_seam(position_mm: float, length_mm: float, field: str) -> None:
    if not 0.0 <= position_mm <= length_mm:
        raise SeamtrackError(
            f"{position_mm:g} mm lies outside the seam (0 to {length_mm:g} mm)",
            field=field,
            fix=f"give a position along the seam, from 0 to {length_mm:g} mm",
        )
