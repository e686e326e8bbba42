"""3D views of a scene with PyVista: workpiece, seam, sensor, laser fan, field of view, stripe.

Nothing low-level imports this module, and PyVista is imported only when a view is built (an
``ImportError`` names ``pip install pyvista`` when it is missing), so seam-mode runs never load
it. What a view shows, all in the world frame (mm):

- the workpiece mesh (mesh mode) and the true seam polyline;
- the sensor at a pose ``T_world_sensor`` (the laser frame {L}): a housing box behind the
  emitter (its front face ``standoff_mm`` before the near end of the depth of field), the
  emitter and the camera centre joined by the baseline, the camera's optical axis, the laser fan
  (the plane x_L = 0, from the emitter to the far end of the range, half transparent) and the
  trapezoidal field of view (near and far widths, Eq. 5-6);
- the stripe, one point per ray coloured by its :class:`~seamtrack.sensing.profiles.Reason` (misses
at
  the far end of their ray), and the seam point the extractor found (seam mode: the crossing);
- after a run: the torch path coloured by the tracking error, and the sensed seam points.

Interactive when a display exists (in Jupyter through the ``trame`` backend, ``static`` in a
headless notebook); off screen, to a PNG, when not. ``pv.OFF_SCREEN = True`` (or the
environment variable ``PYVISTA_OFF_SCREEN=true``) forces off-screen rendering.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.control.robot import CartesianRobot
from seamtrack.geometry.frames import apply, look_rotation, make
from seamtrack.geometry.seam import Seam
from seamtrack.io.output import prepare_file
from seamtrack.sensing.profiles import Feature, Profile, Reason
from seamtrack.sensing.sensor import LaserLineSensor
from seamtrack.viz.plots import REASON_COLORS, plot_profile_2d
from seamtrack.viz.sensor_view import PIP_HINT as PIP_HINT  # re-exported
from seamtrack.viz.sensor_view import (
    add_sensor,
    polyline_mesh,
    pyvista_module,
    sensor_legend,
)
from seamtrack.viz.sensor_view import has_display as has_display  # re-exported
from seamtrack.viz.sensor_view import sensor_meshes as sensor_meshes  # re-exported

__all__ = [
    "SceneView",
    "add_sensor",
    "has_display",
    "plot_profile_2d",
    "render_png",
    "scene_plotter",
    "scene_view",
    "show",
]

FloatArray = NDArray[np.float64]
ScanFn = Callable[[FloatArray, float], "tuple[Profile, Feature]"]
SenseFn = Callable[[FloatArray, float], Feature]

_MESH_COLOR = "#b8c4d6"
_SEAM_COLOR = "#1f3b99"
FEATURE_COLOR = "#ffd700"
_TORCH_COLOR = "#c08000"
_LIFT_MM = 0.2


# --------------------------------------------------------------------------- environment
def in_notebook() -> bool:
    """True inside a Jupyter kernel (IPython is not imported to find out)."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    shell = ipython.get_ipython()
    return shell is not None and type(shell).__name__ == "ZMQInteractiveShell"


def off_screen_mode(off_screen: bool | None) -> bool:
    if off_screen is not None:
        return bool(off_screen)
    return bool(pyvista_module().OFF_SCREEN) or not has_display()


def jupyter_backend() -> str:
    """``"trame"`` (interactive) in a notebook with a display, else ``"static"`` (an image)."""
    return "trame" if has_display() and not pyvista_module().OFF_SCREEN else "static"


# --------------------------------------------------------------------------- the scene
@dataclass(frozen=True, eq=False)
class SceneView:
    """What a view needs from a scene: the seam, the sensor and how it is posed and scans.

    Attributes
    ----------
    seam : Seam
        The true seam, world frame.
    sensor : LaserLineSensor
    name : str
    mesh : trimesh.Trimesh or None
        The workpiece in the world frame (mesh mode); None in seam mode.
    robot : CartesianRobot, ArticulatedRobot or None
        Poses the sensor (``robot.T_world_sensor``; an arm: its joints solved for the tool
        pose of ``tool_program`` at the torch); None: mounted ``look_ahead_mm`` ahead of
        the torch along the seam, ``sensor.range_center_mm`` above it along the torch normal.
    look_ahead_mm : float
    scan : callable or None
        ``scan(T_world_sensor, t_s) -> (Profile, Feature)`` (a mesh-mode scene's own); None
        with a mesh: ``sensor.scan`` and the ``extractor`` named below.
    sense : callable or None
        ``sense(T_world_sensor, t_s) -> Feature`` (seam mode); None: the ideal crossing.
    extractor : str
        Feature extractor used when ``scan`` is None.
    tool_program : ToolProgram or None
        An arm's tool orientations along the seam (the robot program).
    """

    seam: Seam
    sensor: LaserLineSensor
    name: str = "scene"
    mesh: Any = None
    robot: CartesianRobot | None = None
    look_ahead_mm: float = 10.0
    scan: ScanFn | None = None
    sense: SenseFn | None = None
    extractor: str = "v-groove"
    tool_program: Any = None

    @property
    def is_arm(self) -> bool:
        """True when an articulated arm carries the torch (it is drawn, and turns its tool)."""
        return self.robot is not None and bool(getattr(self.robot, "turns_tool", False))

    @cached_property
    def _arm_plan(self) -> tuple[FloatArray, FloatArray]:
        from seamtrack.simulation.robots import plan_along

        return plan_along(self.robot, self.tool_program)

    def joints_at_tcp(self, tcp_world: ArrayLike) -> FloatArray:
        """(n,) an arm's joints (rad) with the torch tip at ``tcp_world`` and the tool turned
        as the robot program says at the closest seam point (solved from the plan there)."""
        assert self.is_arm and self.tool_program is not None
        robot: Any = self.robot
        tcp = np.asarray(tcp_world, dtype=np.float64)
        s_plan, joints = self._arm_plan
        s = float(self.tool_program.seam.closest(tcp[None]).arc_length_mm[0])
        seed = joints[int(np.argmin(np.abs(s_plan - s)))]
        T_world_tcp = make(self.tool_program.rotations([s])[0], tcp)
        result = robot.kinematics.ik(robot._T_base_world @ T_world_tcp, seed)
        return np.asarray(result.q) if result else seed

    def tcp_at(self, at_mm: float) -> FloatArray:
        """(3,) the torch tip on the seam at arc length ``at_mm``."""
        return np.asarray(self.seam.interpolate([at_mm])[0])

    def pose_at_tcp(self, tcp_world: ArrayLike) -> FloatArray:
        """(4, 4) ``T_world_sensor`` with the torch tip at ``tcp_world``."""
        tcp = np.asarray(tcp_world, dtype=np.float64)
        if self.is_arm:
            return self.T_world_tcp(tcp) @ self.robot.T_tcp_sensor  # type: ignore[union-attr]
        if self.robot is not None:
            return self.robot.T_world_sensor(self.robot.q_from_world(tcp))
        return self.T_world_tcp(tcp) @ make(
            look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0]),
            [self.look_ahead_mm, 0.0, self.sensor.range_center_mm],
        )

    def T_world_tcp(self, tcp_world: ArrayLike) -> FloatArray:
        """(4, 4) torch frame: at the tip, z up the torch, x along the travel."""
        tcp = np.asarray(tcp_world, dtype=np.float64)
        if self.is_arm:
            return self.T_world_tcp_at_joints(self.joints_at_tcp(tcp))
        if self.robot is not None:
            return self.robot.T_world_tcp(self.robot.q_from_world(tcp))
        closest = self.seam.closest(tcp[None])
        seg = int(closest.segment[0])
        tangent = self.seam.tangent_at(closest.arc_length_mm)[0]
        return make(look_rotation(self.seam.normals[seg], tangent), tcp)

    def T_world_tcp_at_joints(self, joints: ArrayLike) -> FloatArray:
        """(4, 4) an arm's torch frame at joint positions (rad)."""
        robot: Any = self.robot
        return np.asarray(robot.T_world_base @ robot.kinematics.fk(joints))

    def pose_at(self, at_mm: float) -> FloatArray:
        """(4, 4) ``T_world_sensor`` with the torch at arc length ``at_mm`` (as ``scan --at``)."""
        return self.pose_at_tcp(self.tcp_at(at_mm))

    def stripe(self, T_world_sensor: ArrayLike, t_s: float = 0.0) -> tuple[Profile | None, Feature]:
        """The stripe profile (None in seam mode) and the seam point the sensor reports."""
        T = np.asarray(T_world_sensor, dtype=np.float64)
        if self.scan is not None:
            return self.scan(T, t_s)
        if self.mesh is not None:
            from seamtrack.features.extractors import extractor

            profile = self.sensor.scan(self.mesh, T, t_s=t_s)
            return profile, extractor(self.extractor)(profile)
        if self.sense is not None:
            return None, self.sense(T, t_s)
        from seamtrack.sensing.scan import sense_seam

        return None, sense_seam(self.seam, T, self.sensor)


def scene_view(source: Any, overrides: dict[str, Any] | list[str] | None = None) -> SceneView:
    """A :class:`SceneView` from a scene, a scene name or path, or a workpiece.

    Parameters
    ----------
    source : SceneView, Scene, str, Path, or an object with ``.mesh`` and ``.seam``
        A built-in scene name or TOML file is loaded (with ``overrides``) and built; a
        workpiece (``load_workpiece(...)``) is viewed with the paper's sensor.
    overrides : dict or list of "KEY=VALUE", optional
        Scene overrides, as ``--set``.
    """
    if isinstance(source, SceneView):
        return source
    if hasattr(source, "mesh") and hasattr(source, "seam"):
        from seamtrack.sensing.sensor import preset

        return SceneView(
            seam=source.seam,
            sensor=preset("paper"),
            mesh=source.mesh,
            name=Path(str(getattr(source, "source", "workpiece"))).stem,
        )
    from seamtrack.simulation.scene import Scene, load_scene

    scene = source if isinstance(source, Scene) else load_scene(source, overrides)
    return _from_scene(scene)


def _from_scene(scene: Any) -> SceneView:
    from seamtrack.simulation.assemble import build_parts

    parts = build_parts(scene)
    assert parts.sensor is not None  # every scene builds its sensor
    return SceneView(
        seam=parts.seam,
        sensor=parts.sensor,
        name=scene.name,
        mesh=parts.mesh,
        robot=parts.robot,
        look_ahead_mm=parts.look_ahead_mm,
        scan=parts.scan,
        sense=parts.sense if parts.scan is None else None,
        extractor=parts.extractor_name,
        tool_program=parts.tool_program,
    )


# --------------------------------------------------------------------------- geometry
def _torch_mesh(pv: Any, height_mm: float) -> Any:
    """A torch nozzle in the torch frame: a cone from the tip up the torch's z axis."""
    return pv.Cone(
        center=(0.0, 0.0, 0.5 * height_mm),
        direction=(0.0, 0.0, -1.0),
        height=height_mm,
        radius=0.15 * height_mm,
        resolution=24,
    )


def stripe_polydata(
    pv: Any, sensor: LaserLineSensor, profile: Profile | None, T_world_sensor: ArrayLike
) -> Any:
    """The stripe as points with an ``rgb`` colour per :class:`Reason` (misses drawn at the far
    end of their ray). Empty in seam mode (no profile)."""
    if profile is None or len(profile) == 0:
        return pv.PolyData()
    from seamtrack.sensing.scan import laser_fan

    assert profile.reason is not None
    points = profile.points_laser.copy()
    miss = ~np.isfinite(points).all(axis=1)
    if miss.any():
        directions = laser_fan(sensor, len(profile)).directions
        points[miss] = directions[miss, 1:] * (sensor.range_far_mm / directions[miss, 2:3])
    # Drawn 0.2 mm towards the emitter and the camera side of the laser plane, so that neither
    # the lit surface nor the translucent fan in the same plane hides the stripe.
    rng = np.linalg.norm(points, axis=1, keepdims=True)
    points = points * np.maximum(1.0 - _LIFT_MM / np.maximum(rng, _LIFT_MM), 0.0)
    world = apply(T_world_sensor, np.column_stack([np.full(len(points), _LIFT_MM), points]))
    palette = {code: _rgb(color) for code, color in REASON_COLORS.items()}
    rgb = np.array([palette[Reason(int(code))] for code in profile.reason], dtype=np.uint8)
    cloud = pv.PolyData(world)
    cloud.point_data["rgb"] = rgb.reshape(-1, 3)
    return cloud


def _rgb(hex_color: str) -> tuple[int, int, int]:
    h = hex_color.lstrip("#")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)


def torch_path(
    pv: Any, view: SceneView, result: Any, stop: int | None = None, max_points: int = 4000
) -> Any:
    """The torch tip's path (up to tick ``stop``) with the tracking error as scalars; on a mesh
    drawn 0.4 mm up the torch normal so the groove's surface and the seam line do not hide it."""
    tr = result.trace
    n = len(tr.t_s) if stop is None else max(1, stop)
    idx = np.unique(np.linspace(0, n - 1, min(n, max_points)).astype(int))
    points = tr.tcp_world[idx]
    if view.mesh is not None:
        points = points + 2 * _LIFT_MM * view.seam.normals[view.seam.closest(points).segment]
    path = polyline_mesh(pv, points)
    path.point_data["tracking error (mm)"] = tr.error_mm[idx]
    return path


def add_torch_path(plotter: Any, path_mesh: Any, result: Any) -> None:
    """The torch's path coloured by the tracking error, with its colour bar."""
    plotter.add_mesh(
        path_mesh,
        scalars="tracking error (mm)",
        cmap="plasma",
        clim=error_clim(result),
        line_width=5,
        name="torch-path",
        scalar_bar_args={"title": "tracking error (mm)", "color": "black"},
    )


def error_clim(result: Any) -> tuple[float, float]:
    tr = result.trace
    err = tr.error_mm[tr.welding] if tr.welding.any() else tr.error_mm
    top = float(np.nanmax(err)) if err.size else 1.0
    return 0.0, top if top > 0 else 1.0


# --------------------------------------------------------------------------- views
def scene_plotter(
    scene: Any,
    *,
    at_mm: float | None = None,
    result: Any = None,
    off_screen: bool | None = None,
    window_size: tuple[int, int] = (1200, 800),
    overrides: dict[str, Any] | list[str] | None = None,
    title: bool = True,
    camera: str | None = None,
) -> Any:
    """A PyVista plotter showing a scene; call ``.show()`` or ``.screenshot(path)`` on it.

    Parameters
    ----------
    scene : SceneView, Scene, str, Path or workpiece
        See :func:`scene_view`.
    at_mm : float, optional
        Torch position as arc length along the seam; the sensor, fan, field of view and stripe
        are drawn there and the camera looks at them. Default: mid-seam, or with a ``result``
        the torch's final position and a camera on the whole run.
    result : Result, optional
        A finished run: its torch path coloured by the tracking error, and the sensed points.
    off_screen : bool, optional
        Default: off screen when ``pv.OFF_SCREEN`` is set or there is no display.
    window_size : (2,) int
    overrides : dict or list of "KEY=VALUE", optional
        Scene overrides when ``scene`` is a name or a path.
    title : bool
        Write the scene name and position in a corner.
    camera : {"sensor", "cell"}, optional
        ``"sensor"``: close on the stripe (default for the gantry); ``"cell"``: the whole arm
        and the part (default for an articulated arm, which is then drawn too).

    Returns
    -------
    pyvista.Plotter
    """
    pv = pyvista_module()
    view = scene_view(scene, overrides)
    plotter = pv.Plotter(off_screen=off_screen_mode(off_screen), window_size=list(window_size))
    plotter.set_background("white")
    if view.mesh is not None:
        plotter.add_mesh(
            pv.wrap(view.mesh),
            color=_MESH_COLOR,
            name="workpiece",
            specular=0.2,
            smooth_shading=False,
        )
    lift = _LIFT_MM * view.seam.normals if view.mesh is not None else 0.0  # off the surface
    plotter.add_mesh(
        polyline_mesh(pv, view.seam.points + lift), color=_SEAM_COLOR, line_width=3, name="seam"
    )
    whole_run = result is not None and at_mm is None
    tcp = view.tcp_at(0.5 * view.seam.length_mm if at_mm is None else at_mm)
    tick = None
    if whole_run:  # the sensor where the welding ended
        welding = np.flatnonzero(result.trace.welding)
        tick = int(welding[-1]) if len(welding) else len(result.trace.t_s) - 1
        tcp = result.trace.tcp_world[tick]
    joints = None
    if view.is_arm:
        ran = tick is not None and result.trace.joints_rad.shape[1] > 0
        joints = result.trace.joints_rad[tick] if ran else view.joints_at_tcp(tcp)
        T_tcp = view.T_world_tcp_at_joints(joints)
        T = T_tcp @ view.robot.T_tcp_sensor  # type: ignore[union-attr]
    else:
        T_tcp = view.T_world_tcp(tcp)
        T = view.pose_at_tcp(tcp)
    add_sensor(plotter, view.sensor, T)
    plotter.add_mesh(
        _torch_mesh(pv, 0.2 * view.sensor.range_center_mm), color=_TORCH_COLOR, name="torch"
    ).user_matrix = T_tcp
    if joints is not None:
        from seamtrack.viz.arm import ArmActors

        ArmActors(plotter, view.robot, joints)  # type: ignore[arg-type]
    profile, feature = view.stripe(T)
    if profile is not None:
        cloud = stripe_polydata(pv, view.sensor, profile, T)
        if cloud.n_points:
            plotter.add_mesh(cloud, scalars="rgb", rgb=True, point_size=4, name="stripe")
    marker = pv.Sphere(radius=0.012 * view.sensor.range_center_mm)
    if feature:
        plotter.add_mesh(
            marker.translate(feature.point_world), color=FEATURE_COLOR, name="seam-point"
        )
    if result is not None:
        _add_result(plotter, pv, view, result)
    add_view_legend(plotter, legend_entries(view, profile, feature, result))
    if title:
        where = (
            "whole run"
            if whole_run
            else f"torch at s = {float(view.seam.closest(tcp[None]).arc_length_mm[0]):.1f} mm"
        )
        found = f"; seam point {'found' if feature else 'not found'}"
        plotter.add_text(f"{view.name}: {where}{found}", font_size=10, color="black", name="title")
    if (camera or ("cell" if view.is_arm else "sensor")) == "cell":
        camera_on_cell(plotter, view)
    else:
        camera_on_sensor(plotter, view.sensor, T, fit=whole_run)
    return plotter


def legend_entries(
    view: SceneView, profile: Profile | None, feature: Feature, result: Any = None
) -> list[dict[str, str]]:
    """What a view draws, as legend entries (``label``, ``color``, ``face``): the seam, the
    workpiece, the sensor's parts, the torch cone, the seam point found, the stripe's points
    by :class:`Reason` (with their counts) and, after a run, the sensed seam points."""
    entries = [{"label": "true seam", "color": _SEAM_COLOR, "face": "line"}]
    if view.mesh is not None:
        entries.append({"label": "workpiece", "color": _MESH_COLOR, "face": "rectangle"})
    entries += sensor_legend()
    entries.append({"label": "torch (cone)", "color": _TORCH_COLOR, "face": "triangle"})
    if feature:
        entries.append(
            {"label": "seam point found (yellow sphere)", "color": FEATURE_COLOR, "face": "circle"}
        )
    if profile is not None and profile.reason is not None:
        counts = np.bincount(profile.reason, minlength=len(Reason))
        entries += [
            {
                "label": f"stripe: {code.name.lower().replace('_', ' ')} ({counts[code]})",
                "color": REASON_COLORS[code],
                "face": "circle",
            }
            for code in Reason
            if counts[code]
        ]
    if result is not None:
        entries.append({"label": "sensed seam points", "color": "black", "face": "circle"})
    return entries


def add_view_legend(plotter: Any, entries: list[dict[str, str]]) -> Any:
    """One legend box in the lower left (PyVista keeps one legend per view)."""
    return plotter.add_legend(
        entries,
        bcolor="white",
        border=True,
        loc="lower left",
        size=(0.28, min(0.035 * len(entries), 0.6)),
        background_opacity=0.8,
    )


def _add_result(plotter: Any, pv: Any, view: SceneView, result: Any) -> None:
    add_torch_path(plotter, torch_path(pv, view, result), result)
    frames_ = result.trace.frames
    found = np.asarray(frames_.get("found", np.zeros(0, dtype=bool)), dtype=bool)
    if found.any():
        plotter.add_mesh(
            pv.PolyData(frames_["point_world"][found]),
            color="black",
            point_size=5,
            name="sensed-points",
        )


def camera_on_sensor(
    plotter: Any, sensor: LaserLineSensor, T_world_sensor: ArrayLike, fit: bool = False
) -> None:
    """Look at the stripe from ahead, beside and well above (steep enough to see into a 60 deg
    groove); ``fit``: then zoom out to show everything from that direction."""
    T = np.asarray(T_world_sensor, dtype=np.float64)
    focus = apply(T, [0.3 * sensor.baseline_mm, 0.0, 0.6 * sensor.range_center_mm])
    down, along, across = T[:3, 2], T[:3, 0], T[:3, 1]
    direction = (0.15 if fit else 0.5) * along - 0.4 * across - 0.85 * down
    distance = 1.6 * sensor.range_far_mm
    plotter.camera_position = [
        tuple(focus + distance * direction / np.linalg.norm(direction)),
        tuple(focus),
        tuple(-down),
    ]
    if fit:
        plotter.reset_camera()


def camera_on_cell(plotter: Any, view: SceneView) -> None:
    """Look at the robot and the part from the side of the line from the robot's base to the
    seam, and from above, fitting everything drawn into the view."""
    robot: Any = view.robot
    base = np.asarray(robot.T_world_base[:3, 3]) if robot is not None else np.zeros(3)
    part = view.seam.points.mean(axis=0)
    reach = part - base
    reach[2] = 0.0
    if np.linalg.norm(reach) < 1e-9:
        reach = np.array([1.0, 0.0, 0.0])
    reach /= np.linalg.norm(reach)
    up = np.array([0.0, 0.0, 1.0])
    side = np.cross(up, reach)
    direction = 0.8 * side - 0.35 * reach + 0.55 * up
    focus = 0.5 * (base + part)
    plotter.camera_position = [tuple(focus + 1000.0 * direction), tuple(focus), tuple(up)]
    plotter.reset_camera()


def render_png(
    scene: Any,
    path: str | Path,
    *,
    at_mm: float | None = None,
    result: Any = None,
    window_size: tuple[int, int] = (1200, 800),
    overrides: dict[str, Any] | list[str] | None = None,
    camera: str | None = None,
) -> Path:
    """Render a scene off screen to a PNG (see :func:`scene_plotter` for what is drawn).

    Returns
    -------
    Path
        The PNG written (its folder is created).
    """
    out = prepare_file(path)
    plotter = scene_plotter(
        scene,
        at_mm=at_mm,
        result=result,
        off_screen=True,
        window_size=window_size,
        overrides=overrides,
        camera=camera,
    )
    try:
        plotter.screenshot(str(out))
    finally:
        plotter.close()
    return out


def show(
    scene: Any, *, at_mm: float | None = None, result: Any = None, **kwargs: Any
) -> Path | None:
    """Show a scene: inline in Jupyter, in a window with a display, else as a PNG.

    Returns
    -------
    Path or None
        The PNG written when nothing could be shown (``runs/<scene name>-view.png``), else None.
    """
    pv = pyvista_module()
    if in_notebook():
        plotter = scene_plotter(scene, at_mm=at_mm, result=result, off_screen=True, **kwargs)
        plotter.show(jupyter_backend=jupyter_backend())
        return None
    if not pv.OFF_SCREEN and has_display():
        scene_plotter(scene, at_mm=at_mm, result=result, off_screen=False, **kwargs).show()
        return None
    view = scene_view(scene, kwargs.pop("overrides", None))
    target = Path("runs") / f"{view.name}-view.png"
    return render_png(view, target, at_mm=at_mm, result=result, **kwargs)
