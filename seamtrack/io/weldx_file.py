"""A run as a weldx file (BAM's open format for welding data, https://weldx.readthedocs.io).

``seamtrack run SCENE --weldx run.wx`` writes, with units throughout (pint quantities):

- ``groove``: the ISO 9692-1 groove as a weldx groove object, when the scene gives one
  (``workpiece.groove``);
- ``workpiece``: the part's source and the seam's name and joint type;
- ``seam``: the true seam, ``points`` (n, 3) mm and unit ``torch_normals`` (n, 3);
- ``tcp``: the torch tip's path as a time-dependent ``LocalCoordinateSystem`` (world frame);
- ``trace``: ``TimeSeries`` of the error (total, lateral, vertical) and ``target``, ``seam_point``
  and ``arc_length`` at the times of ``trace.csv``, and ``welding`` (flags);
- ``sensor``: its geometry (baseline, laser-camera angle, range, depth of field, fields of view,
  resolutions), frame rate, latency, look-ahead, preset name, and the mount ``T_tcp_sensor``;
- ``summary``: the dict of ``summary.json`` (units in its key names), and ``scene``: the scene
  as run (TOML text).

The trace arrays hold the rows of ``trace.csv`` at full precision (the CSV prints 6 decimals);
the summary equals ``summary.json``. weldx is an optional extra: ``pip install
'seamtrack[weldx]'``.
"""

from __future__ import annotations

import io
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack._version import __version__
from seamtrack.errors import OutputError, SeamtrackError
from seamtrack.io.output import check_writable, json_safe


def require_weldx(field: str = "--weldx") -> Any:
    """``weldx``, or an error saying which ``pip install`` brings it."""
    try:
        import weldx
    except ImportError:
        raise SeamtrackError(
            "weldx is not installed", field=field, fix="pip install 'seamtrack[weldx]'"
        ) from None
    return weldx


def check_weldx_target(path: str | Path) -> Path:
    """Refuse, before a run, a weldx target that cannot be written (nothing is created)."""
    require_weldx()
    target = Path(path)
    if target.is_dir():
        raise OutputError(f"{str(target)!r} is a folder", field="--weldx", fix="give a file path")
    check_writable(target.parent if str(target.parent) else Path("."), field="--weldx")
    return target


def _sensor_tree(weldx: Any, parts: Any, scene: Any) -> dict[str, Any]:
    Q_ = weldx.Q_
    sensor, cfg = parts.sensor, scene.config.sensor
    return {
        "preset": cfg.preset,
        "mode": cfg.mode,
        "baseline": Q_(sensor.baseline_mm, "mm"),
        "laser_camera_angle": Q_(math.degrees(sensor.angle_rad), "deg"),
        "range_center": Q_(sensor.range_center_mm, "mm"),
        "depth_of_field": Q_(sensor.depth_of_field_mm, "mm"),
        "fov_near": Q_(sensor.fov_near_mm, "mm"),
        "fov_far": Q_(sensor.fov_far_mm, "mm"),
        "depth_resolution": Q_(sensor.depth_resolution_mm, "mm"),
        "lateral_resolution": Q_(sensor.lateral_resolution_mm, "mm"),
        "frame_rate": Q_(cfg.frame_rate_hz, "Hz"),
        "latency": Q_(cfg.latency_s, "s"),
        "look_ahead": Q_(cfg.look_ahead_mm, "mm"),
        "rays": cfg.rays,
        "extractor": parts.extractor_name,
        "T_tcp_sensor": {
            "rotation": parts.robot.T_tcp_sensor[:3, :3].tolist(),
            "translation": Q_(parts.robot.T_tcp_sensor[:3, 3], "mm"),
        },
    }


def weldx_tree(result: Any, scene: Any, parts: Any, trace_period_s: float) -> dict[str, Any]:
    """The tree :func:`write_weldx` writes (see the module docstring)."""
    weldx = require_weldx()
    Q_ = weldx.Q_
    tr = result.trace
    idx = tr.decimated(trace_period_s)
    t = Q_(np.asarray(tr.t_s[idx], dtype=float), "s")

    def series(values: Any, unit: str) -> Any:
        return weldx.TimeSeries(data=Q_(np.asarray(values, dtype=float), unit), time=t)

    tree: dict[str, Any] = {
        "seamtrack": {"version": __version__, "scene_name": scene.name},
        "scene": scene.to_toml(),
        "summary": json_safe(result.summary),
        "seam": {
            "points": Q_(parts.seam.points, "mm"),
            "torch_normals": np.asarray(parts.seam.normals),
        },
        "tcp": weldx.LocalCoordinateSystem(
            coordinates=Q_(np.asarray(tr.tcp_world[idx], dtype=float), "mm"), time=t
        ),
        "trace": {
            "error": series(tr.error_mm[idx], "mm"),
            "error_lateral": series(tr.error_lateral_mm[idx], "mm"),
            "error_vertical": series(tr.error_vertical_mm[idx], "mm"),
            "target": Q_(np.asarray(tr.target_world[idx], dtype=float), "mm"),
            "seam_point": Q_(np.asarray(tr.closest_world[idx], dtype=float), "mm"),
            "arc_length": Q_(np.asarray(tr.arc_length_mm[idx], dtype=float), "mm"),
            "welding": np.asarray(tr.welding[idx], dtype=bool),
        },
        "sensor": _sensor_tree(weldx, parts, scene),
    }
    w = scene.config.workpiece
    if w is not None:
        tree["workpiece"] = {
            "source": w.script or w.step or "groove",
            "seam": parts.seam.name,
            "params": json_safe(dict(w.params)),
        }
        if w.groove is not None:
            from seamtrack.workpiece.grooves import groove_object, groove_spec

            tree["groove"] = groove_object(groove_spec(w.groove))
    return tree


def write_weldx(
    result: Any, scene: Any, parts: Any, path: str | Path, trace_period_s: float = 0.01
) -> Path:
    """Write the run as a weldx file, whole or not at all (a temporary file moved in place)."""
    weldx = require_weldx()
    target = Path(path)
    tree = weldx_tree(result, scene, parts, trace_period_s)
    folder = target.parent if str(target.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    buffer = io.BytesIO()  # weldx leaves file handles open; a buffer it cannot leak
    with weldx.WeldxFile(buffer, tree=tree, mode="rw"):
        pass
    handle, tmp = tempfile.mkstemp(prefix=".partial-", suffix=".wx", dir=folder)
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(buffer.getvalue())
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def read_weldx(path: str | Path) -> Any:
    """Open a weldx file for reading (from memory: weldx would leave the file open); use it
    as a context manager."""
    weldx = require_weldx()
    return weldx.WeldxFile(io.BytesIO(Path(path).read_bytes()))
