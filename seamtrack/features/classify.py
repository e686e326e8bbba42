"""Which joint a profile shows: :func:`classify` over the built-in families, or ``"none"``.

Every family extractor checks that the profile shows its joint before it answers: its model (the
lines it found, each run on over its stretch of the profile: plates beyond a groove's bevels,
faces of a corner to the profile's ends, two plates beside a gap) must explain at least
``min_explained`` (80 %) of the profile's surface points (spikes and reflections left out),
and the family's own tests hold (a groove has a plate beside a bevel and no bevel along a
plate, a square butt's step is no taller than twice its gap, ...). :func:`classify` segments
the profile once, asks every family, and names the one whose model explains most.

>>> import seamtrack as st
>>> joint, confidence = st.classify(profile)  # doctest: +SKIP
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from seamtrack.features.base import ExtractorBase
from seamtrack.features.extractors import BUILTIN
from seamtrack.features.groove.extractor import GrooveExtractor
from seamtrack.features.lines import DATA_ERRORS, segment_profile
from seamtrack.features.refusal import Refusal
from seamtrack.features.vgroove.extractor import VGrooveExtractor
from seamtrack.sensing.profiles import Profile

#: The joint families :func:`classify` tells apart (besides ``"none"``), and ``"groove"``: an
#: empty or partly filled groove (:data:`GROOVE`).
FAMILIES = ("v-groove", "square-butt", "fillet", "lap", "outside-corner")
#: A groove with at least one layer of beads in it (the v-groove extractor refuses it: a surface
#: covers the bevels' meeting point), or one whose flat bottom is wider than the v-groove
#: extractor's largest root gap (a narrow gap, a U), when no other family finds its joint.
GROOVE = "groove"


#: The least depth (mm) of a bottom corner below the top corners' line for :func:`classify` to
#: name a groove.
WALL_MM = 1.0


@lru_cache(maxsize=8)
def _groove(resolution_mm: float | None) -> GrooveExtractor:
    return GrooveExtractor(resolution_mm=resolution_mm)


def _groove_share(
    profile: Profile, resolution_mm: float | None, s: dict[str, float]
) -> float | None:
    """The share the groove model explains when :func:`classify` should name a groove (see
    :data:`GROOVE`), else None."""
    others = [k for k, v in s.items() if v > 0 and k != "v-groove"]
    if others:
        return None
    try:
        with np.errstate(all="ignore"):
            seg = segment_profile(profile, resolution_mm=resolution_mm)
            if isinstance(seg, Refusal):
                return None
            feature, share = _groove(resolution_mm).scored(profile, seg)
    except DATA_ERRORS:
        return None
    if not feature:
        return None
    # A groove has walls: a bottom corner at least WALL_MM below the line of the top corners
    # (a plate with a reflection streak or a spike cluster has none; a capped weld neither).
    (ly, lz), (ry, rz) = feature.edges_laser[0], feature.edges_laser[6]
    depth = max(
        float(z - (lz + (rz - lz) * (y - ly) / (ry - ly))) if ry != ly else 0.0
        for y, z in (feature.edges_laser[1], feature.edges_laser[5])
    )
    if not depth >= WALL_MM:
        return None
    if s.get("v-groove", 0.0) > 0:  # an empty V, unless its bottom is wider than a root gap
        bottom = float(np.hypot(*(feature.edges_laser[5] - feature.edges_laser[1])))
        if bottom <= VGrooveExtractor.max_gap_mm:
            return None
    return share


@lru_cache(maxsize=8)
def _extractors(resolution_mm: float | None) -> tuple[ExtractorBase, ...]:
    out = []
    for name in FAMILIES:
        ex = BUILTIN[name](resolution_mm=resolution_mm)
        assert isinstance(ex, ExtractorBase)
        out.append(ex)
    return tuple(out)


def scores(profile: Profile, *, resolution_mm: float | None = None) -> dict[str, float]:
    """Each family's score on ``profile``: the share of its surface points the family's
    model explains when the family extractor finds its joint, else minus that share (a
    refusal; -0.0 when no candidate was found at all)."""
    out = {name: -0.0 for name in FAMILIES}
    try:
        with np.errstate(all="ignore"):
            seg = segment_profile(profile, resolution_mm=resolution_mm)
            if isinstance(seg, Refusal):
                return out
            for ex in _extractors(resolution_mm):
                feature, share = ex.scored(profile, seg)
                out[ex.name] = share if feature else -share
    except DATA_ERRORS:  # never raise on data
        pass
    return out


def classify(profile: Profile, *, resolution_mm: float | None = None) -> tuple[str, float]:
    """Which joint family ``profile`` shows, and how sure (in [0, 1]).

    Parameters
    ----------
    profile : Profile
    resolution_mm : float, optional
        The sensor's range resolution, as for the extractors (default: read from the data).

    Returns
    -------
    joint : str
        One of :data:`FAMILIES`, ``"groove"`` (:data:`GROOVE`: beads in a groove, or a flat
        bottom wider than a V's root gap), or ``"none"`` when no family's extractor finds its
        joint (a flat plate, a raised block, a profile too noisy or too short).
    confidence : float
        For a family: the share of the profile its model explains, less half the runner-up's
        (another family that also finds its joint). For ``"none"``: one less the largest
        share a refused family's model explained (how far the profile is from any joint).
    """
    s = scores(profile, resolution_mm=resolution_mm)
    groove = _groove_share(profile, resolution_mm, s)
    if groove is not None:
        return GROOVE, float(np.clip(groove, 0.0, 1.0))
    found = sorted(((v, k) for k, v in s.items() if v > 0), reverse=True)
    if not found:
        return "none", float(np.clip(1.0 + min(s.values(), default=0.0), 0.0, 1.0))
    best, joint = found[0]
    second = found[1][0] if len(found) > 1 else 0.0
    return joint, float(np.clip(best - 0.5 * second, 0.0, 1.0))
