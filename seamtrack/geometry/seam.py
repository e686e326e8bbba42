"""The seam: the joint line the torch follows, as the paper models it (a polyline of points).

Between points the seam is the straight segment (linear interpolation, paper Sec. 2.1). Each
point may carry a unit normal: the torch direction there (for a CAD seam, the bisector of the
two adjacent faces' normals). Without normals the torch direction is world +Z made orthogonal to
the tangent, which is how the paper's 3-axis Cartesian robot holds its torch.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from seamtrack import constants
from seamtrack.errors import SeamError

FloatArray = NDArray[np.float64]

#: Query points per block of :meth:`Seam.closest` (its temporaries grow with the block).
_QUERY_BLOCK = 32_768

#: Segments tested exactly per query point before the exactness check (see :meth:`Seam.closest`).
#: 4: a torch's trace lies within a fraction of a segment of its seam, where the 4 nearest
#: midpoints prove the answer (16 cost twice the time in the tree's query: 28 -> 12 ms for the
#: 32,001 ticks of pipe-saddle, the same answers); a query they do not prove asks for 8 times
#: more.
_CANDIDATE_SEGMENTS = 4

#: Up to this many (query point, segment) pairs :meth:`Seam.closest` tests them all, without
#: its tree (a frame's point or two on a seam of a few hundred points: the tree's query costs
#: more than the loop).
_ALL_PAIRS = 4096

#: A query point farther than this from the origin (mm) is searched for at this distance along
#: its direction (:meth:`Seam.closest`): squared distances past ~1e154 mm overflow, and far
#: before that the distances to different seam points agree to the last digit. At 1e12 mm they
#: still resolve 1e-4 mm, and the nearest seam point of a point that far moves by less than
#: (seam size)^2 / 1e12 mm as the point recedes further along its direction.
FAR_MM = 1e12


def paper_points(step_mm: float = 2.0, length_mm: float = 400.0) -> FloatArray:
    """The seam of the paper's verification, Eq. (15)-(17).

    X runs from 0 to ``length_mm`` in steps of ``step_mm`` (both ends included: 201 points for
    the paper's 0..400 step 2, which the paper calls "200 points"), Y = 10 cos(pi X / 200),
    Z = 10 sin(pi X / 200), in the workpiece frame {WP}.

    Returns
    -------
    points : (n, 3) float
    """
    if not step_mm > 0 or not length_mm > 0:
        raise SeamError(
            "step and length must be > 0",
            field="seam.step_mm",
            fix="give positive numbers, e.g. step_mm = 2, length_mm = 400",
        )
    n = int(round(length_mm / step_mm))
    x = np.linspace(0.0, n * step_mm, n + 1)
    phase = x * np.pi / 200.0
    return np.column_stack([x, 10.0 * np.cos(phase), 10.0 * np.sin(phase)])


def paper_curve(x_mm: ArrayLike) -> FloatArray:
    """Exact points of the paper's curve (Eq. 16-17) at given X (mm); (n, 3)."""
    x = np.asarray(x_mm, dtype=np.float64)
    phase = x * np.pi / 200.0
    return np.column_stack([x, 10.0 * np.cos(phase), 10.0 * np.sin(phase)])


@dataclass(frozen=True, eq=False)
class Closest:
    """Closest points on the seam to query points.

    Attributes
    ----------
    points : (m, 3) float
        The closest seam points.
    arc_length_mm : (m,) float
        Their arc length along the seam.
    distance_mm : (m,) float
        Distance from each query point to the seam.
    segment : (m,) int
        Index of the segment that holds each closest point.
    """

    points: FloatArray
    arc_length_mm: FloatArray
    distance_mm: FloatArray
    segment: NDArray[np.intp]


@dataclass(frozen=True, eq=False)
class Seam:
    """A seam polyline with per-point torch normals.

    Build it with :meth:`from_points`, :meth:`from_paper`, or :meth:`from_csv`; those validate the
    input (no NaN, at least two points, no repeated consecutive points).

    Attributes
    ----------
    points : (n, 3) float
        Seam points in mm (world frame unless said otherwise).
    normals : (n, 3) float
        Unit torch directions, orthogonal to the tangent.
    name : str
    """

    points: FloatArray
    normals: FloatArray
    name: str = ""
    _tree: cKDTree | None = field(default=None, repr=False, compare=False)

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_points(
        cls,
        points: ArrayLike,
        normals: ArrayLike | None = None,
        name: str = "",
        field: str = "seam",
    ) -> Seam:
        """Validate points (and optional normals) and build the seam.

        Parameters
        ----------
        points : (n, 3) float
        normals : (n, 3) float, optional
            Torch directions; made unit and orthogonal to the tangent. Default: world +Z made
            orthogonal to the tangent.
        field : str
            Name used in error messages (the scene key or file the points came from).
        """
        pts = np.array(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise SeamError(
                f"points must have shape (n, 3), got {pts.shape}",
                field=field,
                fix="give one x, y, z triple per point",
            )
        if len(pts) < 2:
            raise SeamError(
                f"a seam needs at least 2 points, got {len(pts)}",
                field=field,
                fix="give the seam's start and end at least",
            )
        bad = ~np.isfinite(pts).all(axis=1)
        if bad.any():
            raise SeamError(
                f"point {int(np.flatnonzero(bad)[0])} is not finite (NaN or inf)",
                field=field,
                fix="remove or repair that point",
            )
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        repeated = seg <= constants.SEAM_POINT_TOL_MM
        if repeated.any():
            i = int(np.flatnonzero(repeated)[0])
            raise SeamError(
                f"points {i} and {i + 1} are the same point",
                field=field,
                fix="remove repeated points (a seam must advance between points)",
            )
        tangents = _vertex_tangents(pts)
        if normals is None:
            guide = np.broadcast_to([0.0, 0.0, 1.0], pts.shape)
        else:
            guide = np.array(normals, dtype=np.float64)
            if guide.shape != pts.shape or not np.isfinite(guide).all():
                raise SeamError(
                    f"normals must be finite with shape {pts.shape}, got {guide.shape}",
                    field=field,
                    fix="give one finite normal per point, or none",
                )
        n = guide - np.sum(guide * tangents, axis=1, keepdims=True) * tangents
        norm = np.linalg.norm(n, axis=1)
        if normals is None and (norm < 1e-9).any():
            # Vertical seam pieces: fall back to world +X for the torch direction there.
            alt = np.array([1.0, 0.0, 0.0]) - tangents[:, [0]] * tangents
            n = np.where((norm < 1e-9)[:, None], alt, n)
            norm = np.linalg.norm(n, axis=1)
        if (norm < 1e-9).any():
            i = int(np.flatnonzero(norm < 1e-9)[0])
            raise SeamError(
                f"normal {i} is parallel to the seam tangent",
                field=field,
                fix="give torch directions across the seam, not along it",
            )
        return cls(points=pts, normals=n / norm[:, None], name=name)

    @classmethod
    def from_paper(cls, step_mm: float = 2.0, length_mm: float = 400.0) -> Seam:
        """The paper's verification seam, Eq. (15)-(17)."""
        return cls.from_points(paper_points(step_mm, length_mm), name="paper Eq. 15-17")

    @classmethod
    def from_csv(cls, path: str | Path, field: str = "seam.file") -> Seam:
        """Read a seam from a CSV file.

        Columns ``x_mm, y_mm, z_mm`` and optionally ``nx, ny, nz``, with a header line; or three
        or six bare numeric columns. Lines starting with ``#`` are comments.
        """
        path = Path(path)
        if not path.is_file():
            raise SeamError(
                f"file {str(path)!r} does not exist",
                field=field,
                fix="give the path of a CSV seam file (relative to the scene file)",
            )
        rows: list[list[str]] = []
        line_of: list[int] = []  # each row's line in the file (1-based), for the messages
        try:
            with path.open(newline="", encoding="utf-8-sig") as handle:
                numbered = (
                    (i, line) for i, line in enumerate(handle, 1)
                    if not line.lstrip().startswith("#")
                )  # fmt: skip
                for i, line in numbered:
                    row = next(csv.reader([line]), [])
                    if row and any(cell.strip() for cell in row):
                        rows.append([cell.strip() for cell in row])
                        line_of.append(i)
                    if len(rows) > constants.MAX_SEAM_POINTS + 1:
                        raise SeamError(
                            f"{path.name}: more than {constants.MAX_SEAM_POINTS:.0e} points",
                            field=field,
                            fix="thin the seam out (a point every 0.01 mm is plenty)",
                        )
        except UnicodeDecodeError:
            raise SeamError(
                f"{path.name} is not a text file", field=field, fix="give a CSV text file"
            ) from None
        if rows and not _is_number(rows[0][0]):
            rows, line_of = rows[1:], line_of[1:]
        for row, number in zip(rows, line_of, strict=True):
            if len(row) != len(rows[0]):
                raise SeamError(
                    f"{path.name}, line {number}: {len(row)} cells where line {line_of[0]} has "
                    f"{len(rows[0])}",
                    field=field,
                    fix="give every row the same columns (x_mm, y_mm, z_mm[, nx, ny, nz])",
                )
            bad = next((cell for cell in row if not _is_number(cell)), None)
            if bad is not None:
                raise SeamError(
                    f"{path.name}, line {number}: {bad!r} is not a number",
                    field=field,
                    fix="every data cell must be a number",
                )
        data = np.array([[float(c) for c in row] for row in rows], dtype=np.float64)
        if data.ndim != 2 or data.shape[1] not in (3, 6):
            raise SeamError(
                f"{path.name}: expected 3 or 6 columns, got shape {data.shape}",
                field=field,
                fix="columns x_mm, y_mm, z_mm[, nx, ny, nz]",
            )
        normals = data[:, 3:6] if data.shape[1] == 6 else None
        return cls.from_points(data[:, :3], normals, name=path.stem, field=f"{field} ({path.name})")

    def to_csv(self, path: str | Path) -> None:
        """Write ``x_mm, y_mm, z_mm, nx, ny, nz`` with a header."""
        header = "x_mm,y_mm,z_mm,nx,ny,nz"
        np.savetxt(
            path,
            np.hstack([self.points, self.normals]),
            delimiter=",",
            header=header,
            comments="",
            fmt="%.9f",
        )

    # ----------------------------------------------------------------- geometry
    @property
    def segment_lengths_mm(self) -> FloatArray:
        """(n-1,) segment lengths."""
        cached = self.__dict__.get("_segment_lengths")
        if cached is None:
            cached = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
            cached.flags.writeable = False
            self.__dict__["_segment_lengths"] = cached
        return cached

    @property
    def arc_length_mm(self) -> FloatArray:
        """(n,) arc length at each point, starting at 0."""
        cached = self.__dict__.get("_arc_length")
        if cached is None:
            cached = np.concatenate([[0.0], np.cumsum(self.segment_lengths_mm)])
            cached.flags.writeable = False
            self.__dict__["_arc_length"] = cached
        return cached

    @property
    def length_mm(self) -> float:
        return float(self.segment_lengths_mm.sum())

    @property
    def tangents(self) -> FloatArray:
        """(n, 3) unit tangents at the points (mean of the adjacent segment directions)."""
        return _vertex_tangents(self.points)

    def transformed(self, T_a_b: ArrayLike) -> Seam:
        """The seam mapped by a rigid pose (points and normals)."""
        from seamtrack.geometry.frames import apply, apply_vectors

        return Seam.from_points(
            apply(T_a_b, self.points), apply_vectors(T_a_b, self.normals), name=self.name
        )

    def interpolate(self, arc_length_mm: ArrayLike) -> FloatArray:
        """Points at arc lengths (linear between seam points; clipped to the seam's ends).

        Parameters
        ----------
        arc_length_mm : (m,) float

        Returns
        -------
        points : (m, 3) float
        """
        s = np.clip(np.asarray(arc_length_mm, dtype=np.float64), 0.0, self.length_mm)
        knots = self.arc_length_mm
        return np.column_stack([np.interp(s, knots, self.points[:, k]) for k in range(3)])

    def tangent_at(self, arc_length_mm: ArrayLike) -> FloatArray:
        """(m, 3) unit tangent of the segment that holds each arc length."""
        s = np.atleast_1d(np.asarray(arc_length_mm, dtype=np.float64))
        seg = np.clip(
            np.searchsorted(self.arc_length_mm, s, side="right") - 1, 0, len(self.points) - 2
        )
        d = self.points[seg + 1] - self.points[seg]
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def closest(self, query_points: ArrayLike) -> Closest:
        """Closest points on the seam polyline, vectorized and exact.

        A KD-tree on segment midpoints proposes candidate segments; a query whose candidates do
        not provably contain the nearest segment (the next midpoint could still be nearer than
        the best distance plus half the longest segment) falls back to all segments.

        Parameters
        ----------
        query_points : (m, 3) or (3,) float
            Finite (a NaN or an infinity is the caller's bug: a ``ValueError``). A point
            farther than :data:`FAR_MM` from the origin is answered by the same point moved
            along its direction to that distance (the same nearest seam point to well below a
            micron), with its true distance.
        """
        q = np.asarray(query_points, dtype=np.float64)
        single = q.ndim == 1
        q = np.atleast_2d(q)
        if not np.isfinite(q).all():
            raise ValueError("Seam.closest: the query points must be finite (NaN or inf given)")
        scale = np.abs(q).max(axis=1) if len(q) else np.zeros(0)
        far = scale > FAR_MM
        if far.any():
            near = self.closest(q * np.where(far, FAR_MM / np.maximum(scale, 1.0), 1.0)[:, None])
            m = scale[far][:, None]  # |q - p| = m |q / m - p / m|, without overflow
            near.distance_mm[far] = m[:, 0] * np.linalg.norm(
                q[far] / m - near.points[far] / m, axis=1
            )
            return Closest(near.points, near.arc_length_mm, near.distance_mm, near.segment)
        if len(q) > _QUERY_BLOCK:  # bounded temporaries: (block, candidates, 3) at a time
            parts = [self.closest(q[i : i + _QUERY_BLOCK]) for i in range(0, len(q), _QUERY_BLOCK)]
            return Closest(
                points=np.concatenate([c.points for c in parts]),
                arc_length_mm=np.concatenate([c.arc_length_mm for c in parts]),
                distance_mm=np.concatenate([c.distance_mm for c in parts]),
                segment=np.concatenate([c.segment for c in parts]),
            )
        a = self.points[:-1]
        d = self.points[1:] - a
        n_seg = len(a)
        if len(q) * n_seg <= _ALL_PAIRS:
            from seamtrack.geometry.nearest import nearest_all  # compiled: imported when used

            seg, best_dist, best_t = nearest_all(q, np.ascontiguousarray(a), d)
            return self._closest_of(seg, best_dist, best_t, single)
        k = min(_CANDIDATE_SEGMENTS, n_seg)
        tree = self._midpoint_tree()
        mid_dist, cand = tree.query(q, k=k)
        cand = np.asarray(cand).reshape(len(q), k)
        mid_dist = np.asarray(mid_dist).reshape(len(q), k)
        from seamtrack.geometry.nearest import nearest_of  # compiled: imported when first used

        seg, best_dist, best_t = nearest_of(q, a, d, np.ascontiguousarray(cand, dtype=np.int64))
        if k < n_seg:
            # Exactness: the nearest segment's midpoint is within best + half the longest
            # segment. Queries that cannot prove it ask the tree again with more candidates.
            half_longest = 0.5 * float(np.max(self.segment_lengths_mm))
            unsure = np.flatnonzero(mid_dist[:, -1] <= best_dist + half_longest)
            kk = k
            while len(unsure) and kk < n_seg:
                kk = min(kk * 8, n_seg)
                for chunk in np.array_split(unsure, max(1, len(unsure) * kk // 2_000_000 + 1)):
                    if len(chunk) == 0:
                        continue
                    md, cd = tree.query(q[chunk], k=kk)
                    md = np.asarray(md).reshape(len(chunk), kk)
                    cd = np.asarray(cd).reshape(len(chunk), kk)
                    dist_c, t_c = _point_segment(q[chunk, None, :], a[cd], d[cd])
                    j = np.argmin(dist_c, axis=1)
                    rows_c = np.arange(len(chunk))
                    seg[chunk] = cd[rows_c, j]
                    best_dist[chunk] = dist_c[rows_c, j]
                    best_t[chunk] = t_c[rows_c, j]
                    mid_dist[chunk, -1] = md[:, -1]
                unsure = unsure[
                    (mid_dist[unsure, -1] <= best_dist[unsure] + half_longest) & (kk < n_seg)
                ]
        return self._closest_of(seg, best_dist, best_t, single)

    def _closest_of(
        self, seg: NDArray[np.int64], best_dist: FloatArray, best_t: FloatArray, single: bool
    ) -> Closest:
        a = self.points[:-1]
        d = self.points[1:] - a
        points = a[seg] + best_t[:, None] * d[seg]
        s = self.arc_length_mm[seg] + best_t * self.segment_lengths_mm[seg]
        result = Closest(points=points, arc_length_mm=s, distance_mm=best_dist, segment=seg)
        if single:
            return Closest(points[0:1], s[0:1], best_dist[0:1], seg[0:1])
        return result

    def closest_near(
        self, point: ArrayLike, arc_length_hint_mm: float, window_mm: float = 5.0
    ) -> float:
        """Arc length of the closest seam point to one point, searching only the stretch of
        seam within ``window_mm`` (arc length) of ``arc_length_hint_mm``, widened while the
        best lies on a cut end of that stretch.

        For a point that moves continuously, like the torch: it follows the seam it is on
        rather than jumping to another stretch that passes close by (a hairpin's other leg).
        """
        knots = self.arc_length_mm
        length = self.length_mm
        n_seg = len(self.points) - 1
        p = np.asarray(point, dtype=np.float64)[None, :]
        while True:
            s0 = max(arc_length_hint_mm - window_mm, 0.0)
            s1 = min(arc_length_hint_mm + window_mm, length)
            i0 = min(max(int(np.searchsorted(knots, s0, side="right")) - 1, 0), n_seg - 1)
            i1 = min(max(int(np.searchsorted(knots, s1, side="left")), i0 + 1), n_seg)
            starts = self.points[i0:i1].copy()
            ends = self.points[i0 + 1 : i1 + 1].copy()
            s_start = knots[i0:i1].copy()
            starts[0], ends[-1] = self.interpolate([s0, s1])
            s_start[0] = s0
            d = ends - starts
            dist, t = _point_segment(p, starts, d)
            j = int(np.argmin(dist))
            s = float(s_start[j] + t[j] * np.linalg.norm(d[j]))
            cut_low = s0 > 0.0 and s <= s0 + 1e-12
            cut_high = s1 < length and s >= s1 - 1e-12
            if not (cut_low or cut_high) or window_mm >= length:
                return s
            window_mm *= 2.0

    def distance(self, query_points: ArrayLike) -> FloatArray:
        """(m,) distance from each query point to the seam (see :meth:`closest`)."""
        return self.closest(query_points).distance_mm

    def _midpoint_tree(self) -> cKDTree:
        if self._tree is None:
            mid = 0.5 * (self.points[:-1] + self.points[1:])
            object.__setattr__(self, "_tree", cKDTree(mid))
        assert self._tree is not None
        return self._tree


def _vertex_tangents(points: FloatArray) -> FloatArray:
    seg = np.diff(points, axis=0)
    seg = seg / np.linalg.norm(seg, axis=1, keepdims=True)
    t = np.empty_like(points)
    t[0] = seg[0]
    t[-1] = seg[-1]
    t[1:-1] = seg[:-1] + seg[1:]
    norm = np.linalg.norm(t, axis=1, keepdims=True)
    # A 180 deg reversal leaves no mean direction: use the incoming segment there.
    flat = norm[:, 0] < 1e-12
    t[flat] = np.vstack([seg[:1], seg])[flat]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def _point_segment(q: FloatArray, a: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Distance and parameter t in [0, 1] from points q to segments a + t d (broadcasting)."""
    dd = np.maximum(np.sum(d * d, axis=-1), 1e-300)  # a zero-length (cut) segment is a point
    t = np.clip(np.sum((q - a) * d, axis=-1) / dd, 0.0, 1.0)
    diff = q - (a + t[..., None] * d)
    return np.sqrt(np.sum(diff * diff, axis=-1)), t


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
