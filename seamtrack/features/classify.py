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

from seamtrack.features.base import _Base
from seamtrack.features.extractors import BUILTIN
from seamtrack.features.lines import DATA_ERRORS, segment_profile
from seamtrack.sensing.profiles import Profile

#: The joint families :func:`classify` tells apart (besides ``"none"``).
FAMILIES = ("v-groove", "square-butt", "fillet", "lap", "outside-corner")


@lru_cache(maxsize=8)
def _extractors(resolution_mm: float | None) -> tuple[_Base, ...]:
    out = []
    for name in FAMILIES:
        ex = BUILTIN[name](resolution_mm=resolution_mm)
        assert isinstance(ex, _Base)
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
            if isinstance(seg, str):
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
        One of :data:`FAMILIES`, or ``"none"`` when no family's extractor finds its joint (a
        flat plate, a raised block, a profile too noisy or too short).
    confidence : float
        For a family: the share of the profile its model explains, less half the runner-up's
        (another family that also finds its joint). For ``"none"``: one less the largest
        share a refused family's model explained (how far the profile is from any joint).
    """
    s = scores(profile, resolution_mm=resolution_mm)
    found = sorted(((v, k) for k, v in s.items() if v > 0), reverse=True)
    if not found:
        return "none", float(np.clip(1.0 + min(s.values(), default=0.0), 0.0, 1.0))
    best, joint = found[0]
    second = found[1][0] if len(found) > 1 else 0.0
    return joint, float(np.clip(best - 0.5 * second, 0.0, 1.0))
