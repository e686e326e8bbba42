"""Weld beads in a cross-section: shape, area from mass conservation, laying one on a surface.

Pure 2-D geometry in a station's (y, z) frame (y lateral, z towards the torch), numpy only.

The model
---------
**Area.** The wire melted per second, less the spatter, is the bead's cross-section times the
travel speed (mass conservation)::

    A = eta_d * pi * d**2 / 4 * v_wire / v_travel

so a torch that slows down lays a fatter bead (:func:`bead_area_mm2`).

**Shape on a flat plate** (Ding et al. 2015, Robotics and Computer-Integrated Manufacturing
31:101-110), width ``w``, height ``h``, ``u = 2 y / w``:

- ``parabola``: ``z = h (1 - u**2)``, ``A = 2/3 w h``;
- ``cosine``: ``z = h cos(pi u / 2)``, ``A = 2/pi w h``;
- ``arc``: a circular segment of radius ``R`` and half-angle ``alpha`` (the wetting angle at
  the toe), ``w = 2 R sin(alpha)``, ``h = R (1 - cos(alpha))``,
  ``A = R**2 (2 alpha - sin(2 alpha)) / 2``; ``w / h = 2 / tan(alpha / 2)``.

Given the area and the width-to-height ratio ``r``, ``h = sqrt(A / (c r))`` and ``w = r h``
(``c`` the shape's area factor, :meth:`BeadShape.flat_size`).

**On a surface that is not flat** (a groove, earlier beads) the bead conforms to it: its cap keeps
the flat-plate shape (same curvature, so the same ``w`` and ``h`` on a plate) and is lowered onto
the surface until the area between the cap and the old surface, over the stretch around the
bead's centre where the cap lies above the old surface, equals ``A``. Beyond its flat-plate toes
the cap continues with its toe slope (the parabola with itself), so it always meets the surface:
a cap that reaches a groove wall fills up to it (it wets the wall); a bead placed away from a wall
meets the floor first and leaves the notch between them. The old surface under the bead stays as
it was. The cap's height is solved by bisection on the exact area of the polylines (the area of a
piecewise-linear cap over a piecewise-linear surface), to 1e-9 relative.

One case has no continuous answer: when the rising cap overflows a ridge of the old surface into
a deeper pocket beyond it, the area jumps. Then the bead keeps to the stretch it had just before
the jump and rises within it (the ridge acts as a dam): area is still exact, and the surface may
have a step at the ridge. Real beads rarely do this; plans that do are poor plans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import SceneError

__all__ = [
    "BEAD_KINDS",
    "BeadShape",
    "GridBeads",
    "bead_area_mm2",
    "bead_polygon",
    "check_bead_fits",
    "groove_capacity_mm2",
    "lay_bead",
    "lay_beads_on_grid",
    "polygon_area_mm2",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

BEAD_KINDS = ("arc", "parabola", "cosine")
#: Relative tolerance of the cap-height solve (area between new and old surface vs target).
AREA_RTOL = 1e-9
#: A vertical segment of a surface polyline is tilted by this much (mm) so y is a function.
VERTICAL_NUDGE_MM = 1e-7
#: Samples of the cap across its flat-plate width in :func:`lay_bead`.
CAP_SAMPLES = 400


def _positive(value: float, field: str, what: str = "") -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise SceneError(
            f"must be a finite number > 0, got {value!r}",
            field=field,
            fix=what or "give a value > 0",
        )
    return v


@dataclass(frozen=True)
class BeadShape:
    """The bead's cross-section model (see the module docstring).

    Attributes
    ----------
    kind : str
        ``"arc"`` (circular segment), ``"parabola"`` or ``"cosine"`` (Ding et al. 2015).
    width_to_height : float
        ``w / h`` on a flat plate (> 0). For ``arc`` ignored when ``wetting_angle_rad`` is set.
    wetting_angle_rad : float or None
        ``arc`` only: the contact angle at the toe on a flat plate, in (0, pi/2]; sets ``w / h``.
    """

    kind: str = "parabola"
    width_to_height: float = 3.0
    wetting_angle_rad: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in BEAD_KINDS:
            raise SceneError(
                f"unknown bead shape {self.kind!r}",
                field="process.bead_shape",
                fix=f"use one of {', '.join(BEAD_KINDS)}",
            )
        _positive(self.width_to_height, "process.width_to_height", "give w/h > 0, e.g. 3")
        if self.wetting_angle_rad is not None:
            if self.kind != "arc":
                raise SceneError(
                    "a wetting angle sets only an arc bead's shape",
                    field="process.wetting_angle_deg",
                    fix="drop it, or set process.bead_shape = 'arc'",
                )
            a = float(self.wetting_angle_rad)
            if not (math.isfinite(a) and 0 < a <= math.pi / 2):
                raise SceneError(
                    f"must be in (0, 90] deg, got {math.degrees(a):.6g} deg",
                    field="process.wetting_angle_deg",
                    fix="give a contact angle between 0 and 90 deg, e.g. 60",
                )

    @property
    def ratio(self) -> float:
        """``w / h`` on a flat plate."""
        if self.kind == "arc" and self.wetting_angle_rad is not None:
            return 2.0 / math.tan(self.wetting_angle_rad / 2.0)
        return float(self.width_to_height)

    @property
    def toe_angle_rad(self) -> float:
        """The arc's half-angle ``alpha`` (its wetting angle on a flat plate)."""
        return 2.0 * math.atan(2.0 / self.ratio)

    @property
    def area_factor(self) -> float:
        """``c`` in ``A = c w h`` on a flat plate."""
        if self.kind == "parabola":
            return 2.0 / 3.0
        if self.kind == "cosine":
            return 2.0 / math.pi
        alpha = self.toe_angle_rad
        # R = w / (2 sin a), h = R (1 - cos a), A = R^2 (2a - sin 2a) / 2
        return (2 * alpha - math.sin(2 * alpha)) / (4 * math.sin(alpha) * (1 - math.cos(alpha)))

    def flat_size(self, area_mm2: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Width and height (mm) of a bead of ``area_mm2`` on a flat plate: ``(w, h)``."""
        a = np.asarray(area_mm2, dtype=np.float64)
        h = np.sqrt(a / (self.area_factor * self.ratio))
        return self.ratio * h, h

    def cap(self, dy_mm: ArrayLike, width_mm: ArrayLike, height_mm: ArrayLike) -> FloatArray:
        """The cap relative to its apex (<= 0) at lateral offsets ``dy_mm`` from the centre.

        ``width_mm``/``height_mm`` broadcast against ``dy_mm``; beyond the flat-plate toes
        (``|dy| > w/2``) the cap continues with its toe slope (the parabola with itself).
        """
        dy = np.abs(np.asarray(dy_mm, dtype=np.float64))
        w = np.asarray(width_mm, dtype=np.float64)
        h = np.asarray(height_mm, dtype=np.float64)
        half = w / 2.0
        u = dy / half
        if self.kind == "parabola":
            return -h * u**2
        if self.kind == "cosine":
            inside = h * (np.cos(0.5 * np.pi * np.minimum(u, 1.0)) - 1.0)
            slope = h * np.pi / w  # |dz/dy| at the toe
            return np.where(u <= 1.0, inside, -h - slope * (dy - half))
        alpha = self.toe_angle_rad
        radius = half / math.sin(alpha)
        inside = np.sqrt(np.maximum(radius**2 - np.minimum(dy, half) ** 2, 0.0)) - radius
        return np.where(u <= 1.0, inside, -h - math.tan(alpha) * (dy - half))


def bead_area_mm2(
    wire_diameter_mm: ArrayLike,
    wire_feed_mm_s: ArrayLike,
    travel_speed_mm_s: ArrayLike,
    deposition_efficiency: ArrayLike,
) -> float | FloatArray:
    """Bead cross-section from mass conservation: ``eta * pi * d**2 / 4 * v_wire / v_travel``.

    Parameters
    ----------
    wire_diameter_mm, wire_feed_mm_s, travel_speed_mm_s : float or (n,) float
        Wire diameter (mm), wire feed speed (mm/s) and the torch's travel speed (mm/s), > 0.
    deposition_efficiency : float or (n,) float
        The fraction of the wire that ends in the bead (spatter lost), in (0, 1].

    Returns
    -------
    float or (n,) float
        Area (mm^2); an array when any input is one.
    """
    names = ("process.wire_diameter_mm", "process.wire_feed_m_min", "travel_speed_mm_s")
    arrays = []
    values = (wire_diameter_mm, wire_feed_mm_s, travel_speed_mm_s)
    for value, name in zip(values, names, strict=True):
        arr = np.asarray(value, dtype=np.float64)
        if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise SceneError(
                f"must be finite and > 0, got {_show(arr)}", field=name, fix="give a value > 0"
            )
        arrays.append(arr)
    eta = np.asarray(deposition_efficiency, dtype=np.float64)
    if not np.all(np.isfinite(eta)) or np.any(eta <= 0) or np.any(eta > 1):
        raise SceneError(
            f"must be in (0, 1], got {_show(eta)}",
            field="process.deposition_efficiency",
            fix="give the fraction of wire deposited, about 0.97 for GMAW",
        )
    d, v_wire, v_travel = arrays
    area = eta * np.pi * d**2 / 4.0 * v_wire / v_travel
    return float(area) if area.ndim == 0 else area


def _show(arr: FloatArray) -> str:
    bad = arr[~np.isfinite(arr) | (arr <= 0)] if arr.ndim else arr.reshape(1)
    return repr(float(bad.reshape(-1)[0])) if bad.size else repr(float(arr.reshape(-1)[0]))


def polygon_area_mm2(polygon_yz: ArrayLike) -> float:
    """Unsigned shoelace area of a closed polygon ``(p, 2)`` (mm^2)."""
    p = np.asarray(polygon_yz, dtype=np.float64)
    if len(p) < 3:
        return 0.0
    y, z = p[:, 0], p[:, 1]
    return float(abs(np.dot(y, np.roll(z, -1)) - np.dot(z, np.roll(y, -1))) / 2.0)


class GridBeads(NamedTuple):
    """Beads laid on surfaces sampled on a shared lateral grid (:func:`lay_beads_on_grid`).

    ``z_new`` (m, K) the new surfaces; ``lo``/``hi`` (m,) the first and last grid index the bead
    covers (``lo > hi``: no bead); ``toes`` (m, 2, 2) the left and right toes (y, z) where the
    cap meets the old surface (the exact crossing); ``area_mm2`` (m,) the area laid;
    ``dammed`` (m,) True where the bead was held at a ridge (see the module docstring).
    """

    z_new: FloatArray
    lo: IntArray
    hi: IntArray
    toes: FloatArray
    area_mm2: FloatArray
    dammed: NDArray[np.bool_]


def _level_area(
    r: FloatArray, dy: FloatArray, jc: IntArray, exact_toes: bool, fixed: tuple[IntArray, IntArray]
) -> tuple[FloatArray, IntArray, IntArray, FloatArray]:
    """Area of ``(r)+`` over the run of ``r > 0`` around column ``jc`` of each row.

    ``r`` (m, K) the cap minus the old surface; ``dy`` (K-1,) cell widths. ``fixed`` bounds
    (lo, hi) per row where >= 0 replace the run (the dam). With ``exact_toes`` the boundary
    cells count the exact triangle up to the crossing, else the trapezoid of the nodal values.
    """
    m, k = r.shape
    idx = np.arange(k)
    pos = r > 0
    rows = np.arange(m)
    not_pos = ~pos
    lo = np.where(not_pos & (idx < jc[:, None]), idx, -1).max(axis=1) + 1
    hi = np.where(not_pos & (idx > jc[:, None]), idx, k).min(axis=1) - 1
    use_fixed = fixed[0] >= 0
    lo = np.where(use_fixed, fixed[0], lo)
    hi = np.where(use_fixed, fixed[1], hi)
    centre_wet = pos[rows, jc] | use_fixed
    inside = (idx >= lo[:, None]) & (idx <= hi[:, None]) & centre_wet[:, None] & pos
    q = np.where(inside, r, 0.0)
    area = ((q[:, :-1] + q[:, 1:]) * 0.5 * dy).sum(axis=1)
    wet = inside.astype(np.float64)
    slope = ((wet[:, :-1] + wet[:, 1:]) * 0.5 * dy).sum(axis=1)  # d area / d level
    if exact_toes:
        # A boundary cell holds a triangle up to the crossing, not the trapezoid to the node.
        for a, b in ((q[:, :-1], r[:, 1:]), (q[:, 1:], r[:, :-1])):
            edge = (a > 0) & (b <= 0)
            frac = np.where(edge, a / np.where(edge, a - b, 1.0), 0.0)
            area -= np.where(edge, 0.5 * a * dy * (1.0 - frac), 0.0).sum(axis=1)
    lo = np.where(centre_wet, lo, k)
    hi = np.where(centre_wet, hi, -1)
    return area, lo, hi, slope


def _solve_level(
    terrain: FloatArray,
    dy: FloatArray,
    jc: IntArray,
    target: FloatArray,
    level_lo: FloatArray,
    level_hi: FloatArray,
    exact_toes: bool,
    fixed: tuple[IntArray, IntArray],
    rows: NDArray[np.bool_],
) -> tuple[FloatArray, FloatArray]:
    """Safeguarded Newton on the apex level of each row in ``rows``: the bracket (lo, hi).

    The area rises monotonically with the level; Newton steps from the upper end of the bracket
    (the area is convex there between jumps) and falls back to bisection outside the bracket.
    """
    lo, hi = level_lo.copy(), level_hi.copy()
    level = hi.copy()
    tol = AREA_RTOL * np.maximum(target, 1e-12)
    for _ in range(100):
        area, _, _, slope = _level_area(level[:, None] - terrain, dy, jc, exact_toes, fixed)
        err = area - target
        done = ~rows | (np.abs(err) <= tol) | (hi - lo <= 1e-12 * (1 + np.abs(hi)))
        if np.all(done):
            break
        below = err < 0
        lo = np.where(rows & below, level, lo)
        hi = np.where(rows & ~below, level, hi)
        step = level - err / np.where(slope > 0, slope, np.inf)
        bisect = (step <= lo) | (step >= hi) | ~np.isfinite(step) | (slope <= 0)
        nxt = np.where(bisect, 0.5 * (lo + hi), step)
        level = np.where(done, level, nxt)
    # The final level lies on the side that holds at least the target where a jump sits.
    area, _, _, _ = _level_area(level[:, None] - terrain, dy, jc, exact_toes, fixed)
    level = np.where(rows & (area < target - tol), hi, level)
    return level, lo


def _solve_window(
    terrain: FloatArray,
    y: FloatArray,
    jc: IntArray,
    target: FloatArray,
    level_lo: FloatArray,
    level_hi: FloatArray,
    exact_toes: bool,
    active: NDArray[np.bool_],
) -> tuple[FloatArray, IntArray, IntArray, FloatArray, NDArray[np.bool_]]:
    """The apex level of each row's bead on a window of columns: (level, lo, hi, area, dammed)."""
    m, k = terrain.shape
    dy = np.diff(y)
    none = np.full(m, -1, dtype=np.intp)
    tol = AREA_RTOL * np.maximum(target, 1e-12)
    level, below = _solve_level(
        terrain, dy, jc, target, level_lo, level_hi, exact_toes, (none, none), active
    )
    area, lo, hi, _ = _level_area(level[:, None] - terrain, dy, jc, exact_toes, (none, none))
    dammed = active & (np.abs(area - target) > tol)
    if np.any(dammed):
        # The area jumped where the cap overflowed a ridge: keep the run just below the jump.
        _, lo_d, hi_d, _ = _level_area(below[:, None] - terrain, dy, jc, exact_toes, (none, none))
        fixed = (np.where(dammed, lo_d, -1), np.where(dammed, hi_d, -1))
        width = np.maximum(y[np.clip(hi_d, 0, k - 1)] - y[np.clip(lo_d, 0, k - 1)], 1e-3)
        top = np.maximum(level, below + target / width)
        level_d, _ = _solve_level(
            terrain, dy, jc, target, below, top + 1e-6, exact_toes, fixed, dammed
        )
        level = np.where(dammed, level_d, level)
        area, lo, hi, _ = _level_area(level[:, None] - terrain, dy, jc, exact_toes, fixed)
    return level, lo, hi, area, dammed


def lay_beads_on_grid(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    y_centre_mm: ArrayLike,
    area_mm2: ArrayLike,
    shape: BeadShape,
    *,
    exact_toes: bool = False,
) -> GridBeads:
    """Lay one bead on each of ``m`` surfaces sampled on the same lateral grid (vectorised).

    Parameters
    ----------
    y_mm : (K,) float
        Strictly increasing lateral grid (mm).
    z_mm : (m, K) float
        The old surfaces' heights on the grid.
    y_centre_mm, area_mm2 : (m,) float
        Each bead's centre (inside the grid) and area (>= 0; 0 lays nothing).
    shape : BeadShape
    exact_toes : bool
        False: the area is the trapezoid area of the nodal surfaces (what a grid keeps exactly);
        True: of the piecewise-linear surfaces with the toe crossings inserted (:func:`lay_bead`).
    """
    y = np.asarray(y_mm, dtype=np.float64)
    z = np.atleast_2d(np.asarray(z_mm, dtype=np.float64))
    yc = np.broadcast_to(np.asarray(y_centre_mm, dtype=np.float64), (len(z),))
    target = np.broadcast_to(np.asarray(area_mm2, dtype=np.float64), (len(z),))
    m, k = z.shape
    dy = np.diff(y)
    active = target > 0
    w, h = shape.flat_size(np.where(active, target, 1.0))
    cap0 = shape.cap(y[None, :] - yc[:, None], w[:, None], h[:, None])
    terrain = z - cap0  # the cap's apex level at which the cap touches the surface at each node
    jc = np.clip(np.searchsorted(y, yc), 0, k - 1)
    prev = np.clip(jc - 1, 0, k - 1)
    jc = np.where(np.abs(y[prev] - yc) < np.abs(y[jc] - yc), prev, jc)
    rows = np.arange(m)
    none = np.full(m, -1, dtype=np.intp)
    level_lo = terrain[rows, jc].copy()
    level_hi = terrain.max(axis=1) + target / (y[-1] - y[0]) + 1e-6
    # A first guess of the upper bracket (apex 4 flat heights above the surface at the centre)
    # bounds the columns the bead can reach: the solve runs on those only.
    guess = level_lo + 4.0 * h
    a_guess, lo_g, hi_g, _ = _level_area(guess[:, None] - terrain, dy, jc, exact_toes, (none, none))
    enough = active & (a_guess >= target)
    level_hi = np.where(enough, guess, level_hi)
    first, last = 0, k - 1
    if np.any(active) and np.all(enough | ~active):
        first = max(int(lo_g[enough].min()) - 1, 0)
        last = min(int(hi_g[enough].max()) + 1, k - 1)
    win = slice(first, last + 1)
    level, lo, hi, area, dammed = _solve_window(
        terrain[:, win],
        y[win],
        np.clip(jc - first, 0, last - first),
        target,
        level_lo,
        level_hi,
        exact_toes,
        active,
    )
    lo, hi = lo + first, hi + first
    lo = np.where(active, lo, k)
    hi = np.where(active, hi, -1)
    r = level[:, None] - terrain
    idx = np.arange(k)
    inside = (idx >= lo[:, None]) & (idx <= hi[:, None]) & (r > 0)
    z_new = np.where(inside, z + r, z)
    toes = np.full((m, 2, 2), np.nan)
    for side, node, out in ((0, lo, lo - 1), (1, hi, hi + 1)):
        ok = active & (lo <= hi)
        node_c = np.clip(node, 0, k - 1)
        out_c = np.clip(out, 0, k - 1)
        has_out = ok & (out >= 0) & (out < k)
        r_in, r_out = r[rows, node_c], r[rows, out_c]
        gap = np.where(has_out & (r_in - r_out > 0), r_in - r_out, 1.0)
        frac = np.where(has_out & (r_in - r_out > 0), np.clip(r_in / gap, 0.0, 1.0), 0.0)
        ty = y[node_c] + frac * (y[out_c] - y[node_c])
        tz = z[rows, node_c] + frac * (z[rows, out_c] - z[rows, node_c])
        toes[:, side, 0] = np.where(ok, ty, np.nan)
        toes[:, side, 1] = np.where(ok, tz, np.nan)
    return GridBeads(z_new, lo, hi, toes, np.where(active, area, 0.0), dammed)


def _as_surface(surface_yz: ArrayLike, field: str) -> FloatArray:
    s = np.array(surface_yz, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] != 2 or len(s) < 2:
        raise SceneError(f"must be a (k, 2) polyline, got shape {s.shape}", field=field)
    if not np.all(np.isfinite(s)):
        raise SceneError("holds a NaN or infinite point", field=field, fix="give finite points")
    dy = np.diff(s[:, 0])
    if np.any(dy < 0):
        raise SceneError("is not ordered by y", field=field, fix="sort the points by y")
    # Tilt vertical segments a hair so the surface is a function of y.
    if np.any(dy == 0):
        y = s[:, 0].copy()
        for i in np.flatnonzero(np.diff(y) <= 0):
            y[i + 1] = max(y[i + 1], y[i] + VERTICAL_NUDGE_MM)
        s[:, 0] = y
    return s


def lay_bead(
    surface_yz: ArrayLike, y_centre_mm: float, area_mm2: float, shape: BeadShape
) -> FloatArray:
    """Lay one bead of ``area_mm2`` centred at ``y_centre_mm`` on a surface; the new surface.

    Parameters
    ----------
    surface_yz : (k, 2) float
        The old top surface (y, z), ordered by y (vertical segments allowed).
    y_centre_mm : float
        The bead's centre (where the torch points), inside the surface's y range.
    area_mm2 : float
        The bead's cross-section (mass conservation, :func:`bead_area_mm2`), > 0.
    shape : BeadShape

    Returns
    -------
    (k', 2) float
        The new top surface: the old one where the bead is not, the cap where it is, with the
        toes (where the cap meets the old surface) as vertices. The area between it and the old
        surface equals ``area_mm2`` to 1e-9 relative (:func:`bead_polygon`).
    """
    s = _as_surface(surface_yz, "surface_yz")
    area = _positive(area_mm2, "area_mm2", "give the bead's cross-section in mm^2")
    yc = float(y_centre_mm)
    if not (math.isfinite(yc) and s[0, 0] <= yc <= s[-1, 0]):
        raise SceneError(
            f"{y_centre_mm!r} mm is outside the surface ({s[0, 0]:.3f} .. {s[-1, 0]:.3f} mm)",
            field="y_centre_mm",
            fix="place the bead inside the groove",
        )
    w, _ = shape.flat_size(area)
    step = float(w) / CAP_SAMPLES
    fine = np.arange(s[0, 0], s[-1, 0], step)
    grid = np.unique(np.concatenate([s[:, 0], fine, [yc]]))
    # Drop fine nodes that crowd an original vertex (keeps cells well above round-off).
    keep = np.ones(len(grid), bool)
    near = np.minimum(
        np.abs(grid - s[np.clip(np.searchsorted(s[:, 0], grid), 0, len(s) - 1), 0]),
        np.abs(grid - s[np.clip(np.searchsorted(s[:, 0], grid) - 1, 0, len(s) - 1), 0]),
    )
    keep &= (near == 0) | (near > step * 1e-3)
    grid = grid[keep]
    z = np.interp(grid, s[:, 0], s[:, 1])
    laid = lay_beads_on_grid(grid, z[None, :], [yc], [area], shape, exact_toes=True)
    lo, hi = int(laid.lo[0]), int(laid.hi[0])
    left = s[s[:, 0] < laid.toes[0, 0, 0]]
    right = s[s[:, 0] > laid.toes[0, 1, 0]]
    cap = np.column_stack([grid[lo : hi + 1], laid.z_new[0, lo : hi + 1]])
    pieces = [left]
    if lo > 0:
        pieces.append(laid.toes[0, 0][None, :])
    pieces.append(cap)
    if hi < len(grid) - 1:
        pieces.append(laid.toes[0, 1][None, :])
    pieces.append(right)
    return np.concatenate(pieces)


def bead_polygon(old_yz: ArrayLike, new_yz: ArrayLike) -> FloatArray:
    """The deposited region between an old and a new surface, as a closed polygon ``(p, 2)``.

    The polygon runs along the new surface from the first to the last point where it rises above
    the old one, then back along the old surface; its shoelace area
    (:func:`polygon_area_mm2`) is the area laid. Empty ``(0, 2)`` when nothing was laid.
    """
    old = _as_surface(old_yz, "old_yz")
    new = _as_surface(new_yz, "new_yz")
    grid = np.unique(np.concatenate([old[:, 0], new[:, 0]]))
    z_old = np.interp(grid, old[:, 0], old[:, 1])
    z_new = np.interp(grid, new[:, 0], new[:, 1])
    up = np.flatnonzero(z_new - z_old > 1e-12 * (1 + np.abs(z_old)))
    if len(up) == 0:
        return np.zeros((0, 2))
    a, b = max(up[0] - 1, 0), min(up[-1] + 1, len(grid) - 1)
    top = np.column_stack([grid[a : b + 1], z_new[a : b + 1]])
    bottom = np.column_stack([grid[a : b + 1], z_old[a : b + 1]])[::-1]
    return np.concatenate([top, bottom])


def groove_capacity_mm2(
    surface_yz: ArrayLike, left_top_yz: ArrayLike, right_top_yz: ArrayLike
) -> float:
    """Area (mm^2) between a surface and the straight line joining the groove's top corners.

    The metal the groove can still take before the surface reaches its top (the fill's
    remaining area); parts of the surface above the line count as zero.
    """
    s = _as_surface(surface_yz, "surface_yz")
    (y0, z0), (y1, z1) = np.asarray(left_top_yz, float), np.asarray(right_top_yz, float)
    grid = np.unique(np.concatenate([s[:, 0], [y0, y1]]))
    grid = grid[(grid >= y0) & (grid <= y1)]
    if len(grid) < 2:
        return 0.0
    line = z0 + (grid - y0) * (z1 - z0) / max(y1 - y0, 1e-12)
    depth = line - np.interp(grid, s[:, 0], s[:, 1])
    # Exact integral of the positive part of a piecewise-linear function.
    a, b, dy = depth[:-1], depth[1:], np.diff(grid)
    both = (a >= 0) & (b >= 0)
    one = (a > 0) != (b > 0)
    pos = np.maximum(a, b)
    frac = np.where(one, pos / np.where(one, np.abs(a - b), 1.0), 0.0)
    partial = np.where(one, 0.5 * pos * frac * dy, 0.0)
    return float(np.sum(np.where(both, 0.5 * (a + b) * dy, partial)))


def check_bead_fits(area_mm2: float, capacity_mm2: float, *, field: str = "process") -> None:
    """Raise :class:`~seamtrack.errors.SceneError` when a bead is larger than the groove takes.

    ``capacity_mm2`` is the groove's remaining area (:func:`groove_capacity_mm2`); a bead larger
    than that overflows the plates' top, which no plan should ask for.
    """
    if not area_mm2 <= capacity_mm2:
        raise SceneError(
            f"a bead of {area_mm2:.2f} mm^2 is larger than the groove can take "
            f"({capacity_mm2:.2f} mm^2 left)",
            field=field,
            fix="lower the wire feed or raise the travel speed, or plan fewer passes",
        )
