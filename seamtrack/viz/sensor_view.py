"""The sensor drawn in PyVista: its housing, emitter, camera, laser fan and field of view, in
the laser frame {L}, posed in the world with each actor's ``user_matrix``; and the import of
PyVista with the ``pip install`` that fixes its absence. Views are built in
:mod:`seamtrack.viz.views`.
"""

from __future__ import annotations

import ctypes.util
import math
import os
import sys
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from seamtrack.sensing.sensor import LaserLineSensor

PIP_HINT = "pip install pyvista"
_LASER_COLOR = "#e8161b"
_FOV_COLOR = "#17a2b8"
_HOUSING_COLOR = "#4d4d4d"
_CAMERA_COLOR = "#1f77b4"


#: VTK's off-screen render windows by the library each needs (VTK's runtime settings,
#: https://docs.vtk.org/en/latest/advanced/runtime_settings.html#opengl), in VTK's own order.
_HEADLESS_WINDOWS = (("EGL", "vtkEGLRenderWindow"), ("OSMesa", "vtkOSOpenGLRenderWindow"))


def has_display() -> bool:
    """True when an interactive window can open (Windows, macOS, or X11/Wayland on Linux)."""
    if sys.platform in ("win32", "darwin"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def headless_window() -> str | None:
    """Without a display, choose VTK's off-screen render window (EGL, else OSMesa) through
    ``VTK_DEFAULT_OPENGL_WINDOW`` (unless the user set it), before any window is made: VTK
    would otherwise try X first and print a "bad X server connection" warning before falling
    back. Returns the window class chosen, or None (a display, the user's choice, or neither
    library found)."""
    if has_display() or os.environ.get("VTK_DEFAULT_OPENGL_WINDOW"):
        return None
    for library, window in _HEADLESS_WINDOWS:
        if ctypes.util.find_library(library):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = window
            return window
    return None


def pyvista_module() -> Any:
    try:
        import pyvista as pv
    except ImportError as exc:
        raise ImportError(f"seamtrack's 3D views need PyVista: {PIP_HINT}") from exc
    headless_window()
    return pv


def polyline_mesh(pv: Any, points: ArrayLike) -> Any:
    pts = np.asarray(points, dtype=np.float64)
    return pv.lines_from_points(pts) if len(pts) > 1 else pv.PolyData(pts)


def sensor_meshes(pv: Any, sensor: LaserLineSensor) -> dict[str, Any]:
    """The sensor's parts as PyVista meshes in the laser frame (x_L, y_L, z_L).

    Returns
    -------
    dict
        ``housing``, ``emitter``, ``camera``, ``baseline``, ``optical_axis``, ``fan``, ``fov``
        (the trapezoid's outline) and ``fov_fill``.
    """
    b = sensor.baseline_mm
    near, far = sensor.range_near_mm, sensor.range_far_mm
    w_near, w_far = float(sensor.half_width_mm(near)), float(sensor.half_width_mm(far))
    standoff = sensor.standoff_mm if math.isfinite(sensor.standoff_mm) else 0.5 * near
    front = max(near - standoff, 0.0)
    depth = max(0.6 * standoff, 0.6 * b)
    half_y = max(0.6 * w_near, 0.2 * b)
    housing = pv.Box(bounds=(-0.25 * b, 1.25 * b, -half_y, half_y, front - depth, front))
    radius = 0.06 * b
    tan_max = w_near / near  # the fan opens like scan.laser_fan: over the near width
    angles = np.linspace(-math.atan(tan_max), math.atan(tan_max), 33)
    rim = np.column_stack([np.zeros_like(angles), far * np.tan(angles), np.full_like(angles, far)])
    fan_points = np.vstack([[0.0, 0.0, 0.0], rim])
    fan_faces = np.hstack([[3, 0, k, k + 1] for k in range(1, len(rim))])
    corners = np.array(
        [[0, -w_near, near], [0, w_near, near], [0, w_far, far], [0, -w_far, far]], dtype=np.float64
    )
    crossing = np.array([0.0, 0.0, sensor.range_center_mm])
    camera = np.asarray(sensor.camera_center_laser, dtype=np.float64)
    return {
        "housing": housing,
        "emitter": pv.Sphere(radius=radius, center=(0.0, 0.0, 0.0)),
        "camera": pv.Sphere(radius=1.3 * radius, center=tuple(camera)),
        "baseline": polyline_mesh(pv, np.vstack([np.zeros(3), camera])),
        "optical_axis": polyline_mesh(pv, np.vstack([camera, crossing])),
        "fan": pv.PolyData(fan_points, faces=fan_faces),
        "fov": polyline_mesh(pv, np.vstack([corners, corners[:1]])),
        "fov_fill": pv.PolyData(corners, faces=[4, 0, 1, 2, 3]),
    }


def sensor_legend() -> list[dict[str, str]]:
    """The sensor's parts as legend entries (``label``, ``color``, ``face``) for
    ``pyvista.Plotter.add_legend``, in the colours :func:`add_sensor` draws them."""
    return [
        {"label": "sensor housing (box)", "color": _HOUSING_COLOR, "face": "rectangle"},
        {"label": "laser emitter (red sphere)", "color": _LASER_COLOR, "face": "circle"},
        {"label": "camera centre (blue sphere)", "color": _CAMERA_COLOR, "face": "circle"},
        {"label": "laser fan", "color": _LASER_COLOR, "face": "triangle"},
        {"label": "field of view", "color": _FOV_COLOR, "face": "rectangle"},
    ]


def add_sensor(plotter: Any, sensor: LaserLineSensor, T_world_sensor: ArrayLike) -> list[Any]:
    """Draw the sensor at a pose; returns its actors (move them with ``actor.user_matrix``)."""
    pv = pyvista_module()
    parts = sensor_meshes(pv, sensor)
    styles: dict[str, dict[str, Any]] = {
        "housing": {"color": _HOUSING_COLOR, "opacity": 0.35},
        "emitter": {"color": _LASER_COLOR},
        "camera": {"color": _CAMERA_COLOR},
        "baseline": {"color": "black", "line_width": 3},
        "optical_axis": {"color": _CAMERA_COLOR, "line_width": 1, "opacity": 0.6},
        "fan": {"color": _LASER_COLOR, "opacity": 0.22, "show_edges": False},
        "fov": {"color": _FOV_COLOR, "line_width": 3},
        "fov_fill": {"color": _FOV_COLOR, "opacity": 0.15},
    }
    T = np.asarray(T_world_sensor, dtype=np.float64)
    actors = []
    for key, mesh in parts.items():
        actor = plotter.add_mesh(
            mesh,
            name=f"sensor-{key}",
            lighting=key in ("housing", "emitter", "camera"),
            **styles[key],
        )
        actor.user_matrix = T
        actors.append(actor)
    return actors
