"""A profile to a CSV table (what ``seamtrack scan`` writes beside its PNG plot,
:func:`seamtrack.viz.plots.plot_profile_png`)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from seamtrack.io.output import prepare_file
from seamtrack.sensing.profiles import Profile, Reason

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
    out = prepare_file(path)
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
