"""The built-in family extractors' base class: shared parameters, the never-raise wrapper,
line groups and the V (or ridge) search.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from seamtrack.features.arrays import FloatArray
from seamtrack.features.expect import Expect, parse_expect
from seamtrack.features.line_geometry import Line
from seamtrack.features.lines import (
    DATA_ERRORS,
    Segments,
    segment_profile,
)
from seamtrack.features.refusal import Refusal
from seamtrack.features.vgroove._v_search import (
    COUNT,
    CY,
    CZ,
    NONE,
    RMS,
    START,
    UY,
    UZ,
    LineTable,
    SearchParams,
    explained_of,
    pieces_of,
    search,
)
from seamtrack.sensing.profiles import Feature, Profile, SeamHint

#: A stretch of kept points ``points[lo:hi]`` and the line(s) a joint's model puts there
#: (None: left out of the count, such as a gap).
Zone = tuple[int, int, Line | tuple[Line, ...] | None]


@dataclass(frozen=True)
class ExtractorBase:
    """Shared parameters and the never-raise wrapper of the built-in extractors."""

    name: str = "base"
    min_tol_mm: float | None = None
    resolution_mm: float | None = None
    min_points: int = 8
    min_arm_mm: float = 0.5
    min_explained: float = 0.8
    #: Also try single pieces of a collinear group as arms (a weldment's web seen on both sides
    #: of a gusset standing on it); off by default: a raised block's base would read as a joint.
    arms_from_pieces: bool = False
    expect: Mapping[str, float] | Expect | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "expect", parse_expect(self.expect, self.name))

    def _angles(self, min_deg: float, max_deg: float) -> tuple[float, float]:
        """The family's included-angle range (deg), narrowed to the expected angle."""
        if not isinstance(self.expect, Expect):
            return min_deg, max_deg
        lo, hi = self.expect.angle_range(math.radians(min_deg), math.radians(max_deg))
        return math.degrees(lo), math.degrees(hi)

    def _implausible(self, **measured: float | None) -> Feature | None:
        """A failure when measured values break the expectation (``angle`` in rad,
        ``depth`` and ``gap`` in mm), else None."""
        if not isinstance(self.expect, Expect):
            return None
        why = self.expect.check(**measured)
        return Feature.failed(f"{self.name}: {why}", joint=self.name) if why else None

    @property
    def uses_hint(self) -> bool:
        """Whether the tracker's prior can change this extractor's answer: it overrides
        :meth:`_extract_hinted` (the v-groove's choice among V's). The loop asks the tracker
        for a hint only for an extractor that uses one (computing it costs ~10 us a frame)."""
        return type(self)._extract_hinted is not ExtractorBase._extract_hinted

    def __call__(self, profile: Profile, hint: SeamHint | None = None) -> Feature:
        """The seam point of ``profile``; ``hint``: the tracker's prior on it
        (:class:`~seamtrack.sensing.profiles.SeamHint`), used by the extractors that choose
        among candidates (the v-groove's V's), ignored by the others."""
        return self.scored(profile, hint=hint)[0]

    def segments(self, profile: Profile) -> Segments | Refusal:
        """The profile's straight pieces with this extractor's front-end parameters."""
        return segment_profile(
            profile,
            min_tol_mm=self.min_tol_mm,
            resolution_mm=self.resolution_mm,
            min_points=self.min_points,
        )

    def scored(
        self,
        profile: Profile,
        seg: Segments | Refusal | None = None,
        hint: SeamHint | None = None,
    ) -> tuple[Feature, float]:
        """The feature and the share of the profile's surface points its joint model explains
        (0 when not found); ``seg``: the profile's pieces when already segmented; ``hint``:
        the tracker's prior (:meth:`_extract_hinted`). Never raises on data."""
        try:
            with np.errstate(all="ignore"):
                if seg is None:
                    seg = self.segments(profile)
                if isinstance(seg, Refusal):
                    return Feature.failed(seg.reason, joint=self.name), 0.0
                if hint is None:
                    found = self._extract(profile, seg)
                else:
                    found = self._extract_hinted(profile, seg, hint)
                if isinstance(found, Feature):
                    return found, 0.0
                feature, share = found
                if share < self.min_explained:
                    return Feature.failed(
                        f"not a {self.name}: its model explains {100 * share:.0f} % of the "
                        f"profile (at least {100 * self.min_explained:.0f} % needed)",
                        joint=self.name,
                    ), share
                return feature, share
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"{self.name}: unusable profile ({exc})", joint=self.name), 0.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        """A failure, or the feature and the share of the profile its model explains."""
        raise NotImplementedError

    def _extract_hinted(
        self, profile: Profile, seg: Segments, hint: SeamHint
    ) -> Feature | tuple[Feature, float]:
        """As :meth:`_extract`, with the tracker's prior; the families that have no choice to
        make ignore it."""
        return self._extract(profile, seg)

    def _found(self, profile: Profile, point: FloatArray, **kw: Any) -> Feature:
        return Feature.found(point, profile.T_world_sensor, joint=self.name, **kw)

    def search_params(
        self, opening_down: bool, min_deg: float, max_deg: float, max_reach_mm: float
    ) -> SearchParams:
        """The V search's parameters for a V (or, ``opening_down``, a ridge) enclosing
        ``min_deg..max_deg`` with arms within ``max_reach_mm`` of the apex, and this
        extractor's arm limits."""
        return _search_params(
            opening_down,
            float(min_deg),
            float(max_deg),
            float(max_reach_mm),
            bool(self.arms_from_pieces),
            int(self.min_points),
            float(self.min_arm_mm),
        )

    def _arms(
        self,
        seg: Segments,
        opening_down: bool,
        min_deg: float,
        max_deg: float,
        max_reach_mm: float,
    ) -> tuple[Line, Line, FloatArray, float] | Refusal:
        """The best pair of lines forming a V (opening towards the sensor, -z) or a ridge
        (``opening_down``: the arms fall away from the sensor): (left, right, apex, score).

        Pairs of collinear groups (:meth:`_groups`; with ``arms_from_pieces`` also the pieces
        in no group) are tried: the apex is their crossing, each arm's direction points from
        the apex to its centroid; the arms must lie either side of the apex, open the right
        way, enclose ``min_deg..max_deg`` and have their bisector within 45 deg of the
        opening. Each arm must come within ``max_reach_mm`` of the apex, and not run on
        through it: a tenth of a group may lie past it (fragments of the root collinear with
        a bevel, a bevel's own piece rounding into the root), none by more than three
        tolerances when that piece also lies ahead. The best pair has the most surface points
        on the arms' lines (within two tolerances), on their sides of the apex (fragments of
        a bevel cut up by spikes count, whatever piece they are in). The arms are returned
        without their inliers more than a tolerance past the apex (refitted). Compiled
        (:func:`seamtrack.features.vgroove._v_search.search`)."""
        if not seg.n_lines:
            return Refusal("no pair of lines forms the joint")
        params = self.search_params(opening_down, min_deg, max_deg, max_reach_mm)
        found = search(
            np.ascontiguousarray(seg.points, dtype=np.float64),
            np.asarray(seg.stray, dtype=np.bool_),
            float(seg.tol),
            pieces_of(seg),
            params,
        )
        pair = found.pair
        if pair.left == NONE:
            return Refusal("no pair of lines forms the joint")
        left, right = _record(seg, found.table, pair.left), _record(seg, found.table, pair.right)
        return left, right, np.array([pair.apex_y, pair.apex_z]), float(pair.score)


@functools.lru_cache(maxsize=64)
def _search_params(
    opening_down: bool,
    min_deg: float,
    max_deg: float,
    max_reach: float,
    pieces_too: bool,
    min_points: int,
    min_arm: float,
) -> SearchParams:
    """The V search's parameters, built once per set of values."""
    sign = 1.0 if opening_down else -1.0
    return SearchParams(sign, min_deg, max_deg, max_reach, pieces_too, min_points, min_arm)


def _record(seg: Segments, tb: LineTable, r: int) -> Line:
    """The line of record ``r`` of a table
    (:class:`seamtrack.features.vgroove._v_search.LineTable`): the piece itself when it is
    one, else a new line."""
    if r < seg.n_lines:
        return seg.line(r)
    a, c = int(tb.span[r, START]), int(tb.span[r, COUNT])
    return Line(
        tb.index[a : a + c].copy(),
        tb.geo[r, CY : CZ + 1].copy(),
        tb.geo[r, UY : UZ + 1].copy(),
        tb.along[a : a + c].copy(),
        float(tb.geo[r, RMS]),
    )


def line_confidence(arms: list[Line], seg: Segments) -> float:
    """Share of the kept points explained by the feature's lines, scaled by their fit."""
    explained = sum(a.count for a in arms) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(a.rms for a in arms) / seg.tol)
    return min(max(float(0.5 * explained + 0.5 * fit), 0.0), 1.0)  # NaN stays NaN


def explained(seg: Segments, zones: list[tuple[int, int, Line | tuple[Line, ...] | None]]) -> float:
    """Share of the profile's surface points (detours left out) that lie within three
    tolerances of a line of their zone: ``(lo, hi, lines)`` spans of kept points
    (``seg.points[lo:hi]``) in column order, each with the line (or lines) the joint's model
    puts there; a zone without a line (a gap, a corner) is left out of the count. Points in
    no zone count as unexplained."""
    if not zones:
        return 0.0
    # The zones' lines as one flat list of floats (centroid, normal): one array built, where
    # numpy calls per line cost more than the count.
    spans: list[int] = []
    groups = []
    width = 1
    for lo, hi, z in zones:
        group = () if z is None else z if isinstance(z, tuple) else (z,)
        spans += (lo, hi, len(group))
        groups.append(group)
        width = max(width, len(group))
    flat: list[float] = []
    for group in groups:
        for ln in group:
            (cy, cz), (dy, dz) = ln.centroid.tolist(), ln.direction.tolist()
            flat += (cy, cz, -dz, dy)
        flat += (0.0,) * (4 * (width - len(group)))
    return float(
        explained_of(
            np.ascontiguousarray(seg.points, dtype=np.float64),
            np.asarray(seg.stray, dtype=np.bool_),
            np.array(spans, dtype=np.int64).reshape(-1, 3),
            np.array(flat, dtype=np.float64).reshape(len(zones), width, 4),
            3.0 * seg.tol,
        )
    )


def included(left: Line, right: Line, apex: FloatArray) -> float:
    """Included angle (rad) of the V or ridge whose arms run from ``apex`` to the lines'
    centroids."""
    (ly, lz), (ry, rz), (ay, az) = left.centroid.tolist(), right.centroid.tolist(), apex.tolist()
    vay, vaz, vby, vbz = ly - ay, lz - az, ry - ay, rz - az  # floats: numpy's calls cost more
    c = (vay * vby + vaz * vbz) / max(math.hypot(vay, vaz) * math.hypot(vby, vbz), 1e-300)
    return math.acos(min(1.0, max(-1.0, c)))
