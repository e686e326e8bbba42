"""Pictures of rendered camera images: the stripe image with the rows a detector found, and the
profile measured from it over the true one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.errors import SceneError
from seamtrack.io.output import prepare_file
from seamtrack.sensing.camera import StripeImage
from seamtrack.sensing.profiles import Feature, Profile
from seamtrack.viz.plots import pyplot_module, save_with_legends


def plot_stripe_image(
    image: StripeImage,
    profile: Profile,
    path: str | Path,
    *,
    rows: Any = None,
    feature: Feature | None = None,
    title: str = "",
    dpi: int = 120,
) -> Path:
    """Two panels: the camera image (rows along x_c, range; columns along z_c) with the
    detected rows over it, and the measured profile against the ideal stripe in the laser plane.

    Parameters
    ----------
    image : StripeImage
    profile : Profile
        Measured from ``image`` (``image.profile(...)``).
    path : str or Path
        PNG to write.
    rows : (columns,) float, optional
        The detected sub-pixel rows, drawn over the image.
    feature : Feature, optional
        A seam point found in ``profile``.

    Returns
    -------
    Path
    """
    plt = pyplot_module()
    out = prepare_file(path)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8.0, 7.5), height_ratios=[1.1, 1.0])
    try:
        top.imshow(image.pixels, cmap="gray", vmin=0.0, vmax=1.0, aspect="auto",
                   interpolation="nearest")  # fmt: skip
        cols = np.arange(image.shape[1])
        top.plot(cols, image.truth_row, "-", color="C2", lw=0.6, alpha=0.8, label="ideal stripe")
        if rows is not None:
            top.plot(cols, rows, ".", color="C1", ms=1.0, label="detected")
        if image.reflection.any():
            top.plot(cols, image.reflection_row, "-", color="C3", lw=0.6, alpha=0.8,
                     label="false stripe (reflection)")  # fmt: skip
        top.set_xlabel("column (z_c)")
        top.set_ylabel("row (x_c; down: nearer)")
        cam = image.camera
        top.set_title(
            title
            or f"camera image, {image.shape[0]} x {image.shape[1]} px, f/{cam.f_number:g}, "
            f"{cam.wavelength_nm:g} nm, {image.material.name}"
        )
        legend = top.legend(loc="upper right", fontsize=7, framealpha=0.7)
        truth = image.truth_laser
        bottom.plot(truth[:, 0], truth[:, 1], "-", color="C2", lw=1.0, label="ideal stripe")
        pts = profile.valid_points
        bottom.plot(pts[:, 0], pts[:, 1], ".", color="C0", ms=1.5,
                    label=f"measured ({len(pts)} of {len(profile)} columns)")  # fmt: skip
        if feature:
            bottom.plot(*feature.point_laser, "x", color="C3", ms=10, mew=2, label="seam point")
        bottom.invert_yaxis()
        bottom.set_aspect("equal", adjustable="datalim")
        bottom.set_xlabel("y_L (mm)")
        bottom.set_ylabel("z_L, range (mm)")
        bottom.grid(True, lw=0.3)
        save_with_legends(
            fig, out, dpi, legend, bottom.legend(loc="best", fontsize=8, framealpha=0.8)
        )
    finally:
        plt.close(fig)
    return out


def render_command(
    scene_name: str, at_mm: float, out: str | None, *, overrides: list[str] | None = None
) -> list[str]:
    """``seamtrack render``: the camera image at arc length ``at_mm`` along the seam, the profile
    measured from it (the scene's ``[sensor.camera]`` detector) over the ideal stripe, and the
    seam point the scene's extractor finds in it. Writes the PNG; returns the lines to print."""
    from seamtrack.io.output import check_writable, new_dir
    from seamtrack.simulation.assemble import arc_frame, build_parts, scene_arc_light
    from seamtrack.simulation.countermeasures import rejection
    from seamtrack.simulation.robots import sensor_pose_at
    from seamtrack.simulation.scene import CameraConfig, detect_rows, load_scene, scene_camera

    scene = load_scene(scene_name, overrides)
    c = scene.config
    if c.sensor.mode != "mesh":
        raise SceneError(
            "the camera renders the part's mesh; this scene has none",
            field="sensor.mode",
            fix="use a mesh scene (seamtrack init --list), e.g. v-groove-camera",
        )
    path = Path(out) if out else Path("runs") / f"render-{scene.name}-{at_mm:g}mm.png"
    folder = path.parent if str(path.parent) else Path(".")
    check_writable(folder)
    parts = build_parts(scene)
    seam = parts.seam
    if not 0.0 <= at_mm <= seam.length_mm:
        raise SceneError(
            f"{at_mm} mm is not on the seam (0..{seam.length_mm:.3f} mm)",
            field="--at",
            fix="give an arc length along the seam in mm",
        )
    assert parts.sensor is not None and c.workpiece is not None
    T_world_sensor, _ = sensor_pose_at(parts.robot, parts.tool_program, at_mm)
    detector = c.sensor.camera or CameraConfig()
    camera = scene_camera(c)
    arc_light = scene_arc_light(scene, camera)  # the scene's [arc], if image mode draws it
    arc = None
    if arc_light is not None:
        arc = arc_frame(arc_light, T_world_sensor, [np.linalg.inv(parts.robot.T_tcp_sensor)])
    image = parts.sensor.render(parts.mesh, T_world_sensor, camera=camera,
                                seed=c.simulation.seed, material=c.workpiece.material,
                                **({} if arc is None else {"arc": arc}))  # fmt: skip
    rows = detect_rows(image.pixels, detector, rejection(c))
    level = (f"threshold {detector.threshold:g}" if detector.threshold is not None else
             f"threshold {detector.relative:g} of each column's peak, >= "
             f"{detector.noise_sigmas:g} noise sigmas")  # fmt: skip
    profile = image.profile_from_rows(rows)
    feature = parts.extract(profile)
    with new_dir(folder):
        plot_stripe_image(image, profile, path, rows=rows, feature=feature)
    truth = image.truth_laser
    both = profile.valid & np.isfinite(truth[:, 0])
    error = np.linalg.norm(profile.points_laser[both] - truth[both], axis=1)
    rms = float(np.sqrt(np.mean(error**2))) if len(error) else float("nan")
    worst = float(error.max()) if len(error) else float("nan")
    lines = [
        f"image: {image.shape[0]} x {image.shape[1]} px, material {image.material.name!r}, "
        f"peak {float(image.pixels.max()):.3f} of full scale",
        f"profile ({detector.method}, {level}, {detector.choose}): "
        f"{int(profile.valid.sum())} of {len(profile)} columns; against the ideal stripe RMS "
        f"{rms:.4f} mm, max {worst:.4f} mm; false stripe in {int(image.reflection.sum())} columns",
    ]
    if feature:
        point = feature.point_laser + np.asarray(c.extractor.offset_mm)
        world = T_world_sensor[:3, :3] @ np.array([0.0, *point]) + T_world_sensor[:3, 3]
        lines.append(f"seam point: laser (y, z) = {np.round(point, 4).tolist()} mm, "
                     f"{seam.closest(world).distance_mm[0]:.4f} mm from the true seam")  # fmt: skip
    else:
        lines.append(f"no seam point: {feature.reason}")
    return [*lines, f"wrote {path}"]
