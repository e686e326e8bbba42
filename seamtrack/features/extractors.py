"""Joint-feature extractors: find the seam point in a stripe profile.

An extractor is any object with a ``name`` and ``__call__(profile) -> Feature``
(:class:`FeatureExtractor`). It never raises on data: empty, all-invalid, NaN, constant or huge
profiles give a falsy ``Feature.failed(reason)``. :func:`extractor` builds one by name: a
built-in (:data:`BUILTIN`), a ``"package.module:Class"`` string, or an entry point in the
group ``seamtrack.extractors`` (read lazily: a broken plugin never breaks ``import seamtrack``).

The built-ins share one front end, :func:`segment_profile` (split-and-merge), after the robust
clean-up of :mod:`seamtrack.features.robust`: the range step of quantized profiles and a noise
estimate over several lags set the tolerance; isolated spikes and detours (runs off the line on
which the surface continues across them) are left out; the profile is cut at jumps, each run
split by Douglas-Peucker, neighbours that fit one line merged, and each piece refitted by total
least squares on its inliers. The family extractors then pick pieces by geometry (a V opening
towards the sensor, two plates with a gap, a step between parallel sheets, a ridge) and
intersect their lines; a line that ends at a gap ends half a ray spacing beyond its last point
(the edge lies between two rays). Each checks that the profile shows its joint (its model
explains ``min_explained`` of the points, and the family's own tests hold) and refuses with a
reason otherwise; :func:`seamtrack.features.classify.classify` names the family. The two-plate
extractors (square butt, lap; in :mod:`seamtrack.features.plates.extractor`) gather pieces on one
line into a plate however short they are, and read what lies between two plates: a stray line cut
off both (a false reflection) hides the columns it covers, it opens no gap, and where it covers a
plate's edge the edge is estimated under it. The v-groove extractor
(:mod:`seamtrack.features.vgroove.extractor`) reads what lies just beyond each bevel's lower end: a
stray line there hides the root corner, which is then put where the bevel reaches the other corner's
depth below the plates; with no gap showing, the bevels' intersection is the seam. The generic
extractor needs no segmentation: sliding-window slopes, the sharpest turn, two local fits.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import importlib
import importlib.metadata
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Protocol, runtime_checkable

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import PluginError
from seamtrack.features.arrays import FloatArray
from seamtrack.features.base import ExtractorBase, included, line_confidence
from seamtrack.features.expect import Expect
from seamtrack.features.generic.extractor import GenericExtractor
from seamtrack.features.groove.extractor import GrooveExtractor
from seamtrack.features.line_geometry import Line
from seamtrack.features.lines import Segments
from seamtrack.features.plates._two_lines import two_lines_share
from seamtrack.features.plates.extractor import LapExtractor, SquareButtExtractor
from seamtrack.features.refusal import Refusal
from seamtrack.features.vgroove._v_search import (
    COUNT,
    NONE,
    RMS,
    START,
    SearchParams,
    line_of,
    pieces_of,
    search,
)
from seamtrack.features.vgroove.extractor import VGrooveExtractor
from seamtrack.jit import KERNEL
from seamtrack.sensing.profiles import Feature, Profile

ENTRY_POINT_GROUP = "seamtrack.extractors"
#: Coordinates beyond this (mm) are not measurements: treated as invalid.
MAX_ABS_MM = 1e6


@runtime_checkable
class FeatureExtractor(Protocol):
    """Finds the seam point in a profile. ``name`` labels results and benches. An extractor
    may also take the tracker's prior, ``__call__(profile, hint=None)`` (a
    :class:`~seamtrack.sensing.profiles.SeamHint`); one without it is called as before."""

    @property
    def name(self) -> str: ...

    def __call__(self, profile: Profile) -> Feature: ...


# ----------------------------------------------------------------- extractors
@dataclass(frozen=True)
class CornerExtractor(ExtractorBase):
    """The corner families' search: two faces whose lines cross at the seam, opening towards
    the sensor (a fillet) or falling away from it (``opening_down``: an outside corner)."""

    opening_down: ClassVar[bool] = False
    min_angle_deg: float = 45.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 2.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        down = self.opening_down
        lo, hi = self._angles(self.min_angle_deg, self.max_angle_deg)
        fast = _corner(self, profile, seg, down, lo, hi, self.max_gap_mm)
        if fast is not None:
            return fast
        found = self._arms(seg, down, lo, hi, self.max_gap_mm)
        if isinstance(found, Refusal):
            return Feature.failed(found.reason, joint=self.name)
        return _two_faces(self, profile, seg, found)


@dataclass(frozen=True)
class FilletExtractor(CornerExtractor):
    """Fillet / T joint: two faces meeting in a corner that opens towards the sensor.
    Seam: the faces' intersection (the corner line)."""

    name: str = "fillet"


@dataclass(frozen=True)
class OutsideCornerExtractor(CornerExtractor):
    """Outside corner: two faces falling away from a ridge. Seam: their intersection."""

    opening_down: ClassVar[bool] = True
    name: str = "outside-corner"
    max_angle_deg: float = 160.0


class CornerFound(NamedTuple):
    """What :func:`_corner` reads of the V search (:func:`_corner_search`): a pair found, its
    apex, each face's inlier count and rms residual, and the share of the profile the two
    faces explain (NaN when a face has no inliers)."""

    found: bool
    apex_y: float
    apex_z: float
    left_count: int
    right_count: int
    left_rms: float
    right_rms: float
    share: float


@numba.njit(**KERNEL)
def _corner_search(
    points: FloatArray, stray: NDArray[np.bool_], tol: float, pieces: Any, params: SearchParams
) -> CornerFound:  # fmt: skip
    """:func:`~seamtrack.features.vgroove._v_search.search` and what :func:`_corner` reads of it, in
    one call (boxing the search's tables for Python cost about as much as the search)."""
    found = search(points, stray, tol, pieces, params)
    left, right = found.pair.left, found.pair.right
    if left == NONE:
        return CornerFound(False, 0.0, 0.0, 0, 0, 0.0, 0.0, np.nan)
    geo, span, index = found.table.geo, found.table.span, found.table.index
    l_start, l_count = span[left, START], span[left, COUNT]
    r_start, r_count = span[right, START], span[right, COUNT]
    share = np.nan
    if l_count and r_count:
        lo, hi = index[l_start + l_count - 1] + 1, index[r_start]
        share = two_lines_share(
            points, stray, lo, hi, line_of(geo, left), line_of(geo, right), 3.0 * tol
        )
    return CornerFound(True, found.pair.apex_y, found.pair.apex_z, l_count, r_count,
                       geo[left, RMS], geo[right, RMS], share)  # fmt: skip


def _corner(
    ex: ExtractorBase,
    profile: Profile,
    seg: Segments,
    opening_down: bool,
    min_deg: float,
    max_deg: float,
    max_reach_mm: float,
) -> Feature | tuple[Feature, float] | None:
    """:meth:`~.base.ExtractorBase._arms` and :func:`_two_faces` with the same answers, read off the
    search's table as floats: no :class:`~seamtrack.features.lines.Line` built per face
    (array copies), no numpy call on a 2-vector. None where the Python steps must run: an
    expectation to check the included angle against, no pieces, a face without inliers."""
    if isinstance(ex.expect, Expect) or not seg.n_lines:
        return None
    params = ex.search_params(opening_down, min_deg, max_deg, max_reach_mm)
    points = np.ascontiguousarray(seg.points, dtype=np.float64)
    stray = np.asarray(seg.stray, dtype=np.bool_)
    found, apex_y, apex_z, l_count, r_count, l_rms, r_rms, share = _corner_search(
        points, stray, float(seg.tol), pieces_of(seg), params
    )
    if not found:
        return Feature.failed("no pair of lines forms the joint", joint=ex.name)
    if not (l_count and r_count):
        return None
    # line_confidence's arithmetic on the faces' counts and rms
    explained = (l_count + r_count) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(l_rms, r_rms) / seg.tol)
    confidence = min(max(float(0.5 * explained + 0.5 * fit), 0.0), 1.0)  # NaN stays NaN
    return ex._found(profile, np.array([apex_y, apex_z]), confidence=confidence), share


def _two_faces(
    ex: ExtractorBase, profile: Profile, seg: Segments, found: tuple[Line, Line, FloatArray, float]
) -> Feature | tuple[Feature, float]:
    """A corner's feature from its faces (left, right, apex, score), and the share of the
    profile the model of a corner explains: each face runs on to the profile's end; the
    corner between the faces' last points is left out (:func:`~.base.explained`, here in one
    compiled call, :func:`seamtrack.features.plates._two_lines.two_lines_share`)."""
    left, right, apex, _ = found
    if isinstance(ex.expect, Expect):  # the included angle matters only against an expectation
        wrong = ex._implausible(angle=included(left, right, apex))
        if wrong is not None:
            return wrong
    feature = ex._found(profile, apex, confidence=line_confidence([left, right], seg))
    a = (*left.centroid.tolist(), *left.direction.tolist())  # cy, cz, dy, dz
    b = (*right.centroid.tolist(), *right.direction.tolist())
    lo, hi = int(left.index[-1]) + 1, int(right.index[0])
    share = two_lines_share(seg.points, seg.stray, lo, hi, a, b, 3.0 * seg.tol)
    return feature, share


# ----------------------------------------------------------------- registry
BUILTIN: dict[str, Callable[..., FeatureExtractor]] = {
    "v-groove": VGrooveExtractor,
    "square-butt": SquareButtExtractor,
    "fillet": FilletExtractor,
    "lap": LapExtractor,
    "outside-corner": OutsideCornerExtractor,
    "generic": GenericExtractor,
    "groove": GrooveExtractor,
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
        ``"outside-corner"``, ``"generic"``, ``"groove"``: the 7 points of an empty or
        partly filled groove, :mod:`seamtrack.features.groove.extractor`),
        ``"package.module:Class"``, or the name of an entry point in the group
        ``seamtrack.extractors``. A class is called with ``params``; an object that already is
        an extractor is used as is.

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
