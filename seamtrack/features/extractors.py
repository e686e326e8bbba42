"""Joint-feature extractors: find the seam point in a stripe profile.

An extractor is any object with a ``name`` and ``__call__(profile) -> Feature``
(:class:`FeatureExtractor`). It never raises on data: empty, all-invalid, NaN, constant or huge
profiles give a falsy ``Feature.failed(reason)``. :func:`extractor` builds one by name: a
built-in (:data:`BUILTIN`), a ``"package.module:Class"`` string, or an entry point in the
group ``seamtrack.extractors`` (read lazily: a broken plugin never breaks ``import seamtrack``).

The built-ins share one front end, :func:`segment_profile` (split-and-merge): drop isolated
outliers against a 5-point running median, estimate the noise from second differences, cut the
profile at jumps, split each run by Douglas-Peucker at a noise-scaled tolerance, merge neighbours
that fit one line, and refit each piece by total least squares on its inliers. The family
extractors then pick pieces by geometry (a V opening towards the sensor, two plates with a gap, a
step between parallel sheets, a ridge) and intersect their lines; a line that ends at a gap ends
half a ray spacing beyond its last point (the edge lies between two rays). The two-plate extractors
(square butt, lap; in :mod:`seamtrack.features.plates`) gather pieces on one line into a plate
however short
they are, and read what lies between two plates: a stray line cut off both (a false reflection)
hides the columns it covers, it opens no gap, and where it covers a plate's edge the edge is
estimated under it. The v-groove extractor reads what lies just beyond each bevel's lower end: a
stray line there (a false reflection over the root) hides the root corner, which is then put where
the bevel reaches the other corner's depth below the plates. The generic extractor needs no
segmentation: sliding-window slopes, the sharpest turn, two local fits.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import PluginError
from seamtrack.features.lines import (
    _WALL_DEG,
    DATA_ERRORS,
    Line,
    Segments,
    _Base,
    _confidence,
    _median,
    _ray_t,
    _towards_sensor,
    corner_or_end,
    corner_with,
)
from seamtrack.features.plates import LapExtractor, SquareButtExtractor
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
ENTRY_POINT_GROUP = "seamtrack.extractors"
#: Coordinates beyond this (mm) are not measurements: treated as invalid.
_MAX_ABS_MM = 1e6


@runtime_checkable
class FeatureExtractor(Protocol):
    """Finds the seam point in a profile. ``name`` labels results and benches."""

    @property
    def name(self) -> str: ...

    def __call__(self, profile: Profile) -> Feature: ...


# ----------------------------------------------------------------- extractors
def _covered_end(
    seg: Segments, line: Line, at_end: bool, other: Line, plate: Line | None
) -> tuple[float, float] | None:
    """Where along ``line`` (a bevel) its root end may lie when a stray line covers the
    columns beyond its last seen point (``at_end``: its last inlier, else its first), or
    None when the end is seen.

    The end is covered when the first piece beyond it lies in the next columns (at most
    two columns lost, at most two points off the line in between), is no wall (steep on
    ``plate``: a root face) and no part of ``other`` (the other bevel), and does not run
    on into ``other`` without a jump: a false reflection, in front of or behind the
    surface, which hides where the bevel really ends. Lost columns (the gap, a shadow)
    hide nothing. Returns (t0, t1), coordinates along the line, from the end outwards:
    from the last point seen to where the ray of the stray piece's last point crosses the
    line; or, when at least three points beyond the piece lie on the line again (the bevel
    shows beyond the reflection), from there to the last of them (which may already lie on
    a root face that leaves the line at a small angle). Ends are half a spacing out.
    """
    pts = seg.points
    s = 1 if at_end else -1
    i = int(line.index[-1] if at_end else line.index[0])
    beyond = [ln for ln in seg.lines if (int(ln.index[0]) > i if at_end else int(ln.index[-1]) < i)]
    if not beyond:
        return None
    piece = beyond[0] if at_end else beyond[-1]
    near = int(piece.index[0] if at_end else piece.index[-1])
    far = int(piece.index[-1] if at_end else piece.index[0])
    k = int(np.searchsorted(other.index, near))
    if k < len(other.index) and int(other.index[k]) == near:
        return None  # the other bevel (no gap) or a piece of it
    own = line.index[-11:] if at_end else line.index[:11]
    dphi = _median(np.abs(np.diff(_ray_angle(pts[own]))))
    phi_i, phi_near, phi_far = _ray_angle(pts[[i, near, far]])
    between = pts[min(i, near) + 1 : max(i, near)]
    lost = abs(float(phi_near - phi_i)) / dphi - len(between) - 1 if dphi > 0 else math.inf
    if lost > 2.5 or int((np.abs(_towards_sensor(line, between)) > 2.0 * seg.tol).sum()) > 2:
        return None  # lost columns (the gap, a shadow) or another surface first
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    if abs(float(piece.direction @ flat)) <= math.cos(math.radians(_WALL_DEG)):
        return None  # a wall: a root face
    nxt = far + s
    if 0 <= nxt < len(pts):
        held = max(6.0 * seg.spacing, 4.0 * seg.sigma, 0.1)
        on_other = abs(float((pts[nxt] - other.centroid) @ other.normal)) <= 2.0 * seg.tol
        if (
            on_other
            and abs(float(_ray_angle(pts[nxt : nxt + 1])[0] - phi_far)) <= 3.5 * dphi
            and float(np.hypot(*(pts[nxt] - pts[far]))) <= held
        ):
            return None  # runs on into the other bevel: part of the part
    half = s * 0.5 * max(line.step(at_end), seg.spacing)
    t_far = float(_ray_t(line, pts[far].reshape(1, 2))[0]) + half
    # Beyond the stray piece the bevel may show again.
    ahead = pts[far + s :: s][:400] if s > 0 or far > 0 else pts[:0]
    on = np.abs(_towards_sensor(line, ahead)) <= seg.tol
    again = int(np.argmin(on)) if not on.all() else len(on)
    if again >= 3:
        return t_far, float((ahead[again - 1] - line.centroid) @ line.direction) + half
    return float(line.t[-1] if at_end else line.t[0]) + half, t_far


def _ray_angle(q: FloatArray) -> FloatArray:
    """Angles of the emitter's rays (from the origin) through points ``q`` (rad)."""
    return np.arctan2(q[:, 0], q[:, 1])


def _group_of(piece: Line | None, groups: list[Line]) -> Line | None:
    """The group (collinear pieces joined) that holds ``piece``, else the piece itself."""
    if piece is None:
        return None
    first = int(piece.index[0])
    for g in groups:
        k = int(np.searchsorted(g.index, first))
        if k < len(g.index) and int(g.index[k]) == first:
            return g
    return piece


def _plate_depth(plate: Line, q: FloatArray) -> float:
    """Depth of ``q`` behind ``plate``'s line (away from the sensor, at the origin)."""
    n = plate.normal if float(plate.centroid @ plate.normal) > 0 else -plate.normal
    return float((q - plate.centroid) @ n)


@dataclass(frozen=True)
class VGrooveExtractor(_Base):
    """V-groove: two bevels opening towards the sensor. Seam: the root centre, midpoint of
    the bevels' lower ends (their intersection when they meet). Edges: the top edges.

    Where a stray line (a false reflection) covers a bevel's root end, the end is hidden:
    it is put at the depth of the other root end below the plates (both root corners lie
    at one depth under their plate: thickness minus root face), within the covered
    stretch (confidence halved). Confidence is halved too when a surface that is no wall
    joins the two root ends: there is no gap between them (a false V where the laser plane
    crosses a mitred corner, a tack weld over the root).
    """

    name: str = "v-groove"
    min_angle_deg: float = 20.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 6.0
    min_gap_mm: float = 0.05

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        groups = self._groups(seg)
        found = self._arms(
            seg, False, self.min_angle_deg, self.max_angle_deg, self.max_gap_mm, groups
        )
        if isinstance(found, str):
            return Feature.failed(found, joint=self.name)
        left, right, apex, _ = found
        others = [g for g in seg.lines if g.count >= self.min_points] + [left, right]
        # Column order runs left to right: the left bevel's root end is its last point.
        root_l = corner_or_end(left, True, others, seg)
        root_r = corner_or_end(right, False, others, seg)
        top_l, plate_l = corner_with(left, False, others, seg)
        top_r, plate_r = corner_with(right, True, others, seg)
        # The plates: the pieces met at the top edges, as whole lines (their groups).
        plate_l, plate_r = _group_of(plate_l, groups), _group_of(plate_r, groups)
        sure = True
        ref_l, ref_r = plate_l or plate_r, plate_r or plate_l
        cover_l = _covered_end(seg, left, True, right, ref_l)
        cover_r = _covered_end(seg, right, False, left, ref_r)
        if cover_l is not None or cover_r is not None:
            # A covered end is at least where the bevel is last seen; the shallower root end
            # goes down to the other's depth, within the stretch where it may lie.
            if cover_l is not None:
                root_l = left.point(cover_l[0])
            if cover_r is not None:
                root_r = right.point(cover_r[0])
            if ref_l is not None and ref_r is not None:
                d_l, d_r = _plate_depth(ref_l, root_l), _plate_depth(ref_r, root_r)
                if cover_l is not None and d_l < d_r:
                    root_l, sure = _at_depth(left, ref_l, d_r, cover_l), False
                elif cover_r is not None and d_r < d_l:
                    root_r, sure = _at_depth(right, ref_r, d_l, cover_r), False
            else:  # no plate to measure depth on: the middle of the stretch
                for line, cover in ((left, cover_l), (right, cover_r)):
                    if cover is not None:
                        mid = line.point(0.5 * (cover[0] + cover[1]))
                        root_l, root_r = (mid, root_r) if line is left else (root_l, mid)
                        sure = False
        gap = float(np.hypot(*(root_r - root_l)))
        if gap <= max(self.min_gap_mm, 2.0 * seg.spacing + seg.tol):
            seam, gap = apex, 0.0
        else:
            seam = 0.5 * (root_l + root_r)
            # A surface joining both root ends (no wall) means no gap lies between them: a
            # false V where the laser plane crosses a mitred corner, a tack over the root.
            if _bridged(seg, left, right, root_l, root_r, ref_l, self.min_points):
                sure = False
        conf = _confidence([left, right], seg) * (1.0 if sure else 0.5)
        return self._found(
            profile, seam, confidence=conf, edges_laser=np.array([top_l, top_r]), gap_mm=gap
        )


def _bridged(
    seg: Segments,
    left: Line,
    right: Line,
    root_l: FloatArray,
    root_r: FloatArray,
    plate: Line | None,
    min_points: int,
) -> bool:
    """Whether a piece between the bevels that is no wall (steep on ``plate``) runs from one
    root end to the other: the "gap" between them is a surface."""
    lo, hi = int(left.index[-1]), int(right.index[0])
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    for ln in seg.lines:
        if ln.count < min_points or int(ln.index[0]) <= lo or int(ln.index[-1]) >= hi:
            continue
        if abs(float(ln.direction @ flat)) <= math.cos(math.radians(_WALL_DEG)):
            continue
        reach = 3.0 * max(seg.spacing, ln.step(True), ln.step(False)) + seg.tol
        if (
            float(np.hypot(*(ln.end(False) - root_l))) <= reach
            and float(np.hypot(*(ln.end(True) - root_r))) <= reach
        ):
            return True
    return False


def _at_depth(line: Line, plate: Line, depth: float, stretch: tuple[float, float]) -> FloatArray:
    """The point of ``line`` at ``depth`` behind ``plate``, kept within ``stretch`` (two
    coordinates along the line)."""
    n = plate.normal if float(plate.centroid @ plate.normal) > 0 else -plate.normal
    rate = float(line.direction @ n)
    lo, hi = min(stretch), max(stretch)
    if abs(rate) < 1e-6:
        return line.point(stretch[0])
    t = float((depth - _plate_depth(plate, line.centroid)) / rate)
    return line.point(float(np.clip(t, lo, hi)))


@dataclass(frozen=True)
class FilletExtractor(_Base):
    """Fillet / T joint: two faces meeting in a corner that opens towards the sensor.
    Seam: the faces' intersection (the corner line)."""

    name: str = "fillet"
    min_angle_deg: float = 45.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 2.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        found = self._arms(seg, False, self.min_angle_deg, self.max_angle_deg, self.max_gap_mm)
        if isinstance(found, str):
            return Feature.failed(found, joint=self.name)
        left, right, apex, _ = found
        return self._found(profile, apex, confidence=_confidence([left, right], seg))


@dataclass(frozen=True)
class OutsideCornerExtractor(_Base):
    """Outside corner: two faces falling away from a ridge. Seam: their intersection."""

    name: str = "outside-corner"
    min_angle_deg: float = 45.0
    max_angle_deg: float = 160.0
    max_gap_mm: float = 2.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        found = self._arms(seg, True, self.min_angle_deg, self.max_angle_deg, self.max_gap_mm)
        if isinstance(found, str):
            return Feature.failed(found, joint=self.name)
        left, right, apex, _ = found
        return self._found(profile, apex, confidence=_confidence([left, right], seg))


@dataclass(frozen=True)
class GenericExtractor:
    """Slope / curvature: the sharpest concave turn of the profile (sliding-window slopes),
    refined by intersecting two local line fits; else the widest interior gap or step; else
    the sharpest convex turn. No segmentation, no joint model: the fastest built-in."""

    name: str = "generic"
    window_mm: float = 1.0
    min_turn_deg: float = 25.0
    min_jump_mm: float = 0.3
    min_points: int = 8

    def __call__(self, profile: Profile) -> Feature:
        try:
            with np.errstate(all="ignore"):
                return self._extract(profile)
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"generic: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile) -> Feature:
        from seamtrack.features.generic import front_end, window_turns

        points = np.ascontiguousarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
        valid = np.asarray(profile.valid, dtype=bool).reshape(-1)
        if valid.shape != (len(points),):
            return Feature.failed("valid does not match the points", joint=self.name)
        code, p, spacing, sigma = front_end(points, valid, _MAX_ABS_MM, 4 * self.min_points)
        if code == 1:
            return Feature.failed(f"too few valid points ({len(p)})", joint=self.name)
        if code == 2:
            return Feature.failed("the valid points do not spread out", joint=self.name)
        m = len(p)
        k = min(max(round(max(self.window_mm, 20 * sigma) / spacing), 4), max(4, m // 4))
        if m < 2 * k + 2:
            return Feature.failed("too few points for the slope window", joint=self.name)
        jump_mm = max(6 * spacing, 8 * sigma, 0.1)
        # Total-least-squares direction of each k-point window (from window sums), and the
        # turn between windows k apart where no jump lies between them.
        gaps, turn = window_turns(p, k, jump_mm)
        min_turn = math.radians(self.min_turn_deg)
        i = int(np.argmin(turn))
        if turn[i] <= -min_turn:
            return self._corner(profile, p, i + k, k, -float(turn[i]))
        interior = np.flatnonzero(gaps > max(self.min_jump_mm, jump_mm))
        if interior.size:
            j = int(interior[np.argmax(gaps[interior])])
            a, b = p[j], p[j + 1]
            dy, dz = abs(b[0] - a[0]), abs(b[1] - a[1])
            if dz > 2 * dy:  # a step: the corner at the foot of the higher side
                hi, lo = (a, b) if a[1] < b[1] else (b, a)
                seam = np.array([hi[0], lo[1]])
            else:
                seam = 0.5 * (a + b)
            return Feature.found(
                seam,
                profile.T_world_sensor,
                joint=self.name,
                confidence=0.5,
                edges_laser=np.array([a, b]),
                gap_mm=float(dy),
            )
        i = int(np.argmax(turn))
        if turn[i] >= min_turn:
            return self._corner(profile, p, i + k, k, float(turn[i]))
        return Feature.failed("no turn, gap or step in the profile", joint=self.name)

    def _corner(self, profile: Profile, p: FloatArray, c: int, k: int, turn: float) -> Feature:
        from seamtrack.features.generic import corner_point

        code, y, z = corner_point(p, c, k)
        if code:
            return Feature.failed("the corner is too near the profile's end", joint=self.name)
        conf = float(np.clip(turn / math.radians(90), 0.0, 1.0))
        return Feature.found(
            np.array([y, z]), profile.T_world_sensor, joint=self.name, confidence=conf
        )


# ----------------------------------------------------------------- registry
BUILTIN: dict[str, Callable[..., FeatureExtractor]] = {
    "v-groove": VGrooveExtractor,
    "square-butt": SquareButtExtractor,
    "fillet": FilletExtractor,
    "lap": LapExtractor,
    "outside-corner": OutsideCornerExtractor,
    "generic": GenericExtractor,
}


def available_extractors() -> list[str]:
    """Built-in names and the names of installed entry points (plugins are not imported)."""
    try:
        plugins = [ep.name for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)]
    except Exception:  # a broken distribution's metadata must not break listing
        plugins = []
    return sorted(BUILTIN) + sorted(set(plugins) - set(BUILTIN))


def _load(name: str) -> Any:
    fix_names = f"use one of {', '.join(available_extractors())} or 'package.module:Class'"
    if ":" in name:
        module_name, _, attr = name.partition(":")
        try:
            obj: Any = importlib.import_module(module_name)
            for part in attr.split("."):
                obj = getattr(obj, part)
        except Exception as exc:  # any import-time error of user code
            raise PluginError(
                f"cannot load extractor {name!r}: {exc}",
                field="extractor.name",
                fix="check that the module imports and defines the class ('package.module:Class')",
            ) from exc
        return obj
    try:
        eps = [
            ep for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP) if ep.name == name
        ]
    except Exception:
        eps = []
    if not eps:
        raise PluginError(f"unknown extractor {name!r}", field="extractor.name", fix=fix_names)
    try:
        return eps[0].load()
    except Exception as exc:
        raise PluginError(
            f"the plugin extractor {name!r} fails to load: {exc}",
            field="extractor.name",
            fix="reinstall or fix the plugin package",
        ) from exc


def extractor_target(name: str) -> Any:
    """What an extractor name stands for (a class to build with parameters, or a ready
    extractor object), without building it; raises :class:`PluginError` like :func:`extractor`."""
    return BUILTIN[name] if name in BUILTIN else _load(name)


def extractor(name: str, **params: Any) -> FeatureExtractor:
    """An extractor by name, built with ``params``.

    Parameters
    ----------
    name : str
        A built-in (``"v-groove"``, ``"square-butt"``, ``"fillet"``, ``"lap"``,
        ``"outside-corner"``, ``"generic"``), ``"package.module:Class"``, or the name of an
        entry point in the group ``seamtrack.extractors``. A class is called with
        ``params``; an object that already is an extractor is used as is.

    Raises
    ------
    PluginError
        Unknown name, a plugin that fails to import or to build, or an object without
        ``name`` and ``__call__`` (field ``extractor.name``; ``extractor.params`` for bad
        parameters).
    """
    if not isinstance(name, str) or not name:
        raise PluginError(
            f"extractor name must be a non-empty string, got {name!r}",
            field="extractor.name",
            fix="e.g. 'v-groove'",
        )
    target: Any = BUILTIN[name] if name in BUILTIN else _load(name)
    if isinstance(target, type):
        try:
            target = target(**params)
        except TypeError as exc:
            raise PluginError(
                f"cannot build extractor {name!r}: {exc}",
                field="extractor.params",
                fix="pass only the parameters the extractor accepts",
            ) from exc
    elif params:
        raise PluginError(
            f"{name!r} is an instance, it takes no parameters",
            field="extractor.params",
            fix="drop the parameters",
        )
    if not (callable(target) and isinstance(getattr(target, "name", None), str)):
        raise PluginError(
            f"{name!r} is not a feature extractor",
            field="extractor.name",
            fix="give the class a 'name' string and a __call__(profile) -> Feature",
        )
    return target
