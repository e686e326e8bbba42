"""The part bending while it is welded: ``distortion.png`` of a run whose scene has
``[distortion]`` (issue 39).

The seam's move (:meth:`seamtrack.heat.motion.JointMotion.shift_mm`) along the whole seam at
instants through the run, one line each, coloured by time, with the arc's position on each:
along the torch normal (the plates turning about the weld: the transient angle near the arc,
the permanent angle locked in behind it) and across (the gap closing behind the arc, the free
plate turning ahead of it until a tack or a clamp holds it). Beside them, the seam's move at the
torch and the tracking error along the seam are in ``error.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.viz.plots import pyplot_module, save_figure

FloatArray = NDArray[np.float64]


def seam_snapshots(
    motion: Any, length_mm: float, end_s: float, instants: int = 9, stations: int = 301
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The seam's move at ``instants`` times from 0 to ``end_s`` and ``stations`` stations
    over ``length_mm``: times (k,), stations (m,), across (k, m) and along the normal (k, m)."""
    t = np.linspace(0.0, end_s, instants)
    s = np.linspace(0.0, length_mm, stations)
    lateral, vertical = motion.shift_mm(s[None, :], t[:, None])
    return t, s, np.asarray(lateral, dtype=float), np.asarray(vertical, dtype=float)


def plot_seam_motion(
    motion: Any, length_mm: float, end_s: float, path: str | Path, title: str = ""
) -> Path:
    """``distortion.png``: the seam's move along the seam at instants through the run."""
    plt = pyplot_module()
    t, s, lateral, vertical = seam_snapshots(motion, length_mm, end_s)
    fig, axes = plt.subplots(2, 1, figsize=(9.0, 5.6), sharex=True, constrained_layout=True)
    colors = plt.get_cmap("plasma")(np.linspace(0.0, 0.85, len(t)))
    arc = np.clip(motion.speed_mm_s * t, 0.0, length_mm)
    for k, (when, color) in enumerate(zip(t, colors, strict=True)):
        label = f"t = {when:.1f} s"
        for ax, values in ((axes[0], vertical[k]), (axes[1], lateral[k])):
            ax.plot(s, values, color=color, lw=1.2, label=label)
            ax.plot(arc[k], np.interp(arc[k], s, values), "v", color=color, ms=5)
    axes[0].set_ylabel("along the torch normal (mm)")
    axes[1].set_ylabel("across the seam (mm)")
    axes[1].set_xlabel("arc length along the seam (mm); triangles: the arc")
    for ax in axes:
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[0].set_title(title or "the seam moving while it is welded")
    return save_figure(fig, path)
