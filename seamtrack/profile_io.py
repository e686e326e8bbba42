"""A profile to files: a CSV table and a PNG plot (what ``seamtrack scan`` writes).

matplotlib is imported inside :func:`plot_profile_png`, with the Agg backend, so importing this
module costs nothing and works without a display.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from .profiles import Feature, Profile, Reason

#: CSV columns written by :func:`write_profile_csv`.
CSV_COLUMNS = ("index", "y_L_mm", "z_L_mm", "x_mm", "y_mm", "z_mm", "valid", "reason")


def write_profile_csv(profile: Profile, path: str | Path) -> Path:
    """Write one row per stripe point: laser frame, world frame, validity and reason name.

    Parameters
    ----------
    profile : Profile
    path : str or Path
        Output file; its folder is created.

    Returns
    -------
    Path
        The file written. World columns are empty when the profile has no pose; coordinates
        are empty where they are NaN (a ray that hit nothing).
    """
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    laser = profile.points_laser
    world = profile.points_world if profile.T_world_sensor is not None else None
    assert profile.valid is not None and profile.reason is not None
    with out.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(CSV_COLUMNS)
        for i in range(len(profile)):
            world_cells = [_cell(v) for v in world[i]] if world is not None else ["", "", ""]
            writer.writerow([
                i, _cell(laser[i, 0]), _cell(laser[i, 1]), *world_cells,
                int(profile.valid[i]), Reason(int(profile.reason[i])).name,
            ])  # fmt: skip
    return out


def _cell(value: float) -> str:
    return "" if not math.isfinite(value) else repr(float(value))


def plot_profile_png(
    profile: Profile, path: str | Path, feature: Feature | None = None, *, dpi: int = 120
) -> Path:
    """Plot the stripe in the laser plane (y_L across, z_L down as the sensor looks) to a PNG.

    Valid points are drawn as a line of dots; invalid points that have a position are drawn
    faintly, one colour per :class:`~seamtrack.profiles.Reason`; a found ``feature`` is marked
    with its groove edges.

    Returns
    -------
    Path
        The file written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
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
        ax.invert_yaxis()
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("y_L (mm)")
        ax.set_ylabel("z_L, range (mm)")
        title = "stripe profile" + (f", {misses} rays missed" if misses else "")
        if math.isfinite(profile.t_s):
            title += f", t = {profile.t_s:.4g} s"
        ax.set_title(title)
        ax.grid(True, lw=0.3)
        ax.legend(loc="best", fontsize=8, markerscale=4)
        fig.tight_layout()
        fig.savefig(out, dpi=dpi)
    finally:
        plt.close(fig)
    return out
