"""The groove extractor on real scans (``seamtrack extractors bench --real DIR``): on every
V-groove set (the Keyence root-pass set: a bead in the bottom of a 90 deg V), two checks of
the 7 points against the profile itself, independent of the extractor:

* **top corners within 0.5 mm of the bevels' top edges**: the reference edges are where each
  plate's line (total least squares through the outer 10 % of the profile's valid points on
  that side) meets that side's bevel line (through the points between 20 % and 50 % of the
  depth from the plates down to the set's label, the bevels' intersection, on that side of it);
* **bottom points on the bead's surface**: the bottom corners and the three bottom points each
  within :data:`ON_SURFACE_MM` of a valid point of the profile, and at least
  :data:`ABOVE_ROOT_MM` above the label (on the bead, not at the root under it).

One row per set: ``groove_found`` (share of profiles answered), ``top_ok`` and ``bottom_ok``
(share of profiles with both top corners within 0.5 mm, with all five bottom points on the
surface), the p95 of the top-corner distances and of the bottom points' distances to the
profile (mm), and the median CPU time per profile (us).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from seamtrack.bench.common import markdown_table
from seamtrack.features.extractors import extractor

#: Top corners within this of the bevels' top edges (mm): the issue's must-show.
TOP_MM = 0.5
#: A bottom point within this of a valid profile point lies on the surface (mm).
ON_SURFACE_MM = 0.3
#: ... and at least this above the bevels' intersection (mm): on the bead, not the root.
ABOVE_ROOT_MM = 1.0
GROOVE_COLUMNS = (
    "set",
    "n",
    "groove_found",
    "top_ok",
    "bottom_ok",
    "top_p95_mm",
    "bottom_p95_mm",
    "us_per_profile",
)


def _tls(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A total-least-squares line, refitted three times without the points off it by more than
    max(0.1 mm, 3 robust sigmas) (spikes)."""
    keep = np.ones(len(p), dtype=bool)
    for _ in range(4):
        c = p[keep].mean(axis=0)
        d = np.linalg.svd(p[keep] - c)[2][0]
        r = np.abs((p - c) @ np.array([-d[1], d[0]]))
        keep = r <= max(0.1, 3 * 1.4826 * float(np.median(r[keep])))
    return c, d


def _cross(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    (c1, d1), (c2, d2) = a, b
    t = np.linalg.solve(np.column_stack([d1, -d2]), c2 - c1)
    return np.asarray(c1 + t[0] * d1)


def reference_top_edges(points: np.ndarray, label: np.ndarray) -> np.ndarray:
    """(2, 2) the bevels' top edges of a V-groove profile (left, right): each plate's line
    crossed with its bevel's (module docstring)."""
    p = points[np.isfinite(points).all(axis=1)]
    p = p[np.argsort(p[:, 0], kind="stable")]
    k = max(3, len(p) // 10)
    plates = (_tls(p[:k]), _tls(p[-k:]))
    plate_z = 0.5 * (float(np.median(p[:k, 1])) + float(np.median(p[-k:, 1])))
    depth = float(label[1]) - plate_z
    edges = []
    for side, plate in zip((p[:, 0] < label[0], p[:, 0] > label[0]), plates, strict=True):
        q = p[side]
        frac = (q[:, 1] - plate_z) / depth
        bevel = _tls(q[(frac >= 0.2) & (frac <= 0.5)])
        edges.append(_cross(plate, bevel))
    return np.array(edges)


def bench_real_groove(sets: list[Any]) -> list[dict[str, Any]]:
    """One row per V-groove set with labels (``sets``: the real sets of
    :func:`seamtrack.bench.extractors.load_real_sets`)."""
    ex = extractor("groove")
    rows = []
    for rs in sets:
        if rs.joint != "v-groove" or rs.labels is None:
            continue
        ex(rs.profiles[0])  # warm-up, untimed
        found = top_ok = bottom_ok = 0
        top_d: list[float] = []
        bottom_d: list[float] = []
        took = []
        for profile, label in zip(rs.profiles, rs.labels, strict=True):
            t0 = time.process_time_ns()
            f = ex(profile)
            took.append(time.process_time_ns() - t0)
            if not f:
                continue
            found += 1
            pts = profile.points_laser
            valid = pts[np.isfinite(pts).all(axis=1)]
            ref = reference_top_edges(pts, np.asarray(label))
            d_top = np.hypot(*(f.edges_laser[[0, 6]] - ref).T)
            top_d += d_top.tolist()
            top_ok += bool(np.all(d_top <= TOP_MM))
            bottom = f.edges_laser[1:6]
            d_bot = np.min(
                np.hypot(*(bottom[:, None, :] - valid[None, :, :]).transpose(2, 0, 1)), 1
            )
            bottom_d += d_bot.tolist()
            above = float(label[1]) - bottom[:, 1] >= ABOVE_ROOT_MM  # z_L grows into the groove
            bottom_ok += bool(np.all(d_bot <= ON_SURFACE_MM) and np.all(above))
        n = len(rs.profiles)
        rows.append(
            {
                "set": rs.name,
                "n": n,
                "groove_found": found / n,
                "top_ok": top_ok / n,
                "bottom_ok": bottom_ok / n,
                "top_p95_mm": float(np.percentile(top_d, 95)) if top_d else float("nan"),
                "bottom_p95_mm": float(np.percentile(bottom_d, 95)) if bottom_d else float("nan"),
                "us_per_profile": 1e-3 * float(np.median(took)),
            }
        )
    return rows


def groove_table(rows: list[dict[str, Any]]) -> str:
    """The groove rows as a markdown table."""
    head = (
        "set", "n", "groove found", "top corners <= 0.5 mm", "bottom points on the bead",
        "top p95 mm", "bottom p95 mm", "us/profile",
    )  # fmt: skip
    body = [
        [str(r["set"]), str(r["n"]),
         *(f"{r[k]:.3f}" for k in ("groove_found", "top_ok", "bottom_ok", "top_p95_mm",
                                   "bottom_p95_mm")),
         f"{r['us_per_profile']:.0f}"]
        for r in rows
    ]  # fmt: skip
    return "\n".join(markdown_table(head, body)) + "\n"
