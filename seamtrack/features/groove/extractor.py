"""The groove extractor: the 7 points of an empty or partly filled groove (issue 25).

Multi-pass welding describes a groove by 7 points, in order: the left top corner, the left
bottom corner, three bottom points (left, middle, right) on the fill surface, the right bottom
corner and the right top corner. From the second pass on the sensor sees the beads of the passes
before, and a torch aims at a wall's foot or at the middle of the fill surface, not at a root.

The model, on the pieces of the shared front end (:func:`seamtrack.features.lines.segment_profile`:
spikes and reflection streaks left out, straight pieces by split-and-merge):

* **plates**: the outermost pieces at least ``min_plate_mm`` long, each with the pieces on its
  line that follow it inwards (or on whose line it lies: a quantized plate's short outer
  step) and the points no piece took on its line after them (its last step), refitted as one
  line; the two must run within ``max_plate_deg`` of each other. Their mean direction is
  the groove's width axis u (left to right), its normal v points into the groove.
* **walls**: of the pieces between the plates that go down into the groove at least ``wall_deg``
  off the plates and whose line passes within 1 mm of the plate's inner end, the one whose line
  carries most points, refitted with the pieces on its line and trimmed to the points within two
  tolerances of it (a root radius's round at its foot left out). A piece more than 3 mm below the
  corner, and not carrying on a run of wall pieces from it (a wall split into pieces), must stand
  75 deg off the plates, be 1 mm long and have no more points outwards of it, deeper than a
  millimetre below the corner, than on it (a bead's flank or a spike streak pointing at the corner
  by chance, with the fill's flank outwards of it, is no wall). A wall nearly along the rays (a
  narrow gap's), or in the shadow of its plate's edge, shows no points: then there is none.
* **top corners**: a plate's line meets its wall's line; with no wall seen, the plate's end
  (half a spacing beyond its last point).
* **fill surface**: the groove's points inside the walls and off their lines (by five times the
  wall's rms, at least 0.06 mm and at most two tolerances: a bead's flank running down into the
  notch at the wall stays surface; below where a wall was seen, on its line too; 3 mm below, either
  side), less what a running median over 0.6 mm leaves out and the islands (runs between jumps off
  the surface carried across them, at an end at a slope of at most 1, and again without the islands
  found: spike runs, streaks where a dropout took the surface), the largest stretch without a 2 mm
  break (2.5 mm towards a side with no wall seen: a shadow in a crowned fill).
* **bottom corners**: where the fill surface rises from its deepest part into the wall (a U's
  round, bare or partly filled; a bead's toe on it, a notch read at its tip), the wall's line at
  that part's level (the virtual sharp corner of an empty U). Else a line through the most surface
  points within 1.5 mm of the surface's end (lines through pairs of points: spike scraps do not
  move it) crossed with the wall's line, when that lies within 1.5 mm of the surface's outermost
  point on the line and within 3 mm (or half the wall's seen length) of the wall's points, or
  within 1 mm of the wall's deepest point and not above it (a bead's toe lost in the notch at the
  wall); else that point (half a spacing beyond it). A wall hidden in its plate's shadow is the
  seen one mirrored through its own top corner (bevels are cut alike), when the fill stays inside
  that line; so is one seen over less than 3 mm and a quarter of the other's seen length, ending
  more than 3 mm above the fill (a scrap at its top edge says little of its direction), and of two
  walls 2 deg off each other's mirror the one seen over less than 3/4 of the other's length. A
  hidden wall's round is read finer (its rise over 0.2 mm, from the surface's raw end: a bead's toe
  on the round is all there is of the wall's foot). With a hidden wall, or one seen only far above
  the fill, the corner no ray lights is its line crossed with the surface's line (over its last 0.6
  mm; 1.5 mm under a wall seen far above) where that lies at most 1 mm beyond the surface's
  outermost point on the line. Else, and with no wall seen on a side (buried, or along the rays),
  the surface's outermost point on its line over its last 0.6 mm, carried as far as the rays of the
  points near that line reach (a spike moves a point along its ray: its column still lit the
  surface). With no surface at all (an empty V without a gap), the walls' intersection. A wall no
  piece covers (a quantized wall's staircase) is fitted to the points between the plate's last
  piece and the groove's first.
* **bottom points**: the fill surface between the bottom corners at a quarter, half and three
  quarters of the way across (along u), each a local robust line fit of the surface points
  there, in v; where no surface shows there (an open root), on the line joining the corners.
* **remaining area**: the polygon of the top corners, the bottom corners and the surface
  between them, below the line joining the top corners (mm^2, ``Feature.area_mm2``), signed:
  metal above that line counts against it (about 0 for a nearly full groove, negative under a
  cap).
* **crowned and nearly full grooves**: where the fill rises above the line of the plates' ends (a
  cap, or the last fill layer's crowns), the walls are buried: the top corners are where the
  plates' lines end, the bottom corners the fill surface's outermost points there, and the bottom
  points on the fill surface between them, however convex. Such a raised part is taken for a fill
  when it stands at most ``max_crown_mm`` above the plates' ends and no piece of it a millimetre
  long stands more than 80 deg off the plates as a step between two levels (a spike streak standing
  out of a cap the surface runs on across is none); else a block.

The seam point is chosen by ``reference``: ``"centre"`` the middle bottom point, ``"left"`` /
``"right"`` that bottom corner (the wall's foot at the fill surface). ``edges_laser`` holds the
7 points, (7, 2). Refused, with the reason, when no plate shows on a side, the plates are not
parallel (a fillet, a corner), nothing lies ``min_depth_mm`` below the plates between them
(a flat plate, a lap) or a raised part that is no fill stands there (a block), or the model
explains less than ``min_explained`` of the profile.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import PluginError
from seamtrack.features.arrays import FloatArray, IndexArray
from seamtrack.features.base import ExtractorBase
from seamtrack.features.groove._groove_fit import (  # noqa: F401 (RAY_*: the extractor's names)
    RAY_DEPTH_MM,
    RAY_SPREAD_RAD,
    along_a_ray,
    angle_deg,
    bottom_points,
    contiguous,
    count_outwards,
    cross_uv,
    drop_islands,
    explained_share,
    median_of,
    mirrored_walls,
    on_line,
    polygon_area,
    ray_reach,
    robust_uv_fit,
    short_walls,
    stretched,
    surface_v_at,
    trim_wall,
)
from seamtrack.features.groove._groove_kernels import running_median
from seamtrack.features.groove._groove_rise import a_step, risen_level
from seamtrack.features.line_geometry import Line, fit_line
from seamtrack.features.lines import Segments, intersect, segment_profile
from seamtrack.features.refusal import Refusal
from seamtrack.geometry.groove_points import LEFT_FOOT, POINT_INDEX, RIGHT_FOOT
from seamtrack.sensing.profiles import Feature, Profile

REFERENCES = ("centre", "left", "right")

# The model's thresholds (the module docstring says where each applies; mm unless named).
#: A raised part: more than this share of the points between the plates above their ends.
RAISED_SHARE = 0.2
#: A cap's height is that of this percentile of its points (spikes do not count).
CROWN_PERCENTILE = 95
#: A piece of a raised part this far off the plates (deg) is no level (``a_step``'s mask).
LEVEL_DEG = 60.0
#: A piece of a raised part at least this long and this far off the plates (deg) is a step.
STEP_MIN_MM, STEP_DEG = 1.0, 80.0
#: Pieces within this angle (deg) run on one line (a plate's, a wall's run of pieces).
ON_LINE_DEG = 5.0
#: Points within this many tolerances lie on a line (a plate's pieces, a wall's support, the
#: fill surface's band off a wall).
BAND_TOLS = 2.0
#: A wall piece's shortest extent.
WALL_MIN_MM = 0.3
#: Wall pieces whose ends lie within max(this, this many spacings) carry on one wall.
WALL_JOIN_MM, WALL_JOIN_SPACINGS = 1.0, 5.0
#: A wall's line passes within max(this, this many tolerances) of the plate's inner end.
WALL_TOP_MM, WALL_TOP_TOLS = 1.0, 3
#: A wall piece farther than this below the corner must stand ``WALL_FAR_DEG`` off the plates
#: and be ``WALL_FAR_MIN_MM`` long; surface this far below a seen wall is surface either side.
WALL_FAR_MM = 3.0
WALL_FAR_DEG, WALL_FAR_MIN_MM = 75.0, 1.0
#: Points deeper than this below the corner, outwards of a wall piece, count against it.
WALL_BELOW_MM = 1.0
#: A bare wall's (no piece covers it) rms at most max(this many tolerances, spacings).
BARE_RMS_TOLS, BARE_RMS_SPACINGS = 3.0, 0.5
#: A top corner farther than max(this, this many reaches) from the plate's end is none.
TOP_FAR_MM, TOP_FAR_REACHES = 3.0, 10
#: A corner's reach: this many spacings (and a tolerance).
TOP_REACH_SPACINGS = 3.0
#: Bottom corners crossed by more than max(tolerance, this many spacings): the walls cross.
CROSSED_SPACINGS = 2
#: The fill surface's band off a wall: this many wall rms, at least this (mm).
FLOOR_BAND_RMS, FLOOR_BAND_MM = 5.0, 0.06
#: The fill surface's running median: over this width, of this many points at the least and
#: the most; it keeps points within max(this many tolerances, this mm).
MEDIAN_MM, MEDIAN_MIN, MEDIAN_MAX = 0.6, 5, 101
MEDIAN_TOLS, MEDIAN_FLOOR_MM = 3.0, 0.2
#: The fill surface's largest stretch has no break wider than this; towards a side with no
#: wall seen, a break up to ``SHADOW_MM`` is a shadow.
BREAK_MM, SHADOW_MM = 2.0, 2.5
#: The surface's line for a bottom corner: fitted over its first this-many mm from the wall;
#: a crossing within this of the surface's outermost point is the corner.
SURFACE_END_MM = 1.5
#: Points within this many tolerances of the surface's line are on it.
ON_SURFACE_TOLS = 3.0
#: A wall seen farther above the fill than max(``WALL_FAR_MM``, this share of its length).
FAR_SHARE = 0.5
#: The surface's line near a hidden wall: over its last this-many mm.
SURFACE_LINE_MM = 0.6
#: The corner no ray lights: a wall's line crossing the surface's line at most ``UNLIT_MM``
#: beyond its outermost point (``UNLIT_BACK_MM`` before it) and within ``UNLIT_MM`` of it.
UNLIT_MM, UNLIT_BACK_MM = 1.0, 0.05
#: A bead's toe lost in the notch at a wall: a crossing within this of the wall's foot, at
#: most ``NOTCH_ABOVE_MM`` above it.
NOTCH_MM, NOTCH_ABOVE_MM = 1.0, 0.5


class Plates(NamedTuple):
    """The two plates' lines and the last (first) piece of each, by position in the pieces."""

    left: Line
    right: Line
    left_last: int
    right_first: int


class Wall(NamedTuple):
    """A wall: its line (None: no wall seen) and its first and last piece."""

    line: Line | None
    first: int
    last: int


class GrooveFit(NamedTuple):
    """The model's answer: the 7 points (7, 2) in the laser frame, the remaining area (mm^2),
    the share of the profile it explains, and the worst line fit (mm rms)."""

    points: FloatArray
    area_mm2: float
    explained: float
    rms: float


def _fit(points: FloatArray, index: IndexArray) -> Line:
    return Line.from_fit(np.asarray(index), fit_line(points, np.asarray(index, dtype=np.int64)))


@dataclass(frozen=True)
class GrooveExtractor(ExtractorBase):
    """Groove (issue 25): the 7 points of an empty or partly filled groove (V, narrow gap,
    U; 0..n layers of beads), the remaining area, and a seam point per ``reference``
    (``"centre"``: the middle bottom point; ``"left"`` / ``"right"``: that wall's foot at the
    fill surface). The model and its refusals: :mod:`seamtrack.features.groove.extractor`."""

    name: str = "groove"
    reference: str = "centre"
    min_plate_mm: float = 1.0
    max_plate_deg: float = 15.0
    wall_deg: float = 35.0
    min_depth_mm: float = 0.5
    max_crown_mm: float = 5.0
    max_lines: int = 256

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.reference not in REFERENCES:
            raise PluginError(
                f"unknown groove reference {self.reference!r}",
                field="extractor.reference",
                fix=f"use one of {', '.join(REFERENCES)}",
            )

    def segments(self, profile: Profile) -> Segments | Refusal:
        """The front end's pieces, up to ``max_lines`` of them (beads are curved: a clean
        profile of a few caps needs more pieces than the other families' joints)."""
        return segment_profile(
            profile,
            min_tol_mm=self.min_tol_mm,
            resolution_mm=self.resolution_mm,
            min_points=self.min_points,
            max_lines=self.max_lines,
        )

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        found = self.model(seg)
        if isinstance(found, Refusal):
            return Feature.failed(found.reason, joint=self.name)
        pts = found.points
        point = pts[POINT_INDEX[self.reference]]
        rms = max(0.0, 1.0 - found.rms / max(seg.tol, 1e-12))
        feature = self._found(
            profile,
            point.copy(),
            confidence=float(min(max(0.5 * found.explained + 0.5 * rms, 0.0), 1.0)),
            edges_laser=pts,
            area_mm2=found.area_mm2,
            gap_mm=float(np.hypot(*(pts[RIGHT_FOOT] - pts[LEFT_FOOT]))),
        )
        return feature, found.explained

    # ------------------------------------------------------------------ the model
    def model(self, seg: Segments) -> GrooveFit | Refusal:
        """The groove's 7 points, area and fit, or why the profile shows no groove."""
        P = seg.points
        plates = self._plates(seg)
        if isinstance(plates, Refusal):
            return plates
        pl, pr = plates.left, plates.right
        u = pl.direction + pr.direction
        u = u / math.hypot(*u)
        v = np.array([-u[1], u[0]])
        end_l = pl.end(True)
        end_r = pr.end(False)
        lo, hi = int(pl.index[-1]) + 1, int(pr.index[0])
        inner = np.arange(lo, hi)
        inner = inner[~seg.stray[inner]]
        # Depth below the line joining the plates' ends (positive into the groove).
        chord_u = (end_r - end_l) / max(math.hypot(*(end_r - end_l)), 1e-12)
        chord_v = np.array([-chord_u[1], chord_u[0]])
        depth = (P[inner] - end_l) @ chord_v
        below = np.count_nonzero(depth > self.min_depth_mm) >= self.min_points
        raised = np.count_nonzero(depth < -self.min_depth_mm) > RAISED_SHARE * len(inner)
        if not below and not raised:
            return Refusal("not a groove: nothing lies below the plates between them")
        if raised:  # a crowned fill (a cap over the plates), or a block
            why = self._raised(seg, plates, inner, depth, end_r - end_l)
            if why is not None:
                return why
        groove = list(range(plates.left_last + 1, plates.right_first))
        left = self._wall(seg, groove, v, True, end_l)
        right = self._wall(seg, groove[::-1], v, False, end_r)
        reach = TOP_REACH_SPACINGS * seg.spacing + seg.tol
        tl = self._top(pl, left.line, True, reach)
        tr = self._top(pr, right.line, False, reach)
        fu, fv = self._floor(seg, inner, (left, right), u, v)
        if len(fu) < 3:
            if left.line is None or right.line is None:
                return Refusal("not a groove: no bottom between the walls")
            x = intersect(left.line, right.line)  # an empty V: the walls meet
            if x is None:
                return Refusal("not a groove: no bottom between the walls")
            bl = br = x
        else:
            seen = short_walls((left.line, right.line), fv, v)
            wl, wr = mirrored_walls(seen, (tl, tr), fu, fv, u, v)
            wl = left.line if wl is None else wl
            wr = right.line if wr is None else wr
            bl = self._corner(seg, wl, fu, fv, u, v, True, P[lo:hi])
            br = self._corner(seg, wr, fu, fv, u, v, False, P[lo:hi])
        if (br - bl) @ u < -max(seg.tol, CROSSED_SPACINGS * seg.spacing):
            return Refusal("not a groove: its walls cross (a ridge?)")
        bottom = bottom_points(seg, fu, fv, bl, br, u, v)
        pts = np.vstack([tl, bl, bottom, br, tr])
        if along_a_ray(pts[1:6]):
            return Refusal("not a groove: its bottom lies along one laser ray (a spike streak)")
        area = polygon_area(pts, P, inner, u)
        rms = max(pl.rms, pr.rms, *(w.line.rms for w in (left, right) if w.line is not None))
        walls = (left.line, right.line)
        explained = explained_share(seg, (pl, pr), walls, inner, bl, br, u)
        return GrooveFit(pts, area, explained, rms)

    def _raised(
        self, seg: Segments, plates: Plates, inner: IndexArray, depth: FloatArray, chord: FloatArray
    ) -> Refusal | None:
        """Why a part raised between the plates is no crowned fill (None when it is one): a
        fill's cap stands at most ``max_crown_mm`` above the line of the plates' ends (the
        95th percentile of its points: spikes do not count), and no piece of it a millimetre
        long stands more than 80 deg off the plates as a step (a block's side: ``a_step``)."""
        why = Refusal("not a groove: a raised part stands between the plates")
        if (
            len(inner) < self.min_points
            or float(np.percentile(-depth, CROWN_PERCENTILE)) > self.max_crown_mm
        ):
            return why
        P = seg.points
        along = chord / max(math.hypot(*chord), 1e-12)
        normal = np.array([-along[1], along[0]])
        start = P[int(plates.left.index[-1])]
        steep, mask = [], np.zeros(len(P), dtype=bool)  # (mask: pieces 60 deg off, no level)
        for j in range(plates.left_last + 1, plates.right_first):
            ln = seg.lines[j]
            off = angle_deg(ln.direction, along)
            mask[ln.index] = off > LEVEL_DEG
            raised = float((ln.centroid - start) @ normal) <= -self.min_depth_mm
            if ln.extent >= STEP_MIN_MM and raised and off > STEP_DEG:
                steep.append(ln.index)
        if any(a_step(P, index, normal, mask) for index in steep):
            return why
        return None

    def _plates(self, seg: Segments) -> Plates | Refusal:
        lines = seg.lines
        long = [j for j, ln in enumerate(lines) if ln.extent >= self.min_plate_mm]
        if len(long) < 2:
            return Refusal("not a groove: no plate on both sides")
        a, b = long[0], long[-1]
        la, lb = self._grow(seg, a, +1, b), self._grow(seg, b, -1, a)
        if la[1] >= lb[1]:
            return Refusal("not a groove: no plate on both sides")
        left, right = la[0], lb[0]
        apart = angle_deg(left.direction, right.direction)
        if apart > self.max_plate_deg:
            return Refusal(
                f"not a groove: the plates beside it are {apart:.0f} deg apart "
                f"(at most {self.max_plate_deg:.0f}: a fillet or a corner?)"
            )
        left = stretched(seg, left, seg.lines[la[1] + 1].index[0], +1)
        right = stretched(seg, right, seg.lines[lb[1] - 1].index[-1], -1)
        return Plates(left, right, la[1], lb[1])

    def _grow(self, seg: Segments, j: int, step: int, stop: int) -> tuple[Line, int]:
        """The plate starting at piece ``j``: the pieces on its line that follow it towards
        ``stop`` (within 5 deg, their points within two tolerances), refitted."""
        lines = seg.lines
        base = lines[j]
        index = [base.index]
        k = j
        while k + step != stop:
            nxt = lines[k + step]
            if angle_deg(nxt.direction, base.direction) > ON_LINE_DEG:
                break
            off = np.abs((seg.points[nxt.index] - base.centroid) @ base.normal)
            # (or the plate so far on the next piece's line: a short outer piece, one step
            # of a quantized plate at a tilt, is flatter than the plate)
            back = np.abs((seg.points[base.index] - nxt.centroid) @ nxt.normal)
            if median_of(off) > BAND_TOLS * seg.tol and median_of(back) > BAND_TOLS * seg.tol:
                break
            index.append(nxt.index)
            k += step
            # The plate so far (a quantized plate at a tilt is a staircase of flat pieces).
            base = _fit(seg.points, np.sort(np.concatenate(index)))
        idx = np.sort(np.concatenate(index))
        line = _fit(seg.points, idx) if len(index) > 1 else base
        if line.direction[0] < 0:  # along increasing column (y)
            line = line.flipped()
        return line, k

    def _wall(
        self, seg: Segments, groove: list[int], v: FloatArray, from_left: bool, top: FloatArray
    ) -> Wall:
        """A wall: of the pieces between the plates (``groove``, from this plate inwards) that
        go down into the groove at least ``wall_deg`` off the plates and whose line passes
        within a millimetre of the plate's inner end (``top``), the one whose line carries
        most of the groove's points (a scrap at a rounded edge carries few); refitted on the
        pieces on its line."""
        lines = seg.lines
        P = seg.points
        if not groove:
            return Wall(None, -1, -1)
        lo = min(int(lines[groove[0]].index[0]), int(lines[groove[-1]].index[0]))
        hi = max(int(lines[groove[0]].index[-1]), int(lines[groove[-1]].index[-1])) + 1
        q = P[lo:hi][~seg.stray[lo:hi]]
        best, support = None, self.min_points - 1
        vy, vz = float(v[0]), float(v[1])
        sign = 1.0 if from_left else -1.0  # inwards from the plate
        # The run of wall pieces before j (a wall split into pieces, its top one short): how
        # far its top lies from the corner, its lower end, its direction.
        run_top, run_end, run_dir = math.inf, None, None
        join = max(WALL_JOIN_MM, WALL_JOIN_SPACINGS * seg.spacing)
        for j in groove:
            ln = lines[j]
            _, _, uy, uz, _, _ = ln.scalars  # floats: no numpy call a piece
            dv = sign * (uy * vy + uz * vz)
            off = math.degrees(math.asin(min(1.0, abs(dv))))
            if not (dv > 0 and off >= self.wall_deg and ln.extent >= WALL_MIN_MM):
                run_end = None
                continue
            upper = P[ln.index[0] if from_left else ln.index[-1]]
            near_top = math.hypot(*(upper - top))
            if (
                run_end is not None
                and run_dir is not None
                and math.hypot(*(upper - run_end)) <= join
                and angle_deg(ln.direction, run_dir) <= ON_LINE_DEG
            ):
                near_top = min(near_top, run_top)  # it carries on a wall from the corner
            run_top, run_dir = near_top, ln.direction
            run_end = P[ln.index[-1] if from_left else ln.index[0]]
            if abs(float((top - ln.centroid) @ ln.normal)) > max(
                WALL_TOP_MM, WALL_TOP_TOLS * seg.tol
            ):
                continue
            if near_top > WALL_FAR_MM and (off < WALL_FAR_DEG or ln.extent < WALL_FAR_MIN_MM):
                continue  # a bead's flank or a streak pointing at the corner by chance
            n = int(np.count_nonzero(np.abs((q - ln.centroid) @ ln.normal) <= BAND_TOLS * seg.tol))
            below = float(top @ v) + WALL_BELOW_MM  # (a streak deep in the groove: fill outwards)
            if near_top > WALL_FAR_MM and count_outwards(q, ln, v, from_left, seg.tol, below) > max(
                self.min_points, n
            ):
                continue  # the surface goes on beyond it: a streak in the groove, no wall
            if n > support:
                best, support = j, n
        if best is None:
            return self._bare_wall(seg, groove[0], v, from_left, top)
        ref = lines[best]
        on = [j for j in groove if on_line(seg, ref, lines[j])]
        index = [lines[j].index for j in on]
        line = _fit(P, np.sort(np.concatenate(index))) if len(index) > 1 else ref
        line = trim_wall(P, line, seg.tol)  # a round at its foot, a spike's points: left out
        if line.direction[0] < 0:
            line = line.flipped()
        return Wall(line, on[0], on[-1])

    def _bare_wall(
        self, seg: Segments, first: int, v: FloatArray, from_left: bool, top: FloatArray
    ) -> Wall:
        """A wall no piece covers (a quantized wall's staircase, too jagged for the pieces'
        tolerance): the points between the plate's last piece and the groove's first, when
        they run at least a millimetre down into the groove ``wall_deg`` off the plates from
        the plate's end (``top``)."""
        lines = seg.lines
        if from_left:
            lo, hi = int(lines[first - 1].index[-1]) + 1, int(lines[first].index[0])
        else:
            lo, hi = int(lines[first].index[-1]) + 1, int(lines[first + 1].index[0])
        index = np.arange(lo, hi)
        index = index[~seg.stray[index]]
        if len(index) < self.min_points:
            return Wall(None, -1, -1)
        line = _fit(seg.points, index)
        if line.direction[0] < 0:
            line = line.flipped()
        d = line.direction if from_left else -line.direction
        off = math.degrees(math.asin(min(1.0, abs(float(d @ v)))))
        near = abs(float((top - line.centroid) @ line.normal)) <= max(
            WALL_TOP_MM, WALL_TOP_TOLS * seg.tol
        )
        # from the plate's end: a spike streak deep in a narrow gap, along a ray nearly as
        # steep as its wall, is none
        near &= float(np.min(np.hypot(*(seg.points[index] - top).T))) <= WALL_FAR_MM
        if (
            float(d @ v) <= 0
            or off < self.wall_deg
            or line.extent < WALL_FAR_MIN_MM
            or not near
            or line.rms > max(BARE_RMS_TOLS * seg.tol, BARE_RMS_SPACINGS * seg.spacing)
        ):
            return Wall(None, -1, -1)
        return Wall(line, first, first)

    @staticmethod
    def _top(plate: Line, wall: Line | None, left: bool, reach: float) -> FloatArray:
        end = plate.end(left)
        if wall is None:
            return end
        x = intersect(plate, wall)
        if x is None or math.hypot(*(x - end)) > max(TOP_FAR_MM, TOP_FAR_REACHES * reach):
            return end
        return x

    def _floor(
        self,
        seg: Segments,
        inner: IndexArray,
        walls: tuple[Wall, Wall],
        u: FloatArray,
        v: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """The fill surface's points as (u, v), sorted by u: the groove's points inside the walls
        and off their lines, less what a running median over 0.6 mm leaves out (spike runs)."""
        q = seg.points[inner]
        keep = np.ones(len(q), dtype=bool)
        for w, left in zip(walls, (True, False), strict=True):
            if w.line is None:
                continue
            n = w.line.normal if (w.line.normal @ u > 0) == left else -w.line.normal
            # Off the wall, inwards; below where it was seen, on its line too (a round's
            # upper part, at a U's foot), and more than 3 mm below, either side (a wall
            # carried down from its top, a narrow gap's, cuts no surface short).
            low = float(np.max(seg.points[w.line.index] @ v)) if len(w.line.index) else np.inf
            off, qv_ = (q - w.line.centroid) @ n, q @ v
            band = min(BAND_TOLS * seg.tol, max(FLOOR_BAND_RMS * w.line.rms, FLOOR_BAND_MM))
            keep &= (
                (off > band)
                | ((qv_ > low + BAND_TOLS * seg.tol) & (off > -BAND_TOLS * seg.tol))
                | (qv_ > low + WALL_FAR_MM)
            )
        qu, qv = q[keep] @ u, q[keep] @ v
        run = (np.searchsorted(seg.runs, inner, side="right") - 1)[keep]
        order = np.argsort(qu, kind="stable")
        qu, qv, run = qu[order], qv[order], run[order]
        k = int(min(MEDIAN_MAX, max(MEDIAN_MIN, round(MEDIAN_MM / max(seg.spacing, 1e-9)))) | 1)
        if len(qv) >= k:
            med = running_median(contiguous(qv), k)  # the ends: their whole window's
            ok = np.abs(qv - med) <= max(MEDIAN_TOLS * seg.tol, MEDIAN_FLOOR_MM)
            qu, qv, run = qu[ok], qv[ok], run[ok]
        ok = drop_islands(qu, qv, run, seg.spacing, seg.tol)  # spike runs the median kept
        qu, qv = qu[ok], qv[ok]
        if len(qu) > 1:  # the largest stretch without a break of 2 mm (scraps at the top edges)
            cut = np.flatnonzero(np.diff(qu) > BREAK_MM) + 1
            bounds = np.concatenate(([0], cut, [len(qu)]))
            j = int(np.argmax(np.diff(bounds)))
            a, b = j, j + 1
            # Towards a side with no wall seen (buried under a crowned fill) a break of up to
            # 2.5 mm is a shadow in the fill surface, not a scrap: the surface goes on.
            while (
                walls[0].line is None and a > 0 and qu[bounds[a]] - qu[bounds[a] - 1] <= SHADOW_MM
            ):
                a -= 1
            while (
                walls[1].line is None
                and b < len(bounds) - 1
                and qu[bounds[b]] - qu[bounds[b] - 1] <= SHADOW_MM
            ):
                b += 1
            qu, qv = qu[bounds[a] : bounds[b]], qv[bounds[a] : bounds[b]]
        return qu, qv

    def _corner(
        self,
        seg: Segments,
        wall: Line | None,
        fu: FloatArray,
        fv: FloatArray,
        u: FloatArray,
        v: FloatArray,
        left: bool,
        columns: FloatArray | None = None,
    ) -> FloatArray:
        """Where the fill surface meets the wall (the module docstring): the wall's line at
        the level of a fill that rises into it; the wall's line crossed with a line fitted to
        the surface's first 1.5 mm from the wall; with no wall seen (``columns``: the points
        whose rays may carry the surface on), a crossing farther than 1.5 mm from the
        surface's outermost point or a wall seen only far above, that point (half a spacing
        beyond it)."""
        sign = 1.0 if left else -1.0
        edge = float(fu[0] if left else fu[-1])
        unseen = wall is None or not len(wall.index)  # no wall seen, or a hidden one's mirror
        if wall is not None:
            risen = _risen_corner(seg, wall, fu, fv, u, v, left)
            if risen is not None:  # a round into the wall: the wall's line at the fill's level
                return risen
        if wall is None and columns is None:  # the surface's outermost point
            return _inside(seg, edge, float(fv[0] if left else fv[-1]), u, v, sign)
        sel = sign * (fu - edge) <= SURFACE_END_MM
        su, sv = fu[sel], fv[sel]
        fit = robust_uv_fit(su, sv, seg.tol)
        if fit is not None:  # the surface's outermost point on its line (not a spike's)
            ou, ov = _outermost(su, sv, _on_surface(su, sv, fit, seg.tol), sign)
        else:
            i = 0 if left else len(fu) - 1
            ou, ov = float(fu[i]), float(fv[i])
        cross = None if wall is None or fit is None else cross_uv(wall, fit[0], fit[1], u, v)
        # A wall seen only far above the fill (more than 3 mm, and half its seen length) or a
        # hidden one's mirror is carried too far down to place the corner: then it is the
        # surface's, as for no wall seen.
        mirror = far = None
        if wall is not None and not len(wall.index):
            mirror = wall
            wall = cross = None  # a mirror: the wall is hidden
        elif wall is not None and cross is not None and _far_above(seg, wall, cross, u, v):
            far = wall
            cross, columns = None, None  # below a wall, rays may light it unseen
        if wall is None or cross is None:  # the surface's outermost point
            line = far if far is not None else mirror
            end = _SurfaceEnd(edge, left, unseen, fit, ou, ov)
            return _surface_end(seg, fu, fv, u, v, end, line, columns)
        if math.hypot(cross[0] - ou, cross[1] - ov) <= SURFACE_END_MM:
            return np.asarray(cross[0] * u + cross[1] * v)
        notch = _notch_corner(seg, wall, cross, u, v)
        if notch is not None:
            return notch
        return _inside(seg, ou, ov, u, v, sign)


def _inside(
    seg: Segments, ou: float, ov: float, u: FloatArray, v: FloatArray, sign: float
) -> FloatArray:
    """The surface's outermost point (``ou``, ``ov``) moved half a spacing outwards
    (``sign``: +1 on the left)."""
    return np.asarray((ou - sign * 0.5 * seg.spacing) * u + ov * v)


def _risen_corner(
    seg: Segments, wall: Line, fu: FloatArray, fv: FloatArray, u: FloatArray, v: FloatArray,
    left: bool,
) -> FloatArray | None:  # fmt: skip
    """The wall's line at the level of a fill that rises into it in a round (None: no rise,
    or a wall along the surface); a hidden wall's (its mirror's) rise is read finer: the
    round's rise is all there is of its foot."""
    level = risen_level(fu, fv, left, seg.spacing, seg.tol, fine=not len(wall.index))
    if level is None:
        return None
    cu, cv = float(wall.centroid @ u), float(wall.centroid @ v)
    du, dv = float(wall.direction @ u), float(wall.direction @ v)
    if abs(dv) <= 1e-9:
        return None
    t = (level - cv) / dv
    return np.asarray((cu + t * du) * u + level * v)


def _on_surface(
    su: FloatArray, sv: FloatArray, fit: tuple[float, float], tol: float
) -> NDArray[np.bool_]:
    """Which points lie on the surface's line v = a + b u (within ON_SURFACE_TOLS)."""
    a, b = fit
    return np.abs(sv - (a + b * su)) <= ON_SURFACE_TOLS * tol


def _outermost(
    su: FloatArray, sv: FloatArray, on: NDArray[np.bool_], sign: float
) -> tuple[float, float]:
    """(u, v) of the outermost (``sign``: +1 on the left) of the points ``on`` the line."""
    k = int(np.argmin(sign * su[on]))
    return float(su[on][k]), float(sv[on][k])


def _far_above(seg: Segments, wall: Line, cross: FloatArray, u: FloatArray, v: FloatArray) -> bool:
    """Whether the wall is seen only far above its crossing with the fill surface: more than
    WALL_FAR_MM, and FAR_SHARE of its seen length."""
    seen = seg.points[wall.index] @ np.column_stack([u, v])
    gap = float(np.min(np.hypot(*(seen - cross).T)))
    return gap > max(WALL_FAR_MM, FAR_SHARE * float(np.ptp(wall.t)))


class _SurfaceEnd(NamedTuple):
    """The fill surface's end towards a side: the u of its outermost point, the side, whether
    no wall is seen there, its line v = a + b u over the last 1.5 mm (None: none fits) and
    the outermost point on it (u, v)."""

    edge: float
    left: bool
    unseen: bool
    fit: tuple[float, float] | None
    ou: float
    ov: float


def _surface_end(
    seg: Segments, fu: FloatArray, fv: FloatArray, u: FloatArray, v: FloatArray,
    end: _SurfaceEnd, line: Line | None, columns: FloatArray | None,
) -> FloatArray:  # fmt: skip
    """The corner at the surface's outermost point, with no wall to cross: on the surface's
    line over its last 0.6 mm (where no wall is seen; a flank bends further in); where a
    wall's ``line`` (a hidden one's mirror, or one seen far above) crosses the surface's
    line just beyond that point, the crossing (the corner no ray lights); else that point
    carried on the line as far as the rays of ``columns`` reach, half a spacing beyond."""
    sign = 1.0 if end.left else -1.0
    fit, ou, ov = end.fit, end.ou, end.ov
    near = sign * (fu - end.edge) <= SURFACE_LINE_MM  # on its line there
    if end.unseen and (short := robust_uv_fit(fu[near], fv[near], seg.tol)) is not None:
        fit = short
        on = _on_surface(fu[near], fv[near], fit, seg.tol)
        if np.any(on):
            ou, ov = _outermost(fu[near], fv[near], on, sign)
    if line is not None and fit is not None:
        x = cross_uv(line, fit[0], fit[1], u, v)
        if x is not None and -UNLIT_BACK_MM <= sign * (ou - x[0]) <= UNLIT_MM:
            if math.hypot(x[0] - ou, x[1] - ov) <= UNLIT_MM:
                return np.asarray(x[0] * u + x[1] * v)
    if fit is not None and columns is not None:  # on its line, as far as its rays go
        ou = ray_reach(columns, u, v, fit, ou, end.left)
        ov = fit[0] + fit[1] * ou
    return _inside(seg, ou, ov, u, v, sign)


def _notch_corner(
    seg: Segments, wall: Line, cross: FloatArray, u: FloatArray, v: FloatArray
) -> FloatArray | None:
    """The wall's crossing with the surface when the surface's toe is lost in a notch: the
    wall's foot (where its points end) lies on its line within NOTCH_MM of the crossing, not
    more than NOTCH_ABOVE_MM below it (None: no notch)."""
    seen = seg.points[wall.index] @ np.column_stack([u, v])
    foot = seen[int(np.argmax(seen[:, 1]))]
    if math.hypot(*(cross - foot)) <= NOTCH_MM and cross[1] >= foot[1] - NOTCH_ABOVE_MM:
        return np.asarray(cross[0] * u + cross[1] * v)
    return None
