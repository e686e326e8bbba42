"""Views of a multi-pass fill: a cross-section of the beads, the filled part in 3D, a GIF.

- :func:`draw_fill_section` / :func:`plot_fill_section`: the groove's cross-section at one
  station, the parent metal in grey and each pass's bead as a polygon coloured by pass
  (matplotlib, Agg backend, imported only when a plot is made).
- :func:`fill_plotter` / :func:`render_fill_png`: the part with its fill in 3D (PyVista, off
  screen when there is no display), the fill's top surface coloured by the pass that forms it.
- :func:`animate_fill`: a GIF of the groove filling at one station, one frame per pass.

Every view takes a :class:`seamtrack.workpiece.fill.FillState`; the beads of pass ``p`` are the
state's ``beads[p]``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.io.output import prepare_file
from seamtrack.viz.plots import pyplot_module, save_figure
from seamtrack.viz.run import gif_writer
from seamtrack.viz.sensor_view import pyvista_module
from seamtrack.viz.views import off_screen_mode
from seamtrack.workpiece.fill import FillState
from seamtrack.workpiece.inspection import LEVELS, Inspection

__all__ = [
    "animate_fill",
    "draw_fill_section",
    "fill_plotter",
    "pass_colors",
    "plot_fill_section",
    "plot_inspection",
    "plot_weld_sections",
    "render_fill_png",
    "weld_stations",
]

#: The parent metal's colour in the cross-section.
PLATE_COLOR = "#b0b4b8"


def pass_colors(n_passes: int) -> list[tuple[float, float, float, float]]:
    """One RGBA colour per pass (matplotlib's ``viridis``, first pass dark)."""
    plt = pyplot_module()
    cmap = plt.get_cmap("viridis")
    return [cmap(x) for x in np.linspace(0.0, 0.95, max(n_passes, 1))][:n_passes]


def draw_fill_section(
    ax: Any, state: FillState, station: int, *, passes: int | None = None, legend: bool = True
) -> list[Any]:
    """Draw the cross-section at ``station``: the plates and the first ``passes`` beads.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    state : FillState
    station : int
        Station index (``state.s_mm[station]`` is its arc length).
    passes : int, optional
        How many passes to draw (default all).

    Returns
    -------
    list of matplotlib.patches.Polygon
        One per pass drawn with a bead at this station, in pass order (their ``get_xy()`` is
        the bead's polygon (y, z) in mm).
    """
    from matplotlib.patches import Polygon

    i = int(station)
    n = state.n_passes if passes is None else min(int(passes), state.n_passes)
    y, base = state.y_mm, state.base_z[i]
    floor = base.min() - 3.0
    ax.fill_between(y, floor, base, color=PLATE_COLOR, lw=0, label="parent metal")
    colors = pass_colors(state.n_passes)
    patches = []
    for p in range(n):
        polygon = state.beads[p].polygon(y, i)
        if len(polygon) == 0:
            continue
        patch = Polygon(polygon, closed=True, fc=colors[p], ec="k", lw=0.4, label=f"pass {p + 1}")
        ax.add_patch(patch)
        patches.append(patch)
    top = state.beads[n - 1].z_after[i] if n else base
    ax.plot(y, top, color="k", lw=0.8)
    pts = state.groove_points(i) if n == state.n_passes else None
    if pts is not None:
        ax.plot(pts[:, 0], pts[:, 1], "o", ms=3, color="tab:red", label="7 groove points")
    ax.set_aspect("equal")
    ax.set_xlim(y[0], y[-1])
    ax.set_ylim(floor, max(state.plate_top[i].max(), float(top.max())) + 2.0)
    ax.set_xlabel("lateral y (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title(f"s = {state.s_mm[i]:.1f} mm, {n} pass(es)")
    if legend and patches:
        ax.legend(loc="upper right", fontsize=7, ncol=2)
    return patches


def plot_fill_section(
    state: FillState, station: int, path: str | Path, *, passes: int | None = None
) -> Path:
    """PNG of :func:`draw_fill_section` at ``station``; returns the path written."""
    plt = pyplot_module()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    draw_fill_section(ax, state, station, passes=passes)
    fig.tight_layout()
    return save_figure(fig, path)


def animate_fill(state: FillState, station: int, path: str | Path, *, fps: float = 2.0) -> Path:
    """GIF of the groove filling at ``station``: frame ``p`` shows passes 1..p+1.

    One frame per pass (``state.n_passes`` frames; at least one, the empty groove, when no
    pass was laid). Returns the path written (its folder is created).
    """
    plt = pyplot_module()
    out = prepare_file(path)
    append, finish = gif_writer(out, fps)
    fig, ax = plt.subplots(figsize=(6, 4))
    try:
        for p in range(1, state.n_passes + 1) if state.n_passes else [0]:
            ax.clear()
            draw_fill_section(ax, state, station, passes=p, legend=False)
            fig.tight_layout()
            fig.canvas.draw()
            append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
    finally:
        plt.close(fig)
    finish()
    return out


def fill_plotter(
    state: FillState,
    part_mesh: Any,
    *,
    off_screen: bool | None = None,
    window_size: tuple[int, int] = (1000, 700),
) -> Any:
    """A PyVista plotter of the part (grey) and its fill coloured by pass.

    The fill's mesh is ``state.mesh()`` (its ``pass`` vertex attribute the colour); the camera
    looks down the groove from above its start.
    """
    pv = pyvista_module()
    plotter = pv.Plotter(off_screen=off_screen_mode(off_screen), window_size=list(window_size))
    plotter.add_mesh(pv.wrap(part_mesh), color=PLATE_COLOR, name="part")
    fill = state.mesh()
    if len(fill.faces):
        poly = pv.wrap(fill)
        poly.point_data["pass"] = np.asarray(fill.vertex_attributes["pass"]) + 1
        plotter.add_mesh(
            poly,
            scalars="pass",
            cmap="viridis",
            clim=[1, max(state.n_passes, 2)],
            name="fill",
            scalar_bar_args={"title": "pass"},
        )
    T0 = state.T_world_station[0]
    centre = state.T_world_station[len(state.s_mm) // 2, :3, 3]
    eye = T0[:3, 3] - 60.0 * T0[:3, 0] + 80.0 * T0[:3, 2] + 30.0 * T0[:3, 1]
    plotter.camera_position = [tuple(eye), tuple(centre), tuple(T0[:3, 2])]
    return plotter


def render_fill_png(
    state: FillState,
    part_mesh: Any,
    path: str | Path,
    *,
    window_size: tuple[int, int] = (1000, 700),
) -> Path:
    """Render :func:`fill_plotter` off screen to a PNG; returns the path written."""
    out = prepare_file(path)
    plotter = fill_plotter(state, part_mesh, off_screen=True, window_size=window_size)
    try:
        plotter.screenshot(str(out))
    finally:
        plotter.close()
    return out


#: Line styles of ISO 5817's levels in the weld's pictures.
LEVEL_STYLES = {"B": ("tab:green", "--"), "C": ("tab:orange", "--"), "D": ("tab:red", ":")}


def weld_stations(state: FillState, inspection: Inspection) -> dict[str, int]:
    """The stations a weld's cross-sections show: its start, middle and end (of the welded
    stations the inspection judged) and its worst station (that of the imperfection with the
    worst level, the excess weld metal on a tie)."""
    s = np.asarray(state.s_mm)
    judged = np.searchsorted(s, inspection.s_mm)
    order = {lv: k for k, lv in enumerate((*LEVELS, ""))}
    worst = max(inspection.imperfections, key=lambda i: (order[i.level], i.worst_mm > 0))
    return {
        "start": int(judged[0]),
        "middle": int(judged[len(judged) // 2]),
        "end": int(judged[-1]),
        "worst": int(np.searchsorted(s, worst.worst_s_mm)),
    }


def _draw_limits(ax: Any, state: FillState, station: int, inspection: Inspection) -> None:
    """ISO 5817's excess weld metal limits above the plates' top line (B, C, D) and the
    incompletely-filled-groove limit below it (C), between the groove's top corners."""
    (y0, z0), (y1, z1) = state.top_corners[station]
    y = np.array([y0, y1])
    line = np.array([z0, z1])
    k = int(np.clip(np.searchsorted(inspection.s_mm, state.s_mm[station]), 0,
                    len(inspection.s_mm) - 1))  # fmt: skip
    excess = inspection["excess_weld_metal"].limit_mm
    for level, (color, style) in LEVEL_STYLES.items():
        ax.plot(y, line + excess[level][k], color=color, ls=style, lw=1.0,
                label=f"level {level}: excess weld metal")  # fmt: skip
    under = inspection["incompletely_filled_groove"].limit_mm["C"][k]
    ax.plot(y, line - under, color=LEVEL_STYLES["C"][0], ls="-.", lw=1.0,
            label="level C: deepest short underfill (B: none)")  # fmt: skip
    ax.plot(y, line, color="0.3", lw=0.8, label="plates' top line")


def plot_weld_sections(state: FillState, inspection: Inspection, path: str | Path) -> Path:
    """PNG of four cross-sections (start, middle, end, worst station), each bead coloured by
    pass, the 7 groove points and ISO 5817's limits; one legend below them all, clear of the
    cap beads. Returns the path written."""
    plt = pyplot_module()
    stations = weld_stations(state, inspection)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8), layout="constrained")
    for ax, (name, i) in zip(axes.flat, stations.items(), strict=True):
        draw_fill_section(ax, state, i, legend=False)
        _draw_limits(ax, state, i, inspection)
        (y0, _), (y1, _) = state.top_corners[i]
        ax.set_xlim(min(y0, y1) - 6.0, max(y0, y1) + 6.0)  # the groove and its toes
        bottom, top = ax.get_ylim()
        ax.set_ylim(bottom, max(top, max(line.get_ydata().max() for line in ax.lines) + 0.5))
        ax.set_title(f"{name}: s = {state.s_mm[i]:.1f} mm")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    seen = dict(zip(labels, handles, strict=True))
    fig.suptitle(f"ISO 5817 level met: {inspection.level or 'none'}")
    fig.legend(seen.values(), seen.keys(), loc="outside lower center", ncol=min(6, len(seen)),
               fontsize=7, frameon=False)  # fmt: skip
    return save_figure(fig, path)


def plot_inspection(inspection: Inspection, path: str | Path) -> Path:
    """PNG along the seam: each imperfection's measure and ISO 5817's limits for B, C and D;
    the stations where a level is missed are marked. Returns the path written."""
    plt = pyplot_module()
    s = inspection.s_mm
    fig, axes = plt.subplots(len(inspection.imperfections), 1, figsize=(9, 8), sharex=True)
    for ax, imperfection in zip(axes, inspection.imperfections, strict=True):
        ax.plot(s, imperfection.value_mm, color="k", lw=1.0, label="measured")
        for level, (color, style) in LEVEL_STYLES.items():
            limit = imperfection.limit_mm[level]
            if np.all(np.isfinite(limit)):
                ax.plot(s, limit, color=color, ls=style, lw=1.0, label=f"level {level}")
            bad = np.isnan(limit) & (imperfection.value_mm > 0) | (
                imperfection.value_mm > np.nan_to_num(limit, nan=np.inf) + 1e-9
            )
            if bad.any():
                ax.plot(s[bad], imperfection.value_mm[bad], "x", color=color, ms=4,
                        label=f"over level {level}")  # fmt: skip
        name = imperfection.name.replace("_", " ")
        if imperfection.name == "undercut":
            name += " (not modelled: the bead model cuts no groove beside a toe)"
        ax.set_title(f"{name}: level {imperfection.level or 'none'}", fontsize=9)
        ax.set_ylabel("mm" if imperfection.name != "lack_of_fusion" else "unfused")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=7, frameon=False)
    axes[-1].set_xlabel("s along the seam (mm)")
    fig.suptitle(f"ISO 5817 along the seam: level {inspection.level or 'none'} met")
    fig.tight_layout()
    return save_figure(fig, path)
