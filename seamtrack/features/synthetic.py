"""Synthetic stripe profiles of weld joints, with their ground truth.

The joint is a cross-section in the *joint frame* {J} (used as the world frame of the profile):
x_J runs along the seam, y_J is lateral, z_J points into the part (away from the sensor), and the
joint's reference point (the top surface at the seam) is the origin. Every surface is the
cross-section extruded along x_J, so the 3D problem is exact in 2D:

* the laser frame is placed with its axes along {J}'s at the reference point
  ``(lateral_offset_mm, standoff_mm)`` of the laser plane, then tilted about that point: first
  pitched about the lateral axis y_J by ``pitch_deg`` (the sensor leans along the seam; the
  laser plane is no longer normal to the seam, which stretches the profile in range by
  1 / cos(pitch)), then rolled about the seam axis x_J by ``roll_deg`` (the profile turns in the
  y-z plane). ``T_world_sensor = Rx(roll) Ry(pitch) Trans(0, -lateral_offset, -standoff)``.
* each of N laser rays (the sensor's columns, uniform in angle across the field of view) is cast
  from the emitter; as the surfaces are extruded along x_J, the first hit along a 3D ray is the
  first crossing of its (y_J, z_J) projection with the cross-section polyline, at the same ray
  parameter. The laser-frame point is then t (sin phi, cos phi), exactly.
* a hit is kept when the camera (at x_L = b) sees it (the 2D projection of the sight line
  crosses no other surface, and the camera is on the lit side), the incidence angle is within
  ``sensor.max_incidence_rad``, and it lies in the trapezoidal field of view. It is then
  pixel-quantized with :meth:`LaserLineSensor.measure`.

There is no approximation in the tilted geometry: the profile is the exact section of the
extruded joint by the tilted laser plane, sampled by the fan of rays.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from seamtrack.features import _synthetic_kernels as kern
from seamtrack.features.arrays import FloatArray
from seamtrack.sensing.profiles import Profile, Reason
from seamtrack.sensing.sensor import LaserLineSensor

#: Half length of the "infinite" plates, mm (far beyond any field of view).
_FAR_MM = 1000.0
#: Arcs (tack welds, bead caps) are drawn with this many straight pieces.
_ARC_PIECES = 48

JOINTS = ("square-butt", "v-groove", "fillet", "lap", "outside-corner", "flat", "block")

_DEFAULTS: dict[str, dict[str, float]] = {
    "square-butt": {"gap_mm": 1.0, "misalignment_mm": 0.0, "thickness_mm": 8.0},
    "v-groove": {
        "included_angle_deg": 60.0,
        "gap_mm": 1.0,
        "root_face_mm": 1.0,
        "thickness_mm": 8.0,
        "misalignment_mm": 0.0,
    },
    "fillet": {"web_angle_deg": 90.0},
    "lap": {"thickness_mm": 2.0, "gap_mm": 0.0},
    "outside-corner": {"corner_angle_deg": 90.0},
    "flat": {},
    "block": {"width_mm": 4.0, "height_mm": 6.0, "draft_deg": 5.0},
}


@dataclass(frozen=True)
class Imperfections:
    """Seeded imperfections of a synthetic profile (all off by default).

    Attributes
    ----------
    noise_mm : float
        Standard deviation of Gaussian noise on the range z_L of every lit point.
    outlier_fraction : float
        Fraction of lit columns whose point is replaced by a random range along its ray
        (uniform over the depth of field).
    dropout_runs : int
        Number of runs of consecutive columns lost (``Reason.DROPOUT``).
    dropout_max_columns : int
        Each run's length is uniform in 1..this.
    reflection_probability : float
        Chance of a false reflection stripe: a run of columns whose points lie on a spurious
        line 1-4 mm in front of or behind the surface, tilted by up to 45 deg.
    reflection_fraction : float
        Length of the reflection run as a fraction of the columns.
    tack_probability : float
        Chance that the laser crosses a tack weld: a circular mound of ``tack_height_mm`` and
        ``tack_width_mm`` on the seam point (it hides the root; ground truth is unchanged).
    tack_height_mm, tack_width_mm : float
    bead_height_mm : float
        > 0 adds a weld-bead cap: a circular arc across the joint from toe to toe (``bead_width_mm``
        apart, centred on the seam), its crown this far in front of the higher toe. The joint's
        ground truth is unchanged (the extractor should then fail or be judged wrong).
    bead_width_mm : float
    """

    noise_mm: float = 0.0
    outlier_fraction: float = 0.0
    dropout_runs: int = 0
    dropout_max_columns: int = 10
    reflection_probability: float = 0.0
    reflection_fraction: float = 0.03
    tack_probability: float = 0.0
    tack_height_mm: float = 1.0
    tack_width_mm: float = 4.0
    bead_height_mm: float = 0.0
    bead_width_mm: float = 12.0

    def __bool__(self) -> bool:
        return self.random or self.bead_height_mm > 0

    @property
    def random(self) -> bool:
        """True when a random draw is needed (then an rng is required)."""
        return any(
            (
                self.noise_mm > 0,
                self.outlier_fraction > 0,
                self.dropout_runs > 0,
                self.reflection_probability > 0,
                self.tack_probability > 0,
            )
        )


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """What the synthetic profile shows, exactly.

    Attributes
    ----------
    joint : str
        One of :data:`JOINTS`.
    seam_laser : (2,) float
        (y_L, z_L) of the seam point in the laser plane; empty (0,) for ``"flat"``.
    seam_world : (3,) float
        The same in the joint frame (the profile's world frame); empty for ``"flat"``.
    edges_laser : (k, 2) float
        Groove edges, left to right in the joint frame: the plate edges of a square butt, the
        top (outer) edges of a V-groove, the top sheet's edge of a lap joint; (0, 2) otherwise.
    gap_mm : float
        Root gap (square butt, V-groove), sheet gap (lap), NaN otherwise.
    T_world_sensor : (4, 4) float
        Pose of the laser frame in the joint frame.
    params : mapping
        The joint parameters used (defaults filled in).
    tack, reflection : bool
        Whether this profile crossed a tack weld / shows a false reflection.
    """

    joint: str
    seam_laser: FloatArray
    seam_world: FloatArray
    edges_laser: FloatArray
    gap_mm: float
    T_world_sensor: FloatArray
    params: Mapping[str, float] = field(default_factory=dict)
    tack: bool = False
    reflection: bool = False

    @property
    def has_seam(self) -> bool:
        return self.seam_laser.shape == (2,)


# ----------------------------------------------------------------- joint cross-sections
def _polyline(*vertices: tuple[float, float]) -> FloatArray:
    """(k, 2, 2) segments joining consecutive (y, z) vertices."""
    v = np.asarray(vertices, dtype=np.float64)
    return np.stack([v[:-1], v[1:]], axis=1)


def joint_section(joint: str, **params: float) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """The cross-section of a joint in the joint frame (y_J, z_J), z into the part.

    Seam points (the point a torch aims at), by family:

    * ``square-butt``: the midpoint of the two plates' top edges, (0, misalignment / 2); the
      right plate sits ``misalignment_mm`` deeper.
    * ``v-groove``: the root centre, the midpoint of the two corners where the bevels meet the
      root faces (the bottom of the bevels, at depth thickness - root_face); with no gap it
      is the bevels' intersection.
    * ``fillet``: the corner line where the two faces meet, (0, 0). The faces (web and flange,
      ``web_angle_deg`` apart) are presented symmetric about the laser axis.
    * ``lap``: the corner where the top sheet's edge (a face normal to the sheets) meets the
      lower sheet, (0, 0); the top sheet (``thickness_mm``, ``gap_mm`` above the lower sheet)
      lies on the +y side.
    * ``outside-corner``: the apex where the two faces (``corner_angle_deg`` apart) meet, (0, 0).
    * ``flat``: a plate at z = 0, no seam.
    * ``block``: a raised block on a plate (no joint, no seam): ``width_mm`` wide on top,
      ``height_mm`` high, its walls leaning in by ``draft_deg`` from the plate's normal.

    Returns
    -------
    segments : (k, 2, 2) float
        The visible surfaces as straight pieces ((y0, z0), (y1, z1)).
    seam : (2,) float
        The seam point, empty for ``flat``.
    edges : (m, 2) float
        Groove edges (see :class:`GroundTruth`).
    gap_mm : float
    """
    if joint not in _DEFAULTS:
        raise ValueError(f"unknown joint {joint!r}; use one of {', '.join(JOINTS)}")
    unknown = set(params) - set(_DEFAULTS[joint])
    if unknown:
        raise ValueError(
            f"{joint} has no parameter(s) {sorted(unknown)}; it takes {sorted(_DEFAULTS[joint])}"
        )
    p = {**_DEFAULTS[joint], **params}
    L = _FAR_MM
    no_edges = np.empty((0, 2))
    if joint == "flat":
        return _polyline((-L, 0.0), (L, 0.0)), np.empty(0), no_edges, math.nan
    if joint == "block":
        w, h = p["width_mm"] / 2, p["height_mm"]
        if not (w > 0 and h > 0 and 0 <= p["draft_deg"] < 90):
            raise ValueError("block needs width_mm > 0, height_mm > 0, 0 <= draft_deg < 90")
        foot = w + h * math.tan(math.radians(p["draft_deg"]))
        segs = _polyline((-L, 0.0), (-foot, 0.0), (-w, -h), (w, -h), (foot, 0.0), (L, 0.0))
        return segs, np.empty(0), no_edges, math.nan
    if joint == "square-butt":
        g, m, t = p["gap_mm"], p["misalignment_mm"], p["thickness_mm"]
        segs = np.concatenate(
            [
                _polyline((-L, 0.0), (-g / 2, 0.0), (-g / 2, t)),
                _polyline((g / 2, t + m), (g / 2, m), (L, m)),
            ]
        )
        edges = np.array([[-g / 2, 0.0], [g / 2, m]])
        return segs, np.array([0.0, m / 2]), edges, g
    if joint == "v-groove":
        g, r, t, m = p["gap_mm"], p["root_face_mm"], p["thickness_mm"], p["misalignment_mm"]
        half = math.radians(p["included_angle_deg"]) / 2
        if not (0 < half < math.pi / 2 and 0 <= r < t and g >= 0):
            raise ValueError(
                "v-groove needs 0 < included_angle_deg < 180 and 0 <= root_face "
                "< thickness and gap >= 0"
            )
        w2 = g / 2 + (t - r) * math.tan(half)
        segs = np.concatenate(
            [
                _polyline((-L, 0.0), (-w2, 0.0), (-g / 2, t - r), (-g / 2, t)),
                _polyline((g / 2, t + m), (g / 2, t - r + m), (w2, m), (L, m)),
            ]
        )
        edges = np.array([[-w2, 0.0], [w2, m]])
        return segs, np.array([0.0, t - r + m / 2]), edges, g
    if joint in ("fillet", "outside-corner"):
        angle = p["web_angle_deg"] if joint == "fillet" else p["corner_angle_deg"]
        half = math.radians(angle) / 2
        if not 0 < half < math.pi / 2:
            raise ValueError(f"{joint}: the angle must lie in (0, 180) deg")
        # Faces long enough to leave any field of view, short enough not to pass the emitter.
        face = 60.0
        sign = -1.0 if joint == "fillet" else 1.0  # fillet faces rise towards the sensor
        dy, dz = face * math.sin(half), sign * face * math.cos(half)
        return _polyline((-dy, dz), (0.0, 0.0), (dy, dz)), np.zeros(2), no_edges, math.nan
    # lap
    t, g = p["thickness_mm"], p["gap_mm"]
    segs = np.concatenate(
        [_polyline((-L, 0.0), (L, 0.0)), _polyline((L, -g), (0.0, -g), (0.0, -g - t), (L, -g - t))]
    )
    return segs, np.zeros(2), np.array([[0.0, -g - t]]), g


def _arc(a: FloatArray, crown: FloatArray, b: FloatArray) -> FloatArray:
    """(k, 2, 2) pieces of the circular arc from a through crown to b (a line if collinear)."""
    (ax, ay), (px, py), (bx, by) = a, crown, b
    d = 2 * (ax * (py - by) + px * (by - ay) + bx * (ay - py))
    if abs(d) < 1e-12:
        return _polyline(tuple(a), tuple(b))
    a2, p2, b2 = ax * ax + ay * ay, px * px + py * py, bx * bx + by * by
    cx = (a2 * (py - by) + p2 * (by - ay) + b2 * (ay - py)) / d
    cy = (a2 * (bx - px) + p2 * (ax - bx) + b2 * (px - ax)) / d
    radius = math.hypot(ax - cx, ay - cy)
    ta, tp, tb = (math.atan2(q[1] - cy, q[0] - cx) for q in (a, crown, b))
    sweep = (tb - ta) % (2 * math.pi)
    if (tp - ta) % (2 * math.pi) > sweep:  # the crown lies on the other way round
        sweep -= 2 * math.pi
    angles = ta + np.linspace(0.0, sweep, _ARC_PIECES + 1)
    v = np.column_stack([cx + radius * np.cos(angles), cy + radius * np.sin(angles)])
    return np.stack([v[:-1], v[1:]], axis=1)


# ----------------------------------------------------------------- 2D ray casting
def _cast(origin: FloatArray, dirs: FloatArray, segs: FloatArray) -> tuple[FloatArray, NDArray]:
    """First crossing of rays o + t d (t > 0) with segments.

    Parameters
    ----------
    origin : (2,) float
    dirs : (n, 2) float
    segs : (k, 2, 2) float

    Returns
    -------
    t : (n,) float, inf where nothing is hit
    index : (n,) int, the segment hit (-1 for none)
    """
    hit = kern.cast(_f64(origin), _f64(dirs), _f64(segs).reshape(-1, 2, 2))
    return hit.t, hit.segment


def _occluded(hits: FloatArray, eye: FloatArray, segs: FloatArray) -> NDArray[np.bool_]:
    """(n,) True where the 2D sight line from a hit to ``eye`` crosses a segment (compiled:
    :func:`seamtrack.features._synthetic_kernels.occluded`)."""
    return kern.occluded(_f64(hits), _f64(eye), _f64(segs).reshape(-1, 2, 2))


def _f64(a: FloatArray) -> FloatArray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _rotation(pitch_rad: float, roll_rad: float) -> FloatArray:
    cp, sp, cr, sr = (
        math.cos(pitch_rad),
        math.sin(pitch_rad),
        math.cos(roll_rad),
        math.sin(roll_rad),
    )
    Ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return Rx @ Ry


def ray_angles(sensor: LaserLineSensor, rays: int) -> FloatArray:
    """(rays,) fan angles phi (rad, from the z_L axis towards +y_L) spanning the field of view.

    The fan is as wide as the widest corner of the trapezoid (near or far end), so every
    point of the field of view is sampled; rays outside the trapezoid at some ranges are
    clipped there (``Reason.OUT_OF_RANGE``).
    """
    near, far = sensor.range_near_mm, sensor.range_far_mm
    half = max(math.atan2(float(sensor.half_width_mm(z)), z) for z in (near, far))
    return np.linspace(-half, half, int(rays))


def line_in_laser_plane(T: FloatArray, yz: FloatArray) -> FloatArray:
    """(m, 2) laser-plane crossings of seam-parallel lines through joint-frame points (y, z)."""
    if yz.size == 0:
        return np.empty((0, 2))
    R, o = T[:3, :3], T[:3, 3]
    p = np.column_stack([np.zeros(len(yz)), yz]) - o
    # x_L(p + x e_x) = R[:, 0] . (p + x e_x) = 0
    x = -(p @ R[:, 0]) / R[0, 0]
    p[:, 0] += x
    return (p @ R)[:, 1:]


def synthetic_profile(
    joint: str,
    sensor: LaserLineSensor,
    *,
    rng: np.random.Generator | None = None,
    standoff_mm: float | None = None,
    pitch_deg: float = 0.0,
    roll_deg: float = 0.0,
    lateral_offset_mm: float = 0.0,
    rays: int | None = None,
    imperfections: Imperfections = Imperfections(),
    section: tuple[FloatArray, FloatArray, FloatArray, float] | None = None,
    **joint_params: float,
) -> tuple[Profile, GroundTruth]:
    """A stripe profile of a joint as the sensor would measure it, and its ground truth.

    Parameters
    ----------
    joint : str
        One of :data:`JOINTS`; see :func:`joint_section` for each family's seam point.
    sensor : LaserLineSensor
        Field of view, incidence limit, camera position and pixel quantization.
    rng : numpy.random.Generator, optional
        Required when ``imperfections`` draws anything at random.
    standoff_mm : float, optional
        Range z_L of the joint's reference point (top surface at the seam) before tilting;
        default the sensor's ``range_center_mm``.
    pitch_deg, roll_deg : float
        Tilt about the lateral axis (along the seam) and about the seam axis, about the
        reference point (module docstring).
    lateral_offset_mm : float
        y_L of the reference point before tilting.
    rays : int, optional
        Number of columns (rays); default ``sensor.pixels_v``.
    imperfections : Imperfections
    section : (segments, seam, edges, gap_mm), optional
        A cross-section of your own, as :func:`joint_section` returns it (e.g. a partly filled
        groove of :mod:`seamtrack.features.synthetic_groove`); then ``joint`` only labels it
        and takes no parameters.
    **joint_params : float
        The family's parameters (``gap_mm``, ``included_angle_deg``, ...; see ``_DEFAULTS``).

    Returns
    -------
    profile : Profile
        (rays, 2) points (NaN where invalid), validity, reasons, and ``T_world_sensor`` = the
        pose of the laser frame in the joint frame.
    truth : GroundTruth
    """
    if imperfections.random and rng is None:
        raise ValueError(
            "synthetic_profile: these imperfections need a seeded numpy Generator (rng)"
        )
    if section is None:
        segs, seam, edges, gap = joint_section(joint, **joint_params)
        params = MappingProxyType({**_DEFAULTS[joint], **joint_params})
    else:
        segs, seam, edges, gap = section
        params = MappingProxyType(dict(joint_params))
    standoff = sensor.range_center_mm if standoff_mm is None else float(standoff_mm)
    n = sensor.pixels_v if rays is None else int(rays)
    if n < 1:
        raise ValueError("rays must be >= 1")
    R = _rotation(math.radians(pitch_deg), math.radians(roll_deg))
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = R @ np.array([0.0, -lateral_offset_mm, -standoff])
    imp = imperfections
    segs, tack = _tack_and_bead(segs, seam, imp, rng)
    segs = segs[np.hypot(*(segs[:, 1] - segs[:, 0]).T) > 0]  # e.g. a zero root face
    phi = ray_angles(sensor, n)
    y_L, z_L, reason = _lit(sensor, R, T, segs, phi)

    reflection = False
    if imp.random:
        assert rng is not None
        y_L, z_L, reflection = _imperfect(rng, imp, sensor, phi, y_L, z_L, reason)

    valid = reason == Reason.VALID
    y_m, z_m = sensor.measure(y_L, z_L)
    points = np.where(valid[:, None], np.column_stack([y_m, z_m]), np.nan)
    profile = Profile(points, valid=valid, reason=reason, T_world_sensor=T)
    seam_laser = line_in_laser_plane(T, seam.reshape(-1, 2)).reshape(-1)
    truth = GroundTruth(
        joint=joint,
        seam_laser=seam_laser,
        seam_world=(T @ np.r_[0.0, seam_laser, 1.0])[:3] if seam.size else np.empty(0),
        edges_laser=line_in_laser_plane(T, edges),
        gap_mm=float(gap),
        T_world_sensor=T,
        params=params,
        tack=tack and bool(seam.size),
        reflection=reflection,
    )
    return profile, truth


def _tack_and_bead(
    segs: FloatArray, seam: FloatArray, imp: Imperfections, rng: np.random.Generator | None
) -> tuple[FloatArray, bool]:
    """The section's segments with a tack weld's mound on the seam point (drawn with
    ``imp.tack_probability``) and a weld bead's cap from toe to toe, as ``imp`` asks; and
    whether a tack was drawn."""
    tack = bool(
        imp.tack_probability > 0 and rng is not None and rng.random() < imp.tack_probability
    )
    if tack and seam.size:
        half = imp.tack_width_mm / 2
        segs = np.concatenate(
            [segs, _arc(seam - [half, 0.0], seam - [0.0, imp.tack_height_mm], seam + [half, 0.0])]
        )
    if imp.bead_height_mm > 0 and seam.size:
        down = np.array([[0.0, 1.0]])
        toes_y = seam[0] + np.array([-0.5, 0.5]) * imp.bead_width_mm
        starts = np.column_stack([toes_y, np.full(2, -_FAR_MM)])
        toes = np.array([s + _cast(s, down, segs)[0][0] * down[0] for s in starts])
        crown = np.array([seam[0], min(toes[0, 1], toes[1, 1], seam[1]) - imp.bead_height_mm])
        segs = np.concatenate([segs, _arc(toes[0], crown, toes[1])])
    return segs, tack


def _lit(
    sensor: LaserLineSensor, R: FloatArray, T: FloatArray, segs: FloatArray, phi: FloatArray
) -> tuple[FloatArray, FloatArray, NDArray[np.uint8]]:
    """Where the rays at angles ``phi`` from the laser at pose ``T`` (rotation ``R``; in the
    joint frame)
    meet the section's segments, in the laser frame (y, z; 0 where none), and each ray's
    :class:`Reason`: a miss, out of the field of view, too grazing an incidence, hidden
    from the camera, else valid."""
    n = len(phi)
    dirs_laser = np.column_stack([np.zeros(n), np.sin(phi), np.cos(phi)])
    dirs = dirs_laser @ R.T  # (n, 3) in the joint frame
    emitter = T[:3, 3]
    t_hit, seg_index = _cast(emitter[1:], dirs[:, 1:], segs)
    reason = np.full(n, Reason.MISS, dtype=np.uint8)
    hit = seg_index >= 0
    t_safe = np.where(hit, t_hit, 0.0)
    y_L, z_L = t_safe * np.sin(phi), t_safe * np.cos(phi)
    reason[hit] = Reason.VALID
    reason[hit & ~sensor.in_field_of_view(y_L, z_L)] = Reason.OUT_OF_RANGE

    e = segs[:, 1] - segs[:, 0]
    normals = np.column_stack([-e[:, 1], e[:, 0]]) / np.hypot(e[:, 0], e[:, 1])[:, None]
    idx = np.where(hit, seg_index, 0)
    cos_inc = np.abs(np.einsum("ij,ij->i", dirs[:, 1:], normals[idx]))
    lit = reason == Reason.VALID
    reason[lit & (cos_inc < math.cos(sensor.max_incidence_rad))] = Reason.INCIDENCE
    camera = T[:3, :3] @ sensor.camera_center_laser + T[:3, 3]
    hits_2d = emitter[1:] + t_safe[:, None] * dirs[:, 1:]
    lit = np.flatnonzero(reason == Reason.VALID)
    if lit.size:
        side_laser = np.einsum("ij,ij->i", emitter[1:] - hits_2d[lit], normals[idx[lit]])
        side_camera = np.einsum("ij,ij->i", camera[1:] - hits_2d[lit], normals[idx[lit]])
        hidden = (side_laser * side_camera <= 0) | _occluded(hits_2d[lit], camera[1:], segs)
        reason[lit[hidden]] = Reason.OCCLUDED
    return y_L, z_L, reason


def _imperfect(
    rng: np.random.Generator,
    imp: Imperfections,
    sensor: LaserLineSensor,
    phi: FloatArray,
    y_L: FloatArray,
    z_L: FloatArray,
    reason: NDArray[np.uint8],
) -> tuple[FloatArray, FloatArray, bool]:
    """Noise, outliers, a false reflection and dropouts, in place on ``reason``; new y, z."""
    n = len(phi)
    y, z = y_L.copy(), z_L.copy()
    tan_phi = np.tan(phi)
    lit = np.flatnonzero(reason == Reason.VALID)
    if imp.noise_mm > 0:
        z[lit] += rng.normal(0.0, imp.noise_mm, lit.size)
        y[lit] = z[lit] * tan_phi[lit]  # the point moves along its ray
    if imp.outlier_fraction > 0 and lit.size:
        pick = lit[rng.random(lit.size) < imp.outlier_fraction]
        z[pick] = rng.uniform(sensor.range_near_mm, sensor.range_far_mm, pick.size)
        y[pick] = z[pick] * tan_phi[pick]
    reflection = bool(
        imp.reflection_probability > 0 and lit.size and rng.random() < imp.reflection_probability
    )
    if reflection:
        length = max(3, round(imp.reflection_fraction * n))
        start = int(rng.integers(0, max(1, n - length)))
        cols = np.arange(start, min(n, start + length))
        anchor = lit[np.argmin(np.abs(lit - start))]
        # Off the true surface (not off a noisy point or an outlier that replaced it).
        y0 = y_L[anchor]
        z0 = z_L[anchor] + rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 4.0)
        slope = math.tan(rng.uniform(-math.pi / 4, math.pi / 4))
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (z0 - slope * y0) / (np.cos(phi[cols]) - slope * np.sin(phi[cols]))
        y[cols], z[cols] = t * np.sin(phi[cols]), t * np.cos(phi[cols])
        reason[cols] = Reason.VALID
    inside = sensor.in_field_of_view(y, z)
    reason[(reason == Reason.VALID) & ~inside] = Reason.OUT_OF_RANGE
    for _ in range(imp.dropout_runs):
        length = int(rng.integers(1, imp.dropout_max_columns + 1))
        start = int(rng.integers(0, max(1, n - length + 1)))
        reason[start : start + length] = Reason.DROPOUT
    return y, z, reflection
