"""Line of sight across a gap, and why a weldment gives no seam: the checks of
:mod:`seamtrack.workpiece.weldment` beside the region kernels of
:mod:`seamtrack.workpiece.contacts`.

Two bodies' faces facing each other across a gap make a seam only where nothing stands between
them: three blocks in a row give no seam between the outer two, through the middle one.
:func:`gap_filled` drops a whole facing region whose gap other bodies fill (the prism the region
sweeps across the gap, minus those bodies, has no volume left); :func:`gap_blocked` tests one
seam point (the open segment across the gap, just inside the region, must cross no other body's
surface and not lie inside one), so a partly blocked region keeps its free stretches.

:func:`no_seam_error` says what is really wrong when no seam is left: bodies modelled into each
other (coincident, one inside the other, or overlapping without a crossing that shows), contacts
whose seams are all shorter than ``min_length_mm`` (with the value that would find them), or
faces that do not touch at all. Imported lazily: it needs OCP (CadQuery's OCCT).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
from OCP.gp import gp_Vec

from seamtrack.errors import WorkpieceError
from seamtrack.workpiece.contacts import (
    ON_TOL_MM,
    SIDE_STEP_MM,
    FloatArray,
    FreeSpace,
    Piece,
    bounds,
)
from seamtrack.workpiece.crossings import volume

#: A gap prism with less than this fraction of its volume left free is filled.
FILLED_FRACTION = 1e-6
#: Shared volume within this fraction of a body's volume: the body lies wholly in the other.
SAME_VOLUME_FRACTION = 1e-6


@dataclass
class Findings:
    """What the search met on its way, for the error when no seam is left."""

    overlapping: list[tuple[int, int]] = field(default_factory=list)
    #: a, b, and the body that fills their gap (None: bodies stand in it along every seam)
    filled: list[tuple[int, int, int | None]] = field(default_factory=list)
    short_mm: list[float] = field(default_factory=list)  # longest pieces dropped as too short


def gap_filled(
    region: Any, normal: FloatArray, gap_mm: float, space: FreeSpace, pair: tuple[int, int]
) -> int | None:
    """The body (index) that, with the others beside the pair, fills the whole gap over a
    facing region (lying in B's plane; ``normal``: A's outward normal, towards B), or None."""
    lo, hi = bounds(region)
    back = -gap_mm * np.asarray(normal)
    lo, hi = np.minimum(lo, lo + back), np.maximum(hi, hi + back)
    pad = min(ON_TOL_MM, 0.25 * gap_mm)  # the prism's own faces touch the pair only
    others = space.near(lo + pad, hi - pad, skip=pair)
    if not others:
        return None
    prism = BRepPrimAPI_MakePrism(region, gp_Vec(*back)).Shape()
    total = volume(prism)
    rest = prism
    for i in others:
        cut = BRepAlgoAPI_Cut(rest, space.solids[i])
        if not cut.IsDone():
            return None
        rest = cut.Shape()
    return others[0] if volume(rest) <= FILLED_FRACTION * total else None


def gap_blocked(piece: Piece, point: FloatArray, inward: FloatArray, space: FreeSpace) -> bool:
    """Whether another body stands in the gap at a seam point: the segment across the gap,
    from A's contact plane to B's, a little inside the region."""
    if piece.gap_mm <= ON_TOL_MM or piece.inward is None or piece.plane_a is None:
        return False
    n = piece.contact_normal
    start = point + min(SIDE_STEP_MM, 0.25 * piece.region_extent_mm) * inward
    start = start - float((start - piece.plane_a) @ n) * n
    return space.sight_blocked(start, n, piece.gap_mm, skip=piece.bodies)


def _relation(solids: Sequence[Any], names: Sequence[str], i: int, j: int) -> tuple[str, str]:
    """What is wrong with two bodies that share volume, and the fix."""
    common = BRepAlgoAPI_Common(solids[i], solids[j])
    shared = volume(common.Shape()) if common.IsDone() else 0.0
    va, vb = volume(solids[i]), volume(solids[j])
    a_in = abs(shared - va) <= SAME_VOLUME_FRACTION * va
    b_in = abs(shared - vb) <= SAME_VOLUME_FRACTION * vb
    a, b = names[i], names[j]
    if a_in and b_in:
        return (
            f"{a} and {b} are coincident (the same solid twice, {va:.4g} mm^3)",
            f"remove one of {a} and {b} (a body exported twice)",
        )
    if a_in or b_in:
        inner, outer = (a, b) if a_in else (b, a)
        return (
            f"{inner} lies wholly inside {outer} (containment: they share all of "
            f"{min(va, vb):.4g} mm^3)",
            f"place {inner} against {outer}'s face instead of inside it, or remove it",
        )
    return (
        f"{a} and {b} overlap (interference: they share {shared:.4g} mm^3) but their "
        "surfaces cross nowhere a seam shows",
        f"place {a} and {b} face to face instead of into each other",
    )


def no_seam_error(
    findings: Findings,
    solids: Sequence[Any],
    names: Sequence[str],
    *,
    source: str,
    field_name: str,
    min_length_mm: float,
) -> WorkpieceError:
    """The error for bodies that come close but give no seam: what is really wrong."""
    if findings.overlapping:
        what, fix = _relation(solids, names, *findings.overlapping[0])
        return WorkpieceError(f"{source}: {what}, so no seam was found", field=field_name, fix=fix)
    if findings.short_mm:
        longest = max(findings.short_mm)
        enough = float(f"{0.5 * longest:.1g}")
        return WorkpieceError(
            f"{source}: the bodies touch along planar faces, but every seam there is shorter "
            f"than min_length_mm = {min_length_mm:g} (the longest: {longest:.3g} mm)",
            field=field_name,
            fix=f"lower min_length_mm to {enough:g} (seamtrack seams --min-length-mm "
            f"{enough:g}), or check the part's units",
        )
    if findings.filled:
        a, b, k = findings.filled[0]
        what = "another body" if k is None else names[k]
        return WorkpieceError(
            f"{source}: {names[a]} and {names[b]} face each other only across a gap that "
            f"{what} stands in (no line of sight between their faces), so no seam was found",
            field=field_name,
            fix="seams are found between faces that touch, or face each other across free space",
        )
    return WorkpieceError(
        f"{source}: the bodies touch, but nowhere along planar faces or crossing "
        "surfaces (only at points, lines or curved faces), so no seam was found",
        field=field_name,
        fix="seams are found between planar faces that touch or face each other",
    )
