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
gap ends half a ray spacing beyond its last point (the edge lies between two rays). The generic
extractor needs no segmentation: sliding-window slopes, the sharpest turn, two local fits.

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
    collinear_groups,
    corner_or_end,
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

    def _arms(
        self, seg: Segments, opening_down: bool, min_deg: float, max_deg: float, max_reach_mm: float
    ) -> tuple[Line, Line, FloatArray, float] | str:
        """The best pair of lines forming a V (opening towards the sensor, -z) or a ridge
        (``opening_down``: the arms fall away from the sensor): (left, right, apex, score)."""
        groups = [
            g
            for g in collinear_groups(seg)
            if g.count >= self.min_points and g.extent >= self.min_arm_mm
        ]
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


@dataclass(frozen=True)
class VGrooveExtractor(_Base):
    """V-groove: two bevels opening towards the sensor. Seam: the root centre, midpoint of
    the bevels' lower ends (their intersection when they meet). Edges: the top edges."""

    name: str = "v-groove"
    min_angle_deg: float = 20.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 6.0
    min_gap_mm: float = 0.05

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        found = self._arms(seg, False, self.min_angle_deg, self.max_angle_deg, self.max_gap_mm)
        if isinstance(found, str):
            return Feature.failed(found, joint=self.name)
        left, right, apex, _ = found
        others = [g for g in seg.lines if g.count >= self.min_points] + [left, right]
        # Column order runs left to right: the left bevel's root end is its last point.
        root_l = corner_or_end(left, True, others, seg)
        root_r = corner_or_end(right, False, others, seg)
        gap = float(np.hypot(*(root_r - root_l)))
        if gap <= max(self.min_gap_mm, 2.0 * seg.spacing + seg.tol):
            seam, gap = apex, 0.0
        else:
            seam = 0.5 * (root_l + root_r)
        edges = np.array(
            [corner_or_end(left, False, others, seg), corner_or_end(right, True, others, seg)]
        )
        return self._found(
            profile, seam, confidence=_confidence([left, right], seg), edges_laser=edges, gap_mm=gap
        )


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


def _plates(
    seg: Segments,
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    min_gap_mm: float,
    join_hidden: bool,
) -> list[tuple[Line, bool, bool]]:
    """Pieces in column order as (line, is_plate, hidden_before).

    A plate is within ``max_tilt_deg`` of the y axis and ``min_plate_mm`` long. A plate-like
    piece that continues an earlier one's line is joined to it when what separates them is
    short (< ``min_gap_mm``: a dropout, a removed outlier), or, with ``join_hidden``, when it
    lies only in front of the line (a false reflection hiding the plate). Without
    ``join_hidden`` such a piece starts a new plate flagged ``hidden_before``.
    """
    out: list[list[Any]] = []
    tilt = math.radians(max_tilt_deg)
    for ln in seg.lines:
        if ln.count < min_points:
            continue
        flat = abs(math.atan2(ln.direction[1], ln.direction[0])) <= tilt
        hidden = False
        for last in range(len(out) - 1, -1, -1) if flat else ():
            prev, prev_flat, _ = out[last]
            ends = np.array([ln.point(float(ln.t[0])), ln.point(float(ln.t[-1]))])
            if not prev_flat or np.abs((ends - prev.centroid) @ prev.normal).max() > seg.tol:
                continue
            gap = float(np.hypot(*(ends[0] - prev.point(float(prev.t[-1])))))
            between = seg.points[prev.index[-1] + 1 : ln.index[0]]
            towards_sensor = -1.0 if float(prev.centroid @ prev.normal) > 0 else 1.0
            height = towards_sensor * ((between - prev.centroid) @ prev.normal)
            # In front only (no wall or gap bottom behind the line): a reflection, not a gap.
            hidden = (
                int((height > seg.tol).sum()) >= min_points
                and int((height < -seg.tol).sum()) < min_points
            )
            if gap < min_gap_mm or (hidden and join_hidden):
                idx = np.concatenate([prev.index, ln.index])
                out[last:] = [[_fit(seg.points, idx), True, out[last][2]]]
                ln = None  # type: ignore[assignment]
            break
        if ln is not None:
            out.append([ln, flat, hidden])
    return [(ln, flat and ln.extent >= min_plate_mm, hid) for ln, flat, hid in out]


def _plate_pairs(
    seg: Segments,
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    min_gap_mm: float,
    max_gap_mm: float,
    join_hidden: bool,
) -> list[tuple[Line, Line, bool]]:
    """Consecutive near-parallel plates (left, right, hidden: a reflection lies between)
    whose facing ends are at most ``max_gap_mm`` apart (walls or nothing may lie between)."""
    plates = [
        (ln, hid)
        for ln, plate, hid in _plates(
            seg, min_points, min_plate_mm, max_tilt_deg, min_gap_mm, join_hidden
        )
        if plate
    ]
    return [
        (a, b, hid)
        for (a, _), (b, hid) in itertools.pairwise(plates)
        if _angle(a, b) <= math.radians(10)
        and float(np.hypot(*(b.point(float(b.t[0])) - a.point(float(a.t[-1]))))) <= max_gap_mm
    ]


def _plate_candidates(
    ex: Any, seg: Segments, join_hidden: bool
) -> tuple[list[tuple[Line, Line, bool]], list[Line]]:
    """The plate pairs of a two-plate extractor (square butt, lap), with its own limits, and
    the long pieces that may meet a plate's end."""
    pairs = _plate_pairs(seg, ex.min_points, ex.min_plate_mm, ex.max_tilt_deg, ex.min_gap_mm,
                         ex.max_gap_mm, join_hidden=join_hidden)  # fmt: skip
    return pairs, [ln for ln in seg.lines if ln.count >= ex.min_points]


@dataclass(frozen=True)
class SquareButtExtractor(_Base):
    """Square butt: two plates side by side with a gap and/or a high-low step between them.
    Seam: the midpoint of the two plate edges."""

    name: str = "square-butt"
    min_gap_mm: float = 0.3
    max_gap_mm: float = 6.0
    min_plate_mm: float = 1.0
    max_tilt_deg: float = 40.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        pairs, others = _plate_candidates(self, seg, join_hidden=False)
        best, best_key = None, (False, 0.0)
        for a, b, hidden in pairs:
            ea, eb = corner_or_end(a, True, others, seg), corner_or_end(b, False, others, seg)
            opening = float(np.hypot(*(eb - ea)))
            # An open gap beats one a reflection covers (which may only hide plate).
            key = (not hidden, opening)
            if opening >= max(self.min_gap_mm, 3 * seg.tol) and key > best_key:
                best, best_key = (a, b, ea, eb), key
        if best is None:
            return Feature.failed("no gap or step between two plates", joint=self.name)
        a, b, ea, eb = best
        gap = abs(float((eb - ea) @ a.direction))
        conf = _confidence([a, b], seg) * (1.0 if best_key[0] else 0.5)
        return self._found(
            profile, 0.5 * (ea + eb), confidence=conf, edges_laser=np.array([ea, eb]), gap_mm=gap
        )


@dataclass(frozen=True)
class LapExtractor(_Base):
    """Lap: two parallel sheets with a step. Seam: the top sheet's edge projected normally
    onto the lower sheet (the corner where the edge meets it). Edge: the top sheet's edge."""

    name: str = "lap"
    min_step_mm: float = 0.3
    min_gap_mm: float = 1.0
    max_gap_mm: float = 3.0
    min_plate_mm: float = 2.0
    max_tilt_deg: float = 40.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        pairs, others = _plate_candidates(self, seg, join_hidden=True)
        best, best_score = None, 0.0
        for a, b, _ in pairs:
            step = float((b.centroid - a.centroid) @ a.normal)  # > 0: b is deeper
            if abs(step) < max(self.min_step_mm, 3 * seg.tol):
                continue
            score = float(a.count + b.count)
            if score > best_score:
                best, best_score = (a, b, step), score
        if best is None:
            return Feature.failed("no step between two parallel sheets", joint=self.name)
        a, b, step = best
        top, lower, at_end = (a, b, True) if step > 0 else (b, a, False)
        edge = corner_or_end(top, at_end, others, seg)
        foot = edge - float((edge - lower.centroid) @ lower.normal) * lower.normal
        # The ray over the top edge (from the emitter at the origin) lands on the lower sheet
        # at `shadow`: beyond the foot (away from the top sheet) the corner is in shadow and
        # the foot is the best estimate; otherwise the lower sheet is seen up to the corner.
        away = lower.direction if at_end else -lower.direction
        ray = Line(
            np.empty(0, np.intp),
            np.zeros(2),
            edge / max(float(np.hypot(*edge)), 1e-300),
            np.empty(0),
            0.0,
        )
        shadow = intersect(ray, lower)
        if shadow is not None and float((shadow - foot) @ away) > 0.0:
            seam = foot
        else:
            seam = corner_or_end(lower, not at_end, others, seg)
        return self._found(
            profile, seam, confidence=_confidence([a, b], seg), edges_laser=edge.reshape(1, 2)
        )


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
