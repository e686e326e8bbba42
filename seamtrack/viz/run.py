"""Runs in 3D: an animated GIF (or MP4) of the sensor and stripe moving along the seam, and the
hooks behind ``seamtrack view`` and ``seamtrack run --render``. Views themselves are in
:mod:`seamtrack.viz.views`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.geometry.frames import make
from seamtrack.io.output import prepare_file
from seamtrack.viz.views import (
    FEATURE_COLOR,
    add_torch_path,
    camera_on_cell,
    camera_on_sensor,
    has_display,
    pyvista_module,
    render_png,
    scene_plotter,
    scene_view,
    stripe_polydata,
    torch_path,
)

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------- runs
def _frame_ticks(result: Any, frames_: int) -> NDArray[np.intp]:
    n = len(result.trace.t_s)
    return np.unique(np.linspace(0, n - 1, max(2, frames_)).round().astype(np.intp))


def gif_writer(path: Path, fps: float) -> tuple[Callable[[Any], None], Callable[[], None]]:
    """(append an RGB frame, finish): GIF through Pillow; MP4 through imageio-ffmpeg."""
    if path.suffix.lower() == ".mp4":
        try:
            import imageio.v2 as imageio
        except ImportError as exc:
            raise ImportError(
                "writing MP4 needs imageio-ffmpeg: pip install imageio-ffmpeg (or write a .gif)"
            ) from exc
        writer = imageio.get_writer(str(path), fps=fps, macro_block_size=1)
        return writer.append_data, writer.close
    from PIL import Image

    images: list[Any] = []

    def append(frame: Any) -> None:
        images.append(Image.fromarray(np.asarray(frame)[..., :3]).quantize(colors=128))

    def finish() -> None:
        images[0].save(
            path,
            save_all=True,
            append_images=images[1:],
            loop=0,
            optimize=True,
            duration=int(round(1000.0 / fps)),
        )

    return append, finish


def animate_run(
    scene: Any,
    result: Any,
    path: str | Path,
    *,
    fps: float = 10.0,
    frames: int = 60,
    window_size: tuple[int, int] = (800, 500),
    progress: bool | None = None,
    overrides: dict[str, Any] | list[str] | None = None,
) -> Path:
    """Animate a run: the sensor, its fan and stripe moving along the seam, the torch path
    growing coloured by the tracking error; an articulated arm is drawn at the run's joint
    positions, seen from beside the cell. GIF (Pillow) or MP4 (imageio-ffmpeg, by suffix).

    Parameters
    ----------
    scene : SceneView, Scene, str, Path
        The scene the run came from (the sensor is posed by its robot).
    result : Result
    path : str or Path
        ``.gif`` or ``.mp4``.
    fps : float
    frames : int
        Frames, evenly spaced in time over the run.
    window_size : (2,) int
    progress : bool, optional
        A tqdm bar; default when stderr is a terminal.
    overrides : optional
        Scene overrides when ``scene`` is a name or a path.

    Returns
    -------
    Path
    """
    from tqdm import tqdm

    pv = pyvista_module()
    out = prepare_file(path)
    view = scene_view(scene, overrides)
    ticks = _frame_ticks(result, frames)
    tr = result.trace
    plotter = scene_plotter(view, at_mm=0.0, off_screen=True, window_size=window_size, title=False)
    arm = None
    if view.is_arm and tr.joints_rad.shape[1] > 0:
        from seamtrack.viz.arm import ArmActors

        arm = ArmActors(plotter, view.robot, tr.joints_rad[0])  # type: ignore[arg-type]
    sensor_actors = [plotter.actors[k] for k in plotter.actors if k.startswith("sensor-")]
    torch_actor = plotter.actors["torch"]
    for name in ("stripe", "seam-point"):
        plotter.remove_actor(name)
    plotter.remove_legend()
    stripe = pv.PolyData(np.zeros((1, 3)))  # a placeholder: pyvista refuses empty meshes
    stripe.point_data["rgb"] = np.zeros((1, 3), dtype=np.uint8)
    stripe_actor = plotter.add_mesh(stripe, scalars="rgb", rgb=True, point_size=4, name="stripe")
    path_mesh = torch_path(pv, view, result, stop=1)
    add_torch_path(plotter, path_mesh, result)
    point_actor = plotter.add_mesh(
        pv.Sphere(radius=0.012 * view.sensor.range_center_mm),
        color=FEATURE_COLOR,
        name="seam-point",
    )
    append, finish = gif_writer(out, fps)
    bar = tqdm(
        total=len(ticks),
        unit="frame",
        desc=f"animating {out.name}",
        leave=False,
        disable=not (sys.stderr.isatty() if progress is None else progress),
    )
    try:
        for tick in ticks.tolist():
            tcp = tr.tcp_world[tick]
            if arm is not None:  # the pose the run had, from its joints
                arm.move(tr.joints_rad[tick])
                T_tcp = view.T_world_tcp_at_joints(tr.joints_rad[tick])
                T = T_tcp @ view.robot.T_tcp_sensor  # type: ignore[union-attr]
            else:
                T_tcp = view.T_world_tcp(tcp)
                T = view.pose_at_tcp(tcp)
            for actor in sensor_actors:
                actor.user_matrix = T
            torch_actor.user_matrix = T_tcp
            profile, feature = view.stripe(T, float(tr.t_s[tick]))
            cloud = stripe_polydata(pv, view.sensor, profile, T)
            if cloud.n_points:
                stripe.copy_from(cloud)
            stripe_actor.visibility = cloud.n_points > 0
            path_mesh.copy_from(torch_path(pv, view, result, stop=tick + 1, max_points=1500))
            if feature:
                point_actor.user_matrix = make(translation=feature.point_world)
            point_actor.visibility = bool(feature)
            plotter.add_text(
                f"{view.name}: t = {tr.t_s[tick]:.1f} s, error {tr.error_mm[tick]:.3f} mm",
                font_size=10,
                color="black",
                name="title",
            )
            if arm is None:
                camera_on_sensor(plotter, view.sensor, T)
            elif tick == ticks[0]:
                camera_on_cell(plotter, view)
            plotter.render()
            append(plotter.screenshot(return_img=True))
            bar.update(1)
        finish()
    finally:
        bar.close()
        plotter.close()
    return out


# --------------------------------------------------------------------------- CLI hooks
def view_command(
    scene: Any,
    at_mm: float | None = None,
    out: str | Path | None = None,
    *,
    overrides: dict[str, Any] | list[str] | None = None,
    interactive: bool | None = None,
    window_size: tuple[int, int] = (1200, 800),
) -> Path:
    """``seamtrack view SCENE [--at S_MM] [--out PNG]``: always write the PNG, return its path.

    The PNG is rendered off screen, so this works without a display. With a display, and when
    ``interactive`` is not False (default: only when no ``out`` was given), a window opens
    afterwards.

    Parameters
    ----------
    scene : str, Path, Scene or SceneView
    at_mm : float, optional
        Torch position along the seam (mm); default mid-seam.
    out : str or Path, optional
        Default ``runs/<scene name>-view.png``.
    overrides : dict or list of "KEY=VALUE", optional
    interactive : bool, optional
    window_size : (2,) int
    """
    view = scene_view(scene, overrides)
    if at_mm is not None and not 0.0 <= at_mm <= view.seam.length_mm:
        from seamtrack.errors import SceneError

        raise SceneError(
            f"{at_mm} mm is not on the seam (0..{view.seam.length_mm:.3f} mm)",
            field="--at",
            fix="give an arc length along the seam in mm",
        )
    target = Path(out) if out is not None else Path("runs") / f"{view.name}-view.png"
    path = render_png(view, target, at_mm=at_mm, window_size=window_size)
    wanted = (out is None) if interactive is None else interactive
    if wanted and has_display() and not pyvista_module().OFF_SCREEN:
        scene_plotter(view, at_mm=at_mm, off_screen=False, window_size=window_size).show()
    return path


def render_run(
    scene: Any,
    result: Any,
    out_dir: str | Path,
    *,
    frames: int = 60,
    fps: float = 10.0,
    progress: bool | None = None,
) -> list[Path]:
    """``seamtrack run --render``: ``scene.png`` (the whole run, torch path coloured by error)
    and ``run.gif`` (the sensor and stripe moving along the seam) in ``out_dir``.

    Returns
    -------
    list of Path
        [scene.png, run.gif]
    """
    folder = Path(out_dir)
    view = scene_view(scene)
    png = render_png(view, folder / "scene.png", result=result)
    gif = animate_run(view, result, folder / "run.gif", frames=frames, fps=fps, progress=progress)
    return [png, gif]
