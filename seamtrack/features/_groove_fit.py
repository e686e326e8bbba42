"""Fits the groove extractor's corners rest on (:mod:`seamtrack.features.groove`).

* :func:`trim_wall`: a wall's line refitted on the points that lie on it (a root radius's
  round at the wall's foot, and the odd spike, left out);
* :func:`risen_level`: the level of a fill surface that rises into the wall (a U groove's
  round, bare or partly filled): the wall's foot is that wall's line at the level;
* :func:`ray_reach`: with no wall seen, how far the fill surface reaches towards the side:
  a spike moves a point along its ray, so the ray still says where the surface is across the
  groove.

Points are (u, v): u across the groove (the plates' line, left to right), v into it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from seamtrack.features._segmentation import fit_line
from seamtrack.features.lines import Line

FloatArray = NDArray[np.float64]


def trim_wall(points: FloatArray, line: Line, tol: float, rounds: int = 3) -> Line:
    """``line`` refitted (total least squares) on its points within two tolerances of it, a
    few times over: a round at the wall's foot that leaves the line slowly, and points
    of a spike that the pieces took in, stop pulling it. Unchanged when fewer than half its
    points would stay."""
    index = np.asarray(line.index)
    keep = index
    cur = line
    for _ in range(rounds):
        off = np.abs((points[index] - cur.centroid) @ cur.normal)
        new = index[off <= 2.0 * tol]
        if len(new) < max(3, len(index) // 2) or np.array_equal(new, keep):
            break
        keep = new
        f = fit_line(points, np.asarray(keep, dtype=np.int64))
        cur = Line(keep, np.array([f.cy, f.cz]), np.array([f.uy, f.uz]), f.along, f.rms)
    if cur.direction[0] * line.direction[0] + cur.direction[1] * line.direction[1] < 0:
        cur = Line(cur.index, cur.centroid, -cur.direction, -cur.t, cur.rms)
    return cur


def _running_median(v: FloatArray, k: int) -> FloatArray:
    if len(v) < k:
        return np.full(len(v), float(np.median(v)))
    med = np.median(np.lib.stride_tricks.sliding_window_view(v, k), axis=1)
    return np.asarray(np.pad(med, k // 2, mode="edge"))


def risen_level(
    fu: FloatArray, fv: FloatArray, left: bool, spacing: float, tol: float
) -> float | None:
    """The level (v) of the fill surface's deepest part near a side, when the surface rises
    from there into the wall: its deepest point (a running median over 0.3 mm) lies at least
    half a millimetre in from the surface's outer end, which stands at least 0.3 mm above
    it (a round at a U's foot, bare or partly filled, or the notch between a bead and the
    round). None when the surface comes down to the wall (a bead's toe on the wall: a
    kink). The level is the mean of the deepest part's points (within two tolerances of
    the deepest)."""
    if len(fu) < 5:
        return None
    sign = 1.0 if left else -1.0
    edge = float(fu[0] if left else fu[-1])
    d = sign * (fu - edge)
    zone = d <= 4.0
    zu, zv, zd = fu[zone], fv[zone], d[zone]
    if len(zu) < 5:
        return None
    order = np.argsort(zd, kind="stable")
    zv, zd = zv[order], zd[order]
    k = int(min(51, max(3, round(0.3 / max(spacing, 1e-9)))) | 1)
    smooth = _running_median(zv, k)
    j = int(np.argmax(smooth))
    end = float(np.median(smooth[zd <= max(0.3, 3 * spacing)]))
    if zd[j] < 0.5 or smooth[j] - end < 0.3:
        return None
    deep = smooth >= smooth[j] - 2.0 * tol
    return float(np.mean(zv[deep]))


def ray_reach(
    points: FloatArray,
    u: FloatArray,
    v: FloatArray,
    a: float,
    b: float,
    out_u: float,
    left: bool,
    reach: float = 1.0,
    band: float = 6.0,
) -> float:
    """How far (u) the surface v = a + b u reaches towards a side with no wall seen: each
    point (spikes too) within ``band`` of the line whose ray (from the sensor's origin, the
    laser frame's (0, 0)) meets the line at most ``reach`` beyond ``out_u`` (the surface's
    outermost point on its line) stands for a column that lit the surface there; the
    outermost of those crossings, or ``out_u``."""
    sign = 1.0 if left else -1.0
    pu, pv = points @ u, points @ v
    near = np.abs(pv - (a + b * pu)) <= band
    beyond = sign * (pu - out_u) < -reach - 2.0  # far out: not this surface's columns
    sel = near & ~beyond
    pu, pv = pu[sel], pv[sel]
    if not len(pu):
        return out_u
    # The ray through (pu, pv) from the origin: (t pu, t pv); on the line: t pv = a + b t pu.
    ou, ov = 0.0, 0.0  # the origin in (u, v): u, v are a rotation of the laser frame
    den = pv - ov - b * (pu - ou)
    ok = np.abs(den) > 1e-9
    t = np.where(ok, (a + b * ou - ov) / np.where(ok, den, 1.0), np.nan)
    xu = ou + t * (pu - ou)
    xu = xu[ok & (t > 0)]
    cand = xu[(sign * (out_u - xu) > 0) & (sign * (out_u - xu) <= reach)]
    if not len(cand):
        return out_u
    return float(cand.min() if left else cand.max())
