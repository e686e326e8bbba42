"""Matplotlib plots a welding engineer expects (imported only when a plot is asked for)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .simulation import Result


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def plot_run(result: Result, path: str | Path, title: str = "") -> Path:
    """error.png: the paper's Fig. 7 style path plot (seam vs torch, top view and side view)
    and the tracking error along the seam (total, lateral, vertical)."""
    plt = _pyplot()
    tr = result.trace
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), constrained_layout=True)
    seam_pts = tr.closest_world
    weld = tr.welding
    for ax, (i, j, label) in zip(axes[:2], [(0, 1, "Y"), (0, 2, "Z")], strict=True):
        ax.plot(seam_pts[:, i], seam_pts[:, j], color="0.5", lw=3, label="seam (closest points)")
        ax.plot(tr.tcp_world[:, i], tr.tcp_world[:, j], color="C3", lw=1, label="torch tip")
        found = tr.frames["found"]
        pts = tr.frames["point_world"][found]
        ax.plot(pts[:, i], pts[:, j], "k.", ms=3, label="sensed seam points")
        ax.set_xlabel("X (mm)")
        ax.set_ylabel(f"{label} (mm)")
        ax.legend(loc="best", fontsize=8)
    axes[0].set_title(title or f"status: {result.status}")
    ax = axes[2]
    s = tr.arc_length_mm[weld]
    ax.plot(s, tr.error_mm[weld], color="k", lw=1, label="error")
    ax.plot(s, tr.error_lateral_mm[weld], color="C0", lw=0.8, label="lateral")
    ax.plot(s, tr.error_vertical_mm[weld], color="C1", lw=0.8, label="vertical")
    ax.set_xlabel("arc length along the seam (mm)")
    ax.set_ylabel("tracking error (mm)")
    ax.legend(loc="best", fontsize=8)
    summary = result.summary
    ax.set_title(
        f"max {summary['max_error_mm']:.3f} mm, rms {summary['rms_error_mm']:.3f} mm "
        f"(welding portion)"
    )
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_sweep(
    rows: Sequence[dict[str, Any]],
    param: str,
    path: str | Path,
    keys: Sequence[str] = ("max_error_mm", "min_error_mm"),
) -> Path:
    """Metrics against a swept parameter (log x when all values are positive)."""
    plt = _pyplot()
    x = np.array([float(r["value"]) for r in rows])
    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    for key in keys:
        y = np.array([float(r.get(key, np.nan)) for r in rows])
        ax.plot(x, y, "o-", label=key)
    if (x > 0).all():
        ax.set_xscale("log")
    ax.set_xlabel(param)
    ax.set_ylabel("mm")
    ax.legend()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
