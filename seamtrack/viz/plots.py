"""Matplotlib plots a welding engineer expects (matplotlib is imported only when a plot is made).

- :func:`plot_run`: ``error.png`` of ``seamtrack run``: the path in top and side view and the
  tracking error along the seam.
- :func:`plot_path`: the paper's Fig. 7 / Fig. 11 style path plot (seam vs torch tip).
- :func:`plot_error_components`: the error along the seam, total, lateral and vertical.
- :func:`plot_sweep`: metrics against a swept parameter (Table 4).
- :func:`plot_profile_2d`: one stripe profile in the laser plane, coloured by validity, with the
  seam point found and the ground truth.

Every function takes an output path, writes a PNG (the Agg backend, so no display is needed)
and returns the path; the ``draw_*`` helpers draw onto a given matplotlib ``Axes`` instead, for
notebooks that compose their own figures.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.io.output import prepare_file
from seamtrack.sensing.profiles import Feature, Profile, Reason
from seamtrack.simulation.loop import Result

#: Colours of the stripe points by :class:`~seamtrack.sensing.profiles.Reason` (shared with
#: ``viz``).
REASON_COLORS: dict[Reason, str] = {
    Reason.VALID: "#1a9e1a",
    Reason.OCCLUDED: "#ff7f0e",
    Reason.OUT_OF_RANGE: "#8c8c8c",
    Reason.INCIDENCE: "#9467bd",
    Reason.DROPOUT: "#8c564b",
    Reason.MISS: "#e377c2",
}

_VIEWS = {"top": (0, 1, "Y"), "side": (0, 2, "Z")}
#: Most sensed seam points drawn in a path plot: at 100 frames/s a run senses thousands, whose
#: dots would bury the seam and torch lines; beyond this every k-th is drawn.
MAX_SENSED_MARKERS = 200


def sensed_point_step(n: int) -> int:
    """Draw every ``step``-th of ``n`` sensed points, so that at most
    :data:`MAX_SENSED_MARKERS` are drawn."""
    return max(1, math.ceil(n / MAX_SENSED_MARKERS))


def pyplot_module() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    plt = pyplot_module()
    out = prepare_file(path)
    try:
        fig.savefig(out, dpi=dpi)
    finally:
        plt.close(fig)
    return out


# --------------------------------------------------------------------------- drawing helpers
def draw_path(ax: Any, result: Result, view: str = "top", *, legend: bool = True) -> None:
    """Seam (closest points), torch tip and sensed seam points in one projection.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    result : Result
    view : {"top", "side"}
        ``"top"``: X-Y (the paper's Fig. 7 top view); ``"side"``: X-Z.
    legend : bool
    """
    i, j, label = _VIEWS[view]
    tr = result.trace
    seam_pts = tr.closest_world
    ax.plot(
        seam_pts[:, i], seam_pts[:, j], color="0.6", lw=3, label="seam (closest points)", zorder=2
    )
    ax.plot(tr.tcp_world[:, i], tr.tcp_world[:, j], color="C3", lw=1, label="torch tip", zorder=3)
    found = np.asarray(tr.frames.get("found", np.zeros(0, dtype=bool)), dtype=bool)
    if found.any():
        pts = tr.frames["point_world"][found]
        step = sensed_point_step(len(pts))
        ax.plot(
            pts[::step, i],
            pts[::step, j],
            ".",
            color="k",
            ms=2.5 if step == 1 else 1.5,
            zorder=1,  # under the lines, which stay visible
            label="sensed seam points" + (f" (every {step}th)" if step > 1 else ""),
        )
    ax.set_xlabel("X (mm)")
    ax.set_ylabel(f"{label} (mm)")
    if legend:
        ax.legend(loc="best", fontsize=8)


def draw_error_components(ax: Any, result: Result, *, legend: bool = True) -> None:
    """Tracking error over the welding portion against arc length: total, lateral, vertical.

    The lateral component is along (seam tangent x torch normal), the vertical one along the
    torch normal (see :class:`seamtrack.simulation.loop.Trace`); both are signed.
    """
    tr = result.trace
    weld = tr.welding if tr.welding.any() else np.ones(len(tr.t_s), dtype=bool)
    s = tr.arc_length_mm[weld]
    ax.plot(s, tr.error_mm[weld], color="k", lw=1, label="error")
    ax.plot(s, tr.error_lateral_mm[weld], color="C0", lw=0.8, label="lateral")
    ax.plot(s, tr.error_vertical_mm[weld], color="C1", lw=0.8, label="vertical")
    if len(tr.seam_shift_mm):  # [distortion]: the seam's move, the taught path's error
        ax.plot(s, tr.seam_shift_mm[weld], color="C3", lw=1, ls="--",
                label="seam shift (taught path's error)")  # fmt: skip
    ax.axhline(0.0, color="0.8", lw=0.5, zorder=0)
    ax.set_xlabel("arc length along the seam (mm)")
    ax.set_ylabel("tracking error (mm)")
    if legend:
        ax.legend(loc="best", fontsize=8)


def _error_title(result: Result) -> str:
    summary = result.summary
    maximum, rms = summary.get("max_error_mm", math.nan), summary.get("rms_error_mm", math.nan)
    return f"max {maximum:.3f} mm, rms {rms:.3f} mm (welding portion)"


# --------------------------------------------------------------------------- figures
def plot_run(result: Result, path: str | Path, title: str = "") -> Path:
    """error.png: the paper's Fig. 7 style path plot (seam vs torch, top view and side view)
    and the tracking error along the seam (total, lateral, vertical)."""
    plt = pyplot_module()
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), constrained_layout=True)
    draw_path(axes[0], result, "top")
    draw_path(axes[1], result, "side")
    axes[0].set_title(title or f"status: {result.status}")
    draw_error_components(axes[2], result)
    axes[2].set_title(_error_title(result))
    return save_figure(fig, path)


def plot_path(result: Result, path: str | Path, title: str = "") -> Path:
    """The paper's Fig. 7 / Fig. 11 path plot: seam and torch tip, top (X-Y) and side (X-Z).

    Parameters
    ----------
    result : Result
    path : str or Path
        PNG to write.
    title : str
        Default: the run's status and maximum error.

    Returns
    -------
    Path
    """
    plt = pyplot_module()
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), constrained_layout=True)
    draw_path(axes[0], result, "top")
    draw_path(axes[1], result, "side", legend=False)
    axes[0].set_title(title or f"status: {result.status}; {_error_title(result)}")
    return save_figure(fig, path)


def plot_error_components(result: Result, path: str | Path, title: str = "") -> Path:
    """The tracking error along the seam, split into its lateral and vertical components.

    Returns
    -------
    Path
        The PNG written.
    """
    plt = pyplot_module()
    fig, ax = plt.subplots(figsize=(9, 3.6), constrained_layout=True)
    draw_error_components(ax, result)
    ax.set_title(title or _error_title(result))
    return save_figure(fig, path)


def plot_sweep(
    rows: Sequence[dict[str, Any]],
    param: str,
    path: str | Path,
    keys: Sequence[str] = ("max_error_mm", "p95_error_mm"),
) -> Path:
    """Metrics against a swept parameter (log x when all values are positive), with their 95 %
    confidence half-widths (``<key>_ci95``, several seeds) as error bars."""
    plt = pyplot_module()
    x = np.array([float(r["value"]) for r in rows])
    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    for key in keys:
        y = np.array([float(r.get(key, np.nan)) for r in rows])
        ci = np.array([float(r.get(f"{key}_ci95", 0.0)) for r in rows])
        ax.errorbar(x, y, yerr=ci if ci.any() else None, fmt="o-", capsize=3, label=key)
    if (x > 0).all():
        ax.set_xscale("log")
    ax.set_xlabel(param)
    ax.set_ylabel("mm")
    ax.legend()
    return save_figure(fig, path)


def draw_profile_2d(
    ax: Any,
    profile: Profile,
    *,
    truth: Any = None,
    feature: Feature | None = None,
) -> None:
    """A stripe profile in the laser plane (y_L across, z_L down as the sensor looks).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    profile : Profile
    truth : GroundTruth or (2,) float, optional
        The true seam point (y_L, z_L); a :class:`~seamtrack.features.synthetic.GroundTruth` also
        marks
        its groove edges.
    feature : Feature, optional
        The seam point an extractor found (drawn when truthy).
    """
    assert profile.reason is not None
    pts = profile.points_laser
    finite = np.isfinite(pts).all(axis=1)
    for code in Reason:
        sel = (profile.reason == code) & finite
        if not sel.any():
            continue
        valid = code is Reason.VALID
        ax.plot(
            pts[sel, 0],
            pts[sel, 1],
            ".",
            ms=2.5 if valid else 2,
            alpha=1.0 if valid else 0.5,
            color=REASON_COLORS[code],
            label=f"{code.name.lower()} ({int(sel.sum())})",
        )
    misses = int(np.count_nonzero(profile.reason == Reason.MISS))
    if truth is not None:
        seam = np.asarray(getattr(truth, "seam_laser", truth), dtype=np.float64).reshape(-1)
        if seam.shape == (2,):
            ax.plot(*seam, "o", mfc="none", mec="k", ms=11, mew=1.5, label="true seam point")
        edges = np.asarray(getattr(truth, "edges_laser", np.empty((0, 2))), dtype=np.float64)
        if len(edges):
            ax.plot(edges[:, 0], edges[:, 1], "s", mfc="none", mec="k", ms=7, label="true edges")
    if feature:
        ax.plot(*feature.point_laser, "x", color="C3", ms=11, mew=2, label="seam point found")
        if len(feature.edges_laser):
            ax.plot(
                feature.edges_laser[:, 0],
                feature.edges_laser[:, 1],
                "+",
                color="C3",
                ms=10,
                mew=1.5,
                label="edges found",
            )
    label_stripe_axes(ax, profile, misses, "y_L, across the stripe (mm)")
    ax.legend(loc="best", fontsize=8)


def label_stripe_axes(ax: Any, profile: Profile, misses: int, xlabel: str = "y_L (mm)") -> None:
    """The laser plane's axes: range growing downward (as the sensor looks), equal scales, the
    axes' labels, a title with the rays missed and the frame's time, a grid."""
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("z_L, range (mm)")
    title = "stripe profile" + (f", {misses} rays missed" if misses else "")
    if math.isfinite(profile.t_s):
        title += f", t = {profile.t_s:.4g} s"
    ax.set_title(title)
    ax.grid(True, lw=0.3)


def save_with_legends(fig: Any, out: Path, dpi: int, *legends: Any) -> None:
    """Save ``fig`` (laid out tight) with the legends' marks at a legible size."""
    for legend in legends:
        for handle in legend.legend_handles:  # legible dots, seam-point marks no larger
            if handle is not None and hasattr(handle, "set_markersize"):
                handle.set_markersize(LEGEND_MARKER_PT)
    fig.tight_layout()
    fig.savefig(out, dpi=dpi)


def plot_profile_2d(
    profile: Profile,
    path: str | Path,
    truth: Any = None,
    feature: Feature | None = None,
    *,
    figsize: tuple[float, float] = (7.0, 4.0),
    dpi: int = 110,
) -> Path:
    """Write a PNG of one stripe profile; see :func:`draw_profile_2d` for what is drawn.

    Parameters
    ----------
    profile : Profile
    path : str or Path
    truth : GroundTruth or (2,) float, optional
    feature : Feature, optional
    figsize : (2,) float
        Inches.
    dpi : int

    Returns
    -------
    Path
    """
    plt = pyplot_module()
    fig, ax = plt.subplots(figsize=figsize, constrained_layout=True)
    try:
        draw_profile_2d(ax, profile, truth=truth, feature=feature)
    except Exception:
        plt.close(fig)
        raise
    return save_figure(fig, path, dpi=dpi)


#: Marker size (points) of every legend entry of :func:`plot_profile_png`.
LEGEND_MARKER_PT = 5.0


def plot_profile_png(
    profile: Profile, path: str | Path, feature: Feature | None = None, *, dpi: int = 120
) -> Path:
    """Plot the stripe in the laser plane (y_L across, z_L down as the sensor looks) to a PNG.

    Valid points are drawn as a line of dots; invalid points that have a position are drawn
    faintly, one colour per :class:`~seamtrack.sensing.profiles.Reason`; a found ``feature`` is
    marked
    with its groove edges.

    Returns
    -------
    Path
        The file written.
    """
    plt = pyplot_module()
    out = prepare_file(path)
    assert profile.valid is not None and profile.reason is not None
    pts = profile.points_laser
    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    try:
        ax.plot(pts[profile.valid, 0], pts[profile.valid, 1], ".", ms=2, color="C0",
                label=f"valid ({int(profile.valid.sum())})")  # fmt: skip
        for code in Reason:
            if code is Reason.VALID or code is Reason.MISS:
                continue
            sel = (profile.reason == code) & np.isfinite(pts).all(axis=1)
            if sel.any():
                ax.plot(pts[sel, 0], pts[sel, 1], ".", ms=2, alpha=0.35,
                        label=f"{code.name.lower()} ({int(sel.sum())})")  # fmt: skip
        misses = int((profile.reason == Reason.MISS).sum())
        if feature:
            ax.plot(*feature.point_laser, "x", color="C3", ms=10, mew=2, label="seam point")
            if len(feature.edges_laser):
                ax.plot(feature.edges_laser[:, 0], feature.edges_laser[:, 1], "+", color="C3",
                        ms=9, label="edges")  # fmt: skip
        label_stripe_axes(ax, profile, misses)
        save_with_legends(fig, out, dpi, ax.legend(loc="best", fontsize=8, framealpha=0.8))
    finally:
        plt.close(fig)
    return out
