"""``seamtrack seams PART --view PNG``: the part's bodies, with every found seam numbered.

Matplotlib 3D (Agg backend, no display needed): each body a translucent coarse mesh in its own
colour, each seam a thick line with its id at its middle and a short arrow along its torch
direction; unreachable seams dashed.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: Chord tolerance of the picture's body meshes (mm): a picture, not a measurement.
VIEW_TOLERANCE_MM = 0.5


def draw_seams(
    bodies: Sequence[tuple[str, Any]], seams: Sequence[Any], path: Path, title: str = ""
) -> Path:
    """Write a PNG of the bodies (name, CadQuery solid) and the found seams; return the path."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    fig = plt.figure(figsize=(9, 7))
    ax = fig.add_subplot(projection="3d")
    colours = plt.get_cmap("tab10")
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for k, (name, solid) in enumerate(bodies):
        vertices, triangles = solid.tessellate(VIEW_TOLERANCE_MM, 0.5)
        v = np.array([p.toTuple() for p in vertices])
        tris = np.asarray(triangles, dtype=int)
        lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
        poly = Poly3DCollection(v[tris], alpha=0.18, facecolor=colours(k % 10), edgecolor="none")
        ax.add_collection3d(poly)
        ax.plot([], [], color=colours(k % 10), lw=6, alpha=0.4, label=name)
    span = float(np.max(hi - lo)) if np.all(np.isfinite(hi - lo)) else 1.0
    for s in seams:
        pts = s.points
        style = "-" if s.reachable else "--"
        ax.plot(*pts.T, style, color="crimson", lw=2.5)
        mid = len(pts) // 2
        tip = pts[mid] + 0.06 * span * s.normals[mid]
        ax.plot(*np.stack([pts[mid], tip]).T, color="black", lw=1)
        ax.text(*tip, s.id.removeprefix("s"), fontsize=9, color="black", ha="center")
    centre, half = 0.5 * (lo + hi), 0.5 * span
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.view_init(elev=28, azim=-60)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"{title}: {len(seams)} seams (number = id, dashed = not reachable)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
