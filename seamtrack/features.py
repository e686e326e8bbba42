"""Joint-feature extractors: find the seam point in a stripe profile.

An extractor is any object with a ``name`` and ``__call__(profile) -> Feature``
(:class:`FeatureExtractor`). It never raises on data: empty, all-invalid, NaN, constant or huge
profiles give a falsy ``Feature.failed(reason)``. :func:`extractor` builds one by name: a
built-in (:data:`BUILTIN`), a ``"package.module:Class"`` string, or an entry point in the
group ``seamtrack.extractors`` (read lazily: a broken plugin never breaks ``import seamtrack``).

The built-ins share one front end, :func:`segment_profile` (split-and-merge): drop isolated
outliers against a 5-point running median, estimate the noise from second differences, cut the
profile at jumps, split each run by Douglas-Peucker at a noise-scaled tolerance, merge
neighbours that fit one line, and refit each piece by total least squares on its inliers. The
family extractors then pick pieces by geometry (a V opening towards the sensor, two plates with
a gap, a step between parallel sheets, a ridge) and intersect their lines; a line that ends at a
gap ends half a ray spacing beyond its last point (the edge lies between two rays). The two-plate
extractors (square butt, lap) gather pieces on one line into a plate however short they are, and
read what lies between two plates: a stray line cut off both (a false reflection) hides the
columns it covers, it opens no gap, and where it covers a plate's edge the edge is estimated
under it. The v-groove extractor reads what lies just beyond each bevel's lower end: a stray
line there (a false reflection over the root) hides the root corner, which is then put where
the bevel reaches the other corner's depth below the plates. The generic extractor needs no
segmentation: sliding-window slopes, the sharpest turn, two local fits.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .errors import PluginError
from .lines import (
    Line,
    Segments,
    _angle,
    _fit,
    _median,
    collinear_groups,
    collinear_members,
    corner_or_end,
    corner_with,
    intersect,
    segment_profile,
)
from .profiles import Feature, Profile

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
@dataclass(frozen=True)
class _Base:
    """Shared parameters and the never-raise wrapper of the built-in extractors."""

    name: str = "base"
    min_tol_mm: float = 0.03
    min_points: int = 8
    min_arm_mm: float = 0.5

    def __call__(self, profile: Profile) -> Feature:
        try:
            with np.errstate(all="ignore"):
                seg = segment_profile(
                    profile, min_tol_mm=self.min_tol_mm, min_points=self.min_points
                )
                if isinstance(seg, str):
                    return Feature.failed(seg, joint=self.name)
                return self._extract(profile, seg)
        except (
            ValueError,
            IndexError,
            ZeroDivisionError,
            FloatingPointError,
            np.linalg.LinAlgError,
            AttributeError,
            TypeError,
        ) as exc:  # never raise on data
            return Feature.failed(f"{self.name}: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        raise NotImplementedError

    def _found(self, profile: Profile, point: FloatArray, **kw: Any) -> Feature:
        return Feature.found(point, profile.T_world_sensor, joint=self.name, **kw)

    def _groups(self, seg: Segments) -> list[Line]:
        """Collinear groups supported enough to be an arm or a plate."""
        return [
            g
            for g in collinear_groups(seg)
            if g.count >= self.min_points and g.extent >= self.min_arm_mm
        ]

    def _arms(
        self,
        seg: Segments,
        opening_down: bool,
        min_deg: float,
        max_deg: float,
        max_reach_mm: float,
        groups: list[Line] | None = None,
    ) -> tuple[Line, Line, FloatArray, float] | str:
        """The best pair of lines forming a V (opening towards the sensor, -z) or a ridge
        (``opening_down``: the arms fall away from the sensor): (left, right, apex, score)."""
        if groups is None:
            groups = self._groups(seg)
        sign = 1.0 if opening_down else -1.0
        best: tuple[Line, Line, FloatArray, float] | None = None
        for i, a in enumerate(groups):
            for b in groups[i + 1 :]:
                x = intersect(a, b)
                if x is None:
                    continue
                arms = []
                for g in (a, b):
                    v = g.centroid - x
                    v = v / max(float(np.hypot(*v)), 1e-300)
                    near = float(np.min((seg.points[g.index] - x) @ v))
                    arms.append((v, near, g))
                (va, na, ga), (vb, nb, gb) = sorted(arms, key=lambda arm: float(arm[0][0]))
                included = math.degrees(math.acos(float(np.clip(va @ vb, -1, 1))))
                bis = va + vb
                ok = (
                    va[0] < 0 < vb[0]
                    and sign * va[1] > 0
                    and sign * vb[1] > 0
                    and min_deg <= included <= max_deg
                    and sign * bis[1] > 0.7 * float(np.hypot(*bis))  # bisector within 45 deg
                    and -seg.tol <= min(na, nb)
                    and max(na, nb) <= max_reach_mm
                )
                score = float(ga.count + gb.count)
                if ok and (best is None or score > best[3]):
                    best = (ga, gb, x, score)
        return best if best is not None else "no pair of lines forms the joint"


def _confidence(arms: list[Line], seg: Segments) -> float:
    """Share of the kept points explained by the feature's lines, scaled by their fit."""
    explained = sum(a.count for a in arms) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(a.rms for a in arms) / seg.tol)
    return float(np.clip(0.5 * explained + 0.5 * fit, 0.0, 1.0))


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


#: A gap's wall or a lap's edge face stands at least this steep on the plates (deg). A false
#: reflection is a stray line tilted by at most 45 deg in the laser plane: up to 60 deg on a
#: plate rolled by 15 deg, so it is never taken for a wall.
_WALL_DEG = 65.0
#: A gap's bottom (a backing seen through the gap) lies within this angle of the plates (deg).
_BOTTOM_DEG = 10.0
#: A piece within this angle of a plate (deg) is plate where it lies on the plate's line.
_PLATE_DEG = 20.0


def _on(line: Line, index: NDArray[np.intp], points: FloatArray) -> Line:
    """``line`` carrying other inliers (their coordinates along it): a stub's edge measured
    on the line of the whole plate."""
    t = (points[index] - line.centroid) @ line.direction
    return Line(index, line.centroid, line.direction, t, line.rms)


def _towards_sensor(line: Line, q: FloatArray) -> FloatArray:
    """Signed distance of points from ``line``, positive on the sensor's side (the origin)."""
    h = (q - line.centroid) @ line.normal
    return h if float(line.centroid @ line.normal) < 0 else -h


def _ray_t(line: Line, q: FloatArray) -> FloatArray:
    """Where the rays from the emitter (the origin) through points ``q`` cross ``line``, as
    coordinates along it: which stretch of the plate those columns would have shown."""
    n = line.normal
    s = float(line.centroid @ n) / (q @ n)
    return (q * s[:, None] - line.centroid) @ line.direction


@dataclass(frozen=True)
class _Hole:
    """What lies between two consecutive plate runs (:func:`_hole`).

    ``open_mm``: how much of the stretch between their ends (along the left run's line)
    nothing covers: columns with no point (the laser fell through a gap or into a shadow), a
    wall, or a bottom far behind both plates. A false reflection's columns are unknown, not
    open. ``left`` / ``right``: where a stray line covers a run's end, the best estimate of
    its edge (:func:`_hidden_edge`); None where the end is seen.
    """

    open_mm: float
    left: FloatArray | None
    right: FloatArray | None


def _stretches(
    keep: NDArray[np.bool_], t: FloatArray, spacing: float
) -> tuple[FloatArray, FloatArray, list[NDArray[np.intp]]]:
    """The stretches of consecutive kept points, broken by another point or by missing
    columns: their starts and ends along a line (``t``: where the points' columns cross it),
    and the positions of the points of the first and of the last stretch."""
    k = np.flatnonzero(keep)
    if not k.size:
        return np.empty(0), np.empty(0), []
    tk = t[k]
    starts = np.flatnonzero((np.diff(k) > 1) | (np.abs(np.diff(tk)) > 3.0 * spacing)) + 1
    starts = np.concatenate([[0], starts])
    t0 = np.minimum.reduceat(tk, starts) - 0.5 * spacing
    t1 = np.maximum.reduceat(tk, starts) + 0.5 * spacing
    ends = [*starts[1:].tolist(), len(k)]
    return t0, t1, [k[i:j] for i, j in ((starts[0], ends[0]), (starts[-1], ends[-1]))]


def _hidden_edge(
    line: Line,
    part: NDArray[np.intp],
    t: FloatArray,
    on_line: NDArray[np.bool_],
    stray: NDArray[np.bool_],
    t_end: float,
    spacing: float,
    at_end: bool,
) -> FloatArray | None:
    """Where a run's edge lies when the covered stretch next to it (``part``, from the run's
    end outwards) holds a stray line: the middle of the stray line's stretch along the run's
    line (the edge may lie anywhere under it), or, when the plate shows again beyond it, the
    last plate point seen. None when no stray line touches the run's end."""
    seen = on_line[part] | stray[part]
    stop = int(np.argmin(seen)) if not seen.all() else len(part)
    part = part[:stop]  # up to the first point of anything else (the other plate, a surface)
    s = np.flatnonzero(stray[part])
    if not s.size:
        return None
    p = np.flatnonzero(on_line[part])
    sign = 1.0 if at_end else -1.0
    if p.size and p[-1] > s[-1]:
        return line.point(float(t[part[p[-1]]]) + sign * 0.5 * spacing)
    return line.point(0.5 * (t_end + float(t[part[s[-1]]]) + sign * 0.5 * spacing))


def _hole(seg: Segments, owner: NDArray[np.intp], a: Line, b: Line, min_bottom_mm: float) -> _Hole:
    """What lies between run ``a``'s last inlier and run ``b``'s first (``owner``: each kept
    point's piece, -1 for none)."""
    lo, hi = int(a.index[-1]), int(b.index[0])
    sp_a, sp_b = max(a.step(True), seg.spacing), max(b.step(False), seg.spacing)
    ta = float(a.t[-1]) + 0.5 * a.step(True)
    tb_b = float(b.t[0]) - 0.5 * b.step(False)
    tb = float((b.point(tb_b) - a.centroid) @ a.direction)
    width = tb - ta
    if hi - lo < 2:
        return _Hole(width, None, None)
    q = seg.points[lo + 1 : hi]
    own = owner[lo + 1 : hi]
    # Points on a plate's line (leftovers too short for a piece, a corner piece's end) are
    # plate: no opening, no stray line.
    off_a, off_b = np.abs(_towards_sensor(a, q)), np.abs(_towards_sensor(b, q))
    off = np.minimum(off_a, off_b)
    plate = off <= seg.tol
    # What covers the hole (is no opening): the plates and any surface but a wall (steep on
    # the plates, reaching off them) or a bottom far behind both plates (a backing seen
    # through a gap). A line crossing a plate's line at an angle is no plate where it does.
    cover = np.zeros(len(q), dtype=bool)
    wall, bottom = math.radians(_WALL_DEG), math.radians(_BOTTOM_DEG)
    for j in np.unique(own[own >= 0]):
        mine = own == j
        ln = seg.lines[int(j)]
        rel = _angle(ln, a)
        if rel >= wall and float(off[mine].max()) >= 2 * seg.tol:
            continue
        if rel <= bottom:
            c = ln.centroid.reshape(1, 2)
            depth = -max(float(_towards_sensor(a, c)[0]), float(_towards_sensor(b, c)[0]))
            if depth >= min_bottom_mm:
                continue
        if rel > math.radians(_PLATE_DEG):
            plate &= ~mine
        cover |= mine
    # Points in no piece off the plates: stray points (fewer than three in a row) and walls
    # cover nothing; other runs of three or more do.
    loose = np.flatnonzero((own < 0) & ~plate)
    if loose.size >= 3:
        bounds = np.flatnonzero(np.diff(loose) > 1) + 1
        for i, j in zip([0, *bounds.tolist()], [*bounds.tolist(), len(loose)], strict=True):
            part = loose[i:j]
            if j - i >= 3 and (
                _angle(_fit(q, part), a) < wall or float(off[part].max()) < 2 * seg.tol
            ):
                cover[part] = True
    cover |= plate
    if not cover.any():
        return _Hole(width, None, None)
    # A surface that runs on from a plate without a jump (a tack, an edge face, a chamfer) is
    # part of the part; a line cut off both plates by jumps (a false reflection) is stray:
    # its columns are unknown, and over a plate's end it may hide the edge. A stray line
    # ends next to a plate only by chance, so a plate holds on to its surface more tightly
    # (noise, not the split tolerance) than the surface holds together.
    seq = seg.points[lo : hi + 1]
    d = np.hypot(*np.diff(seq, axis=0).T)
    cut = d > max(6 * seg.spacing, 2 * seg.tol, 0.1)
    held = max(6 * seg.spacing, 4 * seg.sigma, 0.1)
    cut[0], cut[-1] = d[0] > held, d[-1] > held
    stray = cover & ~plate
    if not cut.any():
        stray[:] = False
    else:
        k = np.flatnonzero(cut)
        if not cut[0]:
            stray[: k[0]] = False  # held by the left plate
        if not cut[-1]:
            stray[k[-1] :] = False  # held by the right plate
    qa = _ray_t(a, q)
    t0, t1, (first, _) = _stretches(cover, qa, sp_a)
    covered = float(np.clip(np.minimum(t1, tb) - np.maximum(t0, ta), 0.0, None).sum())
    left = right = None
    if stray.any():
        on_a = plate & (off_a <= seg.tol)
        if t0[0] <= ta + 2.0 * sp_a:
            left = _hidden_edge(a, first, qa, on_a, stray, ta, sp_a, True)
        qb = _ray_t(b, q)
        t0, t1, (_, last) = _stretches(cover, qb, sp_b)
        if t1[-1] >= tb_b - 2.0 * sp_b:
            on_b = plate & (off_b <= seg.tol)
            right = _hidden_edge(b, last[::-1], qb, on_b, stray, tb_b, sp_b, False)
    return _Hole(max(0.0, width - covered), left, right)


@dataclass(frozen=True)
class _Sheets:
    """The plates of a profile: runs of pieces on one plate line, in column order."""

    runs: list[Line]
    groups: list[int]
    owner: NDArray[np.intp]
    others: list[Line]


def _owner(seg: Segments) -> NDArray[np.intp]:
    """The piece each kept point is an inlier of (-1: none)."""
    owner = np.full(len(seg.points), -1, dtype=np.intp)
    for j, ln in enumerate(seg.lines):
        owner[ln.index] = j
    return owner


def _sheets(
    seg: Segments,
    owner: NDArray[np.intp],
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    apart: Callable[[Line, Line], bool] | None,
) -> _Sheets:
    """Plates and where they are interrupted.

    Flat pieces (within ``max_tilt_deg`` of the y axis) that lie on one line form a plate
    line, however short each piece is (a stub cut off a plate by a reflection stays on its
    plate); a line spanning ``min_plate_mm`` is a plate. Column order then gives runs:
    consecutive pieces of one plate line stay one run unless ``apart(left, right)`` says
    the hole between them is a joint (a square butt's open gap), so a reflection or a
    dropout never splits a plate.
    """
    tilt = math.radians(max_tilt_deg)
    flat = [
        ln
        for ln in seg.lines
        if ln.count >= min_points and abs(math.atan2(ln.direction[1], ln.direction[0])) <= tilt
    ]

    def span(line: Line, pieces: list[Line]) -> float:
        """Extent along ``line`` of pieces on it (from their ends)."""
        t = []
        for p in pieces:
            c = float((p.centroid - line.centroid) @ line.direction)
            d = float(p.direction @ line.direction)
            t += [c + d * float(p.t[0]), c + d * float(p.t[-1])]
        return max(t) - min(t)

    plates: list[tuple[int, Line]] = []
    groups: list[list[Line]] = []
    for members in collinear_members(seg, flat):
        pieces = [flat[i] for i in members]
        if span(pieces[0], pieces) >= min_plate_mm:
            plates += [(len(groups), p) for p in pieces]
            groups.append(pieces)
    plates.sort(key=lambda gp: int(gp[1].index[0]))
    # Plates follow each other in column order: a plate line that shows only briefly between
    # two stretches of another, or not parallel to it, is no plate there (a reflection lying
    # on its line by chance, a tilted one long enough to pass for a plate).
    # When two such blocks compete (a plate's stub next to the reflection), the smaller goes.
    while True:
        blocks = []
        i = 1
        while i < len(plates) - 1:
            j = i
            while j < len(plates) and plates[j][0] == plates[i][0]:
                j += 1
            if j < len(plates) and plates[i - 1][0] == plates[j][0]:
                block = [p for _, p in plates[i:j]]
                tilted = _angle(block[0], groups[plates[j][0]][0]) > math.radians(10)
                if tilted or span(groups[plates[i][0]][0], block) < min_plate_mm:
                    blocks.append((sum(p.count for p in block), i, j))
            i = j
        if not blocks:
            break
        _, i, j = min(blocks)
        del plates[i:j]
    runs: list[tuple[int, list[Line]]] = []
    for g, piece in plates:
        if runs and runs[-1][0] == g:
            # The hole between the run so far and this piece, on the plate's line (the ends
            # suffice: its last and first inliers and their spacing).
            if apart is None or not apart(
                _on(groups[g][0], runs[-1][1][-1].index[-11:], seg.points),
                _on(groups[g][0], piece.index[:11], seg.points),
            ):
                runs[-1][1].append(piece)
                continue
        runs.append((g, [piece]))
    # A run long enough is its own line (two plates a hair out of line keep their heights);
    # a stub is measured on its plate's line.
    out = []
    for g, pieces in runs:
        if len(pieces) == 1 and pieces[0].extent >= min_plate_mm:
            out.append(pieces[0])
            continue
        idx = np.concatenate([p.index for p in pieces])
        if span(groups[g][0], pieces) >= min_plate_mm:
            out.append(_fit(seg.points, idx))
        else:
            out.append(_on(groups[g][0], idx, seg.points))
    others = [ln for ln in seg.lines if ln.count >= min_points]
    return _Sheets(out, [g for g, _ in runs], owner, others)


def _neighbours(sheets: _Sheets, max_gap_mm: float) -> list[tuple[Line, Line, bool]]:
    """Consecutive near-parallel runs (left, right, same plate line) whose facing ends are at
    most ``max_gap_mm`` apart."""
    out = []
    for (a, ga), (b, gb) in itertools.pairwise(zip(sheets.runs, sheets.groups, strict=True)):
        if (
            _angle(a, b) <= math.radians(10)
            and float(np.hypot(*(b.point(float(b.t[0])) - a.point(float(a.t[-1]))))) <= max_gap_mm
        ):
            out.append((a, b, ga == gb))
    return out


def _edge(
    line: Line, at_end: bool, hidden: FloatArray | None, sheets: _Sheets, seg: Segments
) -> FloatArray:
    """A run's edge: its corner or end, or where a stray line covers its end, the estimate
    of :func:`_hole` (on the run's line)."""
    if hidden is None:
        return corner_or_end(line, at_end, sheets.others, seg)
    return _foot(hidden, line)


@dataclass(frozen=True)
class SquareButtExtractor(_Base):
    """Square butt: two plates side by side with a gap and/or a high-low step between them.
    Seam: the midpoint of the two plate edges.

    Between two plates on one line the gap must be open over ``min_open_mm``: no points
    there (the laser falls through), walls, or a bottom at least ``min_bottom_mm`` behind
    (a backing). A stray line nearer the plates (a false reflection) is unknown, not gap: a
    plate interrupted only by one is a single plate. Where such a line covers a plate's
    edge, the edge is put in the middle of the covered stretch (confidence halved).
    """

    name: str = "square-butt"
    min_gap_mm: float = 0.3
    max_gap_mm: float = 6.0
    min_plate_mm: float = 1.0
    max_tilt_deg: float = 40.0
    min_open_mm: float = 0.15
    min_bottom_mm: float = 5.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        min_opening = max(self.min_gap_mm, 3 * seg.tol)

        holes: dict[tuple[int, int], _Hole] = {}

        def apart(left: Line, right: Line) -> bool:
            if float((right.end(False) - left.end(True)) @ left.direction) < min_opening:
                return False
            hole = _hole(seg, owner, left, right, self.min_bottom_mm)
            holes[int(left.index[-1]), int(right.index[0])] = hole
            return hole.open_mm >= self.min_open_mm

        owner = _owner(seg)
        sheets = _sheets(seg, owner, self.min_points, self.min_plate_mm, self.max_tilt_deg, apart)
        best, best_key = None, (False, 0.0)
        for a, b, _ in _neighbours(sheets, self.max_gap_mm):
            opening = float(np.hypot(*(b.end(False) - a.end(True))))
            if opening < min_opening:
                continue
            hole = holes.get((int(a.index[-1]), int(b.index[0])))
            if hole is None:
                hole = _hole(seg, owner, a, b, self.min_bottom_mm)
            # An open gap beats one a stray line covers.
            key = (hole.open_mm >= self.min_open_mm, opening)
            if key > best_key:
                best, best_key = (a, b, hole), key
        if best is None:
            return Feature.failed("no gap or step between two plates", joint=self.name)
        a, b, hole = best
        ea = _edge(a, True, hole.left, sheets, seg)
        eb = _edge(b, False, hole.right, sheets, seg)
        gap = abs(float((eb - ea) @ a.direction))
        sure = best_key[0] and hole.left is None and hole.right is None
        conf = _confidence([a, b], seg) * (1.0 if sure else 0.5)
        return self._found(
            profile, 0.5 * (ea + eb), confidence=conf, edges_laser=np.array([ea, eb]), gap_mm=gap
        )


@dataclass(frozen=True)
class LapExtractor(_Base):
    """Lap: two parallel sheets with a step. Seam: the top sheet's edge projected normally
    onto the lower sheet (the corner where the edge meets it). Edge: the top sheet's edge.

    A sheet interrupted by a false reflection or a dropout stays one sheet. Where a stray
    line covers the top sheet's edge, the lower sheet's visible end gives the corner (or,
    when the corner lies in the edge's shadow, the ray over that end gives the edge); where
    it covers the lower sheet's end, the top edge's foot does (confidence halved).
    """

    name: str = "lap"
    min_step_mm: float = 0.3
    max_gap_mm: float = 3.0
    min_plate_mm: float = 2.0
    max_tilt_deg: float = 40.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        sheets = _sheets(seg, _owner(seg), self.min_points, self.min_plate_mm,
                         self.max_tilt_deg, None)  # fmt: skip
        best, best_score = None, 0.0
        for a, b, same in _neighbours(sheets, self.max_gap_mm):
            step = float((b.centroid - a.centroid) @ a.normal)  # > 0: b is deeper
            if same or abs(step) < max(self.min_step_mm, 3 * seg.tol):
                continue
            score = float(a.count + b.count)
            if score > best_score:
                best, best_score = (a, b, step), score
        if best is None:
            return Feature.failed("no step between two parallel sheets", joint=self.name)
        a, b, step = best
        hole = _hole(seg, sheets.owner, a, b, math.inf)
        top, lower, at_end = (a, b, True) if step > 0 else (b, a, False)
        top_hidden, lower_hidden = (hole.left, hole.right) if at_end else (hole.right, hole.left)
        # Away from the top sheet, along the lower one.
        away = lower.direction if at_end else -lower.direction
        if top_hidden is None:
            edge = corner_or_end(top, at_end, sheets.others, seg)
            foot = _foot(edge, lower)
            # The ray over the top edge (from the emitter at the origin) lands on the lower
            # sheet at `shadow`: beyond the foot (away from the top sheet) the corner is in
            # shadow and the foot is the best estimate; otherwise the lower sheet is seen up
            # to the corner.
            shadow = intersect(_ray(edge), lower)
            if lower_hidden is not None or (
                shadow is not None and float((shadow - foot) @ away) > 0.0
            ):
                seam = foot
            else:
                seam = corner_or_end(lower, not at_end, sheets.others, seg)
        elif lower_hidden is None:
            # The lower sheet's visible end is the corner, or (in the edge's shadow) where
            # the ray over the hidden top edge lands.
            end = corner_or_end(lower, not at_end, sheets.others, seg)
            over = intersect(_ray(end), top)
            seam = end
            edge = _edge(top, at_end, top_hidden, sheets, seg)
            if over is not None and float((_foot(over, lower) - end) @ away) < 0.0:
                edge, seam = over, _foot(over, lower)
        else:
            edge = _edge(top, at_end, top_hidden, sheets, seg)
            seam = _foot(edge, lower)
        sure = top_hidden is None and lower_hidden is None
        return self._found(
            profile,
            seam,
            confidence=_confidence([a, b], seg) * (1.0 if sure else 0.5),
            edges_laser=edge.reshape(1, 2),
        )


def _foot(point: FloatArray, line: Line) -> FloatArray:
    """``point`` projected normally onto ``line``."""
    return point - float((point - line.centroid) @ line.normal) * line.normal


def _ray(point: FloatArray) -> Line:
    """The ray from the emitter (the origin) through ``point``, as a line."""
    u = point / max(float(np.hypot(*point)), 1e-300)
    return Line(np.empty(0, np.intp), np.zeros(2), u, np.empty(0), 0.0)


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
        except (
            ValueError,
            IndexError,
            ZeroDivisionError,
            FloatingPointError,
            np.linalg.LinAlgError,
            AttributeError,
            TypeError,
        ) as exc:
            return Feature.failed(f"generic: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile) -> Feature:
        from .generic_kernel import front_end, window_turns

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
        from .generic_kernel import corner_point

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
