"""Where the fill surface rises into a wall, and raised parts that are no block (the groove
extractor's, :mod:`seamtrack.features.groove.extractor`).

* :func:`risen_level`: the level of a fill surface that rises into the wall (a U groove's
  round, bare or partly filled; a bead's toe on the round, a notch): the wall's foot is that
  wall's line at the level;
* :func:`a_step`: whether a steep piece in a raised part is a step (a block's side) or a
  streak the surface runs on across (spikes over a crowned fill).

Points are (u, v): u across the groove (the plates' line, left to right), v into it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IndexArray
from seamtrack.features.groove._groove_fit import median_of, robust_uv_fit, running_median

#: A notch where a bead's toe meets a U's round, read finely (its deepest point a running median
#: over NOTCH_WINDOW_MM): at least NOTCH_IN_MM in from the surface's outer end, which stands
#: NOTCH_RISE_MM above it, rising between NOTCH_SLOPE[0] and [1] times its run (a round; a
#: steeper rise is a wall's points left in the surface, a gentler one a root bead's face).
NOTCH_WINDOW_MM = 0.1
NOTCH_IN_MM = 0.08
NOTCH_RISE_MM = 0.25
NOTCH_SLOPE = (0.8, 4.0)
#: A notch's tip is where its flanks' lines cross: the outer one (from the outer end to the
#: deepest point) and the inner one (FLANK_MM inwards of it), when the inner one rises inwards
#: at least INNER_SLOPE times its run (a bead's flank; a flat bottom makes no notch).
FLANK_MM = 0.4
INNER_SLOPE = 0.3


#: A round's deepest point is a running median's over ROUND_WINDOW_MM; a hidden wall's round
#: (:func:`risen_level`'s ``fine``: the round's rise is all there is of its foot) is read over
#: FINE_RISE_MM, its outer end of the points themselves.
ROUND_WINDOW_MM = 0.3
FINE_RISE_MM = 0.2


def risen_level(
    fu: FloatArray, fv: FloatArray, left: bool, spacing: float, tol: float, fine: bool = False
) -> float | None:
    """The level (v) of the fill surface's deepest part near a side, when the surface rises
    from there into the wall (a U's round, bare or partly filled; None when it does not).

    Two reads of the side, either may find the rise:

    * **a round**: the deepest point of a running median over :data:`ROUND_WINDOW_MM`
      (``fine``: :data:`FINE_RISE_MM`; cut short at the ends) lies at least a quarter of a
      millimetre in from the surface's outer end (its last 0.1 mm, of the running median or,
      ``fine``, of the points), which stands at least
      0.3 mm above it and rises at least 0.45 times as much as it runs from the deepest
      part's nearest point (the synthetic 3 mm round: 0.42-1.2 bare, more beside a bead; a
      root bead's concave face, the fill's own, rises 0.13-0.43 times on the Keyence
      root-pass scans; a bead's toe on the wall comes down to it: a kink, no rise);
    * **a notch** (a bead's toe on the round, seen over its last tenths of a millimetre:
      the wall band may leave little of the round): the constants ``NOTCH_*`` above.

    The level is the notch's tip where its flanks' lines cross (``FLANK_MM``,
    ``INNER_SLOPE``; a running median shaves a V's tip, 0.1-0.3 mm on a bead's toe), else the
    mean of the deepest part's points (within 0.05 mm, or two tolerances, of the deepest)."""
    if len(fu) < 5:
        return None
    sign = 1.0 if left else -1.0
    edge = float(fu[0] if left else fu[-1])
    d = sign * (fu - edge)
    zone = d <= 4.0
    zv, zd = fv[zone], d[zone]
    if len(zv) < 5:
        return None
    order = np.argsort(zd, kind="stable")
    zv, zd = zv[order], zd[order]
    window, raw_end = (FINE_RISE_MM, True) if fine else (ROUND_WINDOW_MM, False)
    level = _round_level(zd, zv, spacing, tol, window, raw_end)
    near = zd <= 1.5
    nd, nv = zd[near], zv[near]
    if len(nv) < 7:
        return level
    smooth = running_median(nv, _odd(NOTCH_WINDOW_MM / max(spacing, 1e-9)))
    j = int(np.argmax(smooth))
    if level is None:
        end = median_of(nv[nd <= max(0.05, 2 * spacing)])
        rise, run = float(smooth[j]) - end, float(nd[j])
        lo, hi = NOTCH_SLOPE
        if not (run >= NOTCH_IN_MM and rise >= NOTCH_RISE_MM and lo * run <= rise <= hi * run):
            return None
        level = float(smooth[j])
    tip = _flank_crossing(nd, nv, float(nd[j]), float(smooth[j]), tol)
    return level if tip is None else tip


def _odd(n: float, lo: int = 3, hi: int = 51) -> int:
    return int(min(hi, max(lo, round(n)))) | 1


def _round_level(
    zd: FloatArray, zv: FloatArray, spacing: float, tol: float, window: float, raw_end: bool
) -> float | None:
    """:func:`risen_level`'s read of a round (its first bullet), on the side's points ``zd``
    (in from the outer end, ascending) and ``zv``."""
    smooth = running_median(zv, _odd(window / max(spacing, 1e-9)))
    j = int(np.argmax(smooth))
    end = median_of((zv if raw_end else smooth)[zd <= max(0.1, 3 * spacing)])
    if zd[j] < 0.25 or smooth[j] - end < 0.3:
        return None
    deep = smooth >= smooth[j] - min(2.0 * tol, 0.05)
    if smooth[j] - end < 0.45 * float(np.min(zd[deep])):
        return None  # a gentle rise (a root bead's concave face): the fill's own, no round
    return float(np.mean(zv[deep]))


def _flank_crossing(
    zd: FloatArray, zv: FloatArray, deepest: float, level: float, tol: float
) -> float | None:
    """v where the notch's outer flank's line crosses its inner one's (:func:`risen_level`);
    None when either has fewer than 3 points or no line, the inner one does not rise, or the
    crossing lies more than 0.1 mm above or 0.4 mm below the running median's deepest
    ``level``."""
    outer = zd <= deepest
    inner = (zd >= deepest) & (zd <= deepest + FLANK_MM)
    if np.count_nonzero(outer) < 3 or np.count_nonzero(inner) < 3:
        return None
    fo = robust_uv_fit(zd[outer], zv[outer], tol)
    fi = robust_uv_fit(zd[inner], zv[inner], tol)
    if fo is None or fi is None or fi[1] > -INNER_SLOPE or abs(fo[1] - fi[1]) < 1e-6:
        return None  # (v grows into the groove: a flank rising inwards has v falling)
    x = (fi[0] - fo[0]) / (fo[1] - fi[1])
    tip = fo[0] + fo[1] * x
    return tip if level - 0.1 <= tip <= level + 0.4 else None


def a_step(
    points: FloatArray, index: IndexArray, normal: FloatArray, steep: NDArray[np.bool_]
) -> bool:
    """Whether the steep piece ``index`` of a raised part is a step: its rise (along
    ``normal``) lies at least half between the surface's levels beyond its ends (the median of
    the first 8 points beyond each end within 2 mm of it across the groove, less those of
    any ``steep`` piece: more than 60 deg off the plates). A block's side joins two levels; a
    spike streak over a crowned fill (12-15 points over 1.2-2.9 mm, 81 deg off the plates)
    stands out of a surface that runs on across it. A side with fewer than 3 such points
    counts as a step."""
    lo, hi = int(index[0]), int(index[-1])
    level = points @ normal
    along = np.array([normal[1], -normal[0]])
    ends = []
    for k, edge in (
        (np.arange(lo - 1, -1, -1), points[lo]),
        (np.arange(hi + 1, len(points)), points[hi]),
    ):
        k = k[~steep[k]]
        k = k[np.abs((points[k] - edge) @ along) <= 2.0][:8]
        if len(k) < 3:
            return True
        ends.append(median_of(level[k]))
    rise = level[index]
    overlap = min(float(rise.max()), max(ends)) - max(float(rise.min()), min(ends))
    return overlap >= 0.5 * float(np.ptp(rise))
