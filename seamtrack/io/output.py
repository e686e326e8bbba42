"""Run outputs: summary.json, trace.csv, frames.csv, scene.toml and error.png, written whole.

Files are first written into a hidden staging folder next to the destination and moved into
place only when all of them are complete, so a failed run leaves nothing half-written.
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
from typing import Any

import numpy as np

from seamtrack.errors import OutputError
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
)


def prepare_dir(path: str | Path, field: str = "--out") -> Path:
    """Create ``path`` (and parents) and prove it writable, or raise :class:`OutputError`."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=out, prefix=".probe-"):
            pass
    except OSError as exc:
        raise OutputError(
            f"cannot write to {str(out)!r}: {exc.strerror or exc}",
            field=field,
            fix="choose a folder you can write to",
        ) from None
    return out


@contextmanager
def staged(out_dir: str | Path) -> Iterator[Path]:
    """Yield a staging folder; on success move its files into ``out_dir``, else delete it."""
    out = prepare_dir(out_dir)
    stage = Path(tempfile.mkdtemp(prefix=".partial-", dir=out))
    try:
        yield stage
        for item in sorted(stage.iterdir()):
            os.replace(item, out / item.name)
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
        ]
    )
    np.savetxt(path, table, delimiter=",", header=",".join(TRACE_COLUMNS), comments="", fmt="%.6f")


def write_frames_csv(result: Result, path: Path) -> None:
    f = result.trace.frames
    table = np.column_stack([f["t_capture_s"], f["found"].astype(float), f["point_world"]])
    np.savetxt(
        path,
        table,
        delimiter=",",
        header="t_capture_s,found,x_mm,y_mm,z_mm",
        comments="",
        fmt="%.6f",
    )


def write_run(
    result: Result,
    out_dir: str | Path,
    scene_toml: str | None = None,
    trace_period_s: float = 0.01,
    extra: Callable[[Path], object] | None = None,
) -> Path:
    """Write a run's outputs into ``out_dir`` (see the module docstring); ``extra(stage)`` adds
    files (e.g. the error plot) to the staged folder before it is moved into place."""
    with staged(out_dir) as stage:
        (stage / "summary.json").write_text(json.dumps(json_safe(result.summary), indent=2) + "\n")
        write_trace_csv(result, stage / "trace.csv", trace_period_s)
        write_frames_csv(result, stage / "frames.csv")
        if scene_toml is not None:
            (stage / "scene.toml").write_text(scene_toml)
        if extra is not None:
            extra(stage)
    return Path(out_dir)
