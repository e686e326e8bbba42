"""Run outputs: summary.json, trace.csv, frames.csv, scene.toml and error.png, written whole.

Files are first written into a hidden staging folder next to the destination and moved into
place only when all of them are complete, so a failed run leaves nothing half-written.

Two runs never share a folder (:func:`check_fresh`): a run goes into a new or empty folder; a
folder that holds an earlier seamtrack output is replaced whole only with ``--force``, once
the new output is complete; a folder holding anything else is never written into.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from seamtrack.errors import OutputError

if TYPE_CHECKING:
    from seamtrack.simulation.loop import Result

TRACE_COLUMNS = (
    "t_s",
    "tcp_x_mm",
    "tcp_y_mm",
    "tcp_z_mm",
    "target_x_mm",
    "target_y_mm",
    "target_z_mm",
    "error_mm",
    "error_lateral_mm",
    "error_vertical_mm",
    "seam_x_mm",
    "seam_y_mm",
    "seam_z_mm",
    "arc_length_mm",
    "welding",
    "work_angle_error_deg",
    "travel_angle_error_deg",
)


def check_writable(path: str | Path, field: str = "--out") -> Path:
    """Prove that the folder ``path`` can be written (or created) without creating anything,
    or raise :class:`OutputError`: a refused run leaves no empty folder behind."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise OutputError(
            f"{str(out)!r} is a file, not a folder", field=field, fix="give a folder path"
        )
    existing = out.absolute()
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise OutputError(
            f"{str(existing)!r} is a file, so {str(out)!r} cannot be a folder",
            field=field,
            fix="give a folder path",
        )
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(
            f"cannot write to {str(existing)!r}: permission denied",
            field=field,
            fix="choose a folder you can write to",
        )
    return out


#: The files that make a folder seamtrack's own output, each set enough: a run, a job, a real
#: set (``extractors import``).
OWN_OUTPUTS = (("summary.json", "scene.toml"), ("job.json", "scene.toml"), ("set.json",))


def is_own_output(folder: Path) -> bool:
    """Whether ``folder`` holds an output seamtrack wrote (:data:`OWN_OUTPUTS`)."""
    return any(all((folder / name).is_file() for name in names) for names in OWN_OUTPUTS)


def check_fresh(path: str | Path, force: bool = False, field: str = "--out") -> bool:
    """Refuse to mix a new output with an old one: ``True`` when ``path`` holds an earlier
    seamtrack output that ``force`` lets the new one replace whole, ``False`` when it is new
    or empty; else :class:`OutputError` (checked before the run, nothing written)."""
    out = check_writable(path, field)
    if not out.is_dir() or not any(out.iterdir()):
        return False
    if not is_own_output(out):
        raise OutputError(
            f"{str(out)!r} is not empty and holds no seamtrack output",
            field=field,
            fix="give a new or empty folder (seamtrack never deletes files it did not write)",
        )
    if not force:
        raise OutputError(
            f"{str(out)!r} holds an earlier output",
            field=field,
            fix="add --force to replace it whole, or give a new folder",
        )
    return True


def prepare_dir(path: str | Path, field: str = "--out") -> Path:
    """Create ``path`` (and parents), once there is something to write into it."""
    out = check_writable(path, field)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(
            f"cannot write to {str(out)!r}: {exc.strerror or exc}",
            field=field,
            fix="choose a folder you can write to",
        ) from None
    return out


def prepare_file(path: str | Path, field: str = "--out") -> Path:
    """``path`` with its folder created (and parents), ready for a writer to write the file
    into; :class:`OutputError` where that folder cannot be (a file stands in the way, no
    permission)."""
    out = Path(path)
    prepare_dir(out.parent, field)
    return out


@contextmanager
def new_dir(path: str | Path, field: str = "--out") -> Iterator[Path]:
    """Create ``path`` for writing; if the block fails and the folder is still empty, remove
    the folders this call created (an existing folder is left as it was)."""
    out = check_writable(path, field)
    created = []
    probe = out.absolute()
    while not probe.exists():
        created.append(probe)
        probe = probe.parent
    prepare_dir(out, field)
    try:
        yield out
    except BaseException:
        for folder in created:  # innermost first
            try:
                folder.rmdir()  # only if empty
            except OSError:
                break
        raise


@contextmanager
def staged(out_dir: str | Path, replace: bool = False) -> Iterator[Path]:
    """Yield a staging folder; on success move its files into ``out_dir`` (``replace``: after
    removing what ``out_dir`` held before, so old and new never mix), else delete it."""
    with new_dir(out_dir) as out:
        stage = Path(tempfile.mkdtemp(prefix=".partial-", dir=out))
        try:
            yield stage
            for old in sorted(out.iterdir()) if replace else ():
                if old == stage:
                    continue
                if old.is_dir() and not old.is_symlink():
                    shutil.rmtree(old)
                else:
                    old.unlink()
            for item in sorted(stage.iterdir()):
                target = out / item.name
                if item.is_dir() and target.is_dir():  # a job's pass folder from a run before
                    shutil.rmtree(target)
                os.replace(item, target)
        finally:
            shutil.rmtree(stage, ignore_errors=True)


def json_safe(value: Any) -> Any:
    """Plain JSON values: numpy scalars to Python, NaN to None."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_trace_csv(result: Result, path: Path, period_s: float) -> None:
    tr = result.trace
    idx = tr.decimated(period_s)
    table = np.column_stack(
        [
            tr.t_s[idx],
            tr.tcp_world[idx],
            tr.target_world[idx],
            tr.error_mm[idx],
            tr.error_lateral_mm[idx],
            tr.error_vertical_mm[idx],
            tr.closest_world[idx],
            tr.arc_length_mm[idx],
            tr.welding[idx].astype(float),
            np.degrees(tr.work_angle_error_rad[idx]),
            np.degrees(tr.travel_angle_error_rad[idx]),
            np.degrees(tr.joints_rad[idx]),  # an arm's joints (none for the gantry)
        ]
    )
    joints = [f"q{j + 1}_deg" for j in range(tr.joints_rad.shape[1])]
    if len(tr.seam_shift_mm):  # [distortion] only: other runs' traces stay as they were
        table = np.column_stack([table, tr.seam_shift_mm[idx]])
        joints.append("seam_shift_mm")
    header = ",".join([*TRACE_COLUMNS, *joints])
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.6f")


def write_frames_csv(result: Result, path: Path) -> None:
    """One row per sensor frame: its capture time, ``found`` as 0 or 1 (an integer, not
    ``1.000000``), and the seam point found (NaN where none was)."""
    f = result.trace.frames
    table = np.column_stack([f["t_capture_s"], f["found"].astype(float), f["point_world"]])
    np.savetxt(
        path,
        table,
        delimiter=",",
        header="t_capture_s,found,x_mm,y_mm,z_mm",
        comments="",
        fmt=["%.6f", "%d", "%.6f", "%.6f", "%.6f"],
    )


def write_run(
    result: Result,
    out_dir: str | Path,
    scene_toml: str | None = None,
    trace_period_s: float = 0.01,
    extra: Callable[[Path], object] | None = None,
    replace: bool = False,
) -> Path:
    """Write a run's outputs into ``out_dir`` (see the module docstring); ``extra(stage)`` adds
    files (e.g. the error plot) to the staged folder before it is moved into place;
    ``replace``: what ``out_dir`` held is removed first (:func:`check_fresh`)."""
    with staged(out_dir, replace) as stage:
        (stage / "summary.json").write_text(json.dumps(json_safe(result.summary), indent=2) + "\n")
        write_trace_csv(result, stage / "trace.csv", trace_period_s)
        write_frames_csv(result, stage / "frames.csv")
        if scene_toml is not None:
            (stage / "scene.toml").write_text(scene_toml)
        if extra is not None:
            extra(stage)
    return Path(out_dir)


def write_job(
    job: Any,
    out_dir: str | Path,
    scene_toml: str | None = None,
    trace_period_s: float = 0.01,
    extra: Callable[[Any, Path], object] | None = None,
    finish: Callable[[Path], object] | None = None,
    replace: bool = False,
) -> Path:
    """Write a multi-pass job (:class:`seamtrack.multipass.job.JobResult`) into ``out_dir``:
    one folder a pass (``pass_00_scan``, ``pass_01``, ...: a run's summary.json, trace.csv,
    frames.csv and scene.toml, plus what ``extra(record, folder)`` adds), ``job.json`` and the
    job's scene.toml, then what ``finish(folder)`` adds (the job's pictures); all staged and
    moved into place at the end, so a failed or interrupted job writes nothing. ``replace``: as
    :func:`write_run`'s."""
    with staged(out_dir, replace) as stage:
        for record in job.passes:
            folder = stage / record.name
            folder.mkdir()
            summary = json.dumps(json_safe(record.result.summary), indent=2)
            (folder / "summary.json").write_text(summary + "\n")
            write_trace_csv(record.result, folder / "trace.csv", trace_period_s)
            write_frames_csv(record.result, folder / "frames.csv")
            (folder / "scene.toml").write_text(record.scene.to_toml())
            if extra is not None:
                extra(record, folder)
        (stage / "job.json").write_text(json.dumps(json_safe(job.summary), indent=2) + "\n")
        if scene_toml is not None:
            (stage / "scene.toml").write_text(scene_toml)
        if finish is not None:
            finish(stage)
    return Path(out_dir)
