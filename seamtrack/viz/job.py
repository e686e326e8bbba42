"""A multi-pass job's pictures, written into its run folder beside ``job.json``:

- ``weld.png``: the cross-sections at the weld's start, middle, end and worst station, each bead
  coloured by pass, with the 7 groove points and ISO 5817's limits;
- ``inspection.png``: each imperfection along the seam against the limits of levels B, C, D;
- ``fill.png``: the part with its fill in 3D, the top surface coloured by pass.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from seamtrack.multipass.summary import inspect_job
from seamtrack.viz.fill import plot_inspection, plot_weld_sections, render_fill_png

#: The pictures a job's folder holds, by file name.
JOB_PICTURES = ("weld.png", "inspection.png", "fill.png")


def write_job_pictures(job: Any, scene: Any, folder: str | Path) -> list[Path]:
    """Draw :data:`JOB_PICTURES` for a finished job into ``folder``; returns the paths written
    (without the ISO pictures when the weld could not be judged, e.g. plate of 3 mm or less)."""
    from seamtrack.simulation.assemble import build_parts

    folder = Path(folder)
    welded = [r for r in job.passes if r.plan is not None]
    written = []
    weld = inspect_job(scene, job.fill, welded) if welded else None
    if weld is not None:
        written.append(plot_weld_sections(job.fill, weld, folder / "weld.png"))
        written.append(plot_inspection(weld, folder / "inspection.png"))
    part = build_parts(scene).mesh
    written.append(render_fill_png(job.fill, part, folder / "fill.png"))
    return written
