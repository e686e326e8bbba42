"""Image regression tests of the 3D views and the profile plot, rendered off screen.

Each test renders a PNG and compares it with its reference in ``tests/image_cache/`` through
``pyvista.compare_images`` (mean pixel difference after edge detection), with a tolerance for
other OpenGL drivers and fonts. The tests never write the cache: a missing reference fails and
says how to make it. Update the references after an intended change of the views with

    SEAMTRACK_UPDATE_IMAGES=1 .venv/bin/python -m pytest tests/test_viz.py

and look at the new PNGs before committing them. (pytest-pyvista's ``verify_image_cache`` is
not used: its cache folder is set through pytest options or ini keys, and its "images differ a
little" warnings become errors under ``filterwarnings = error``.)
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import seamtrack as st
from seamtrack.sensing.sensor import preset

pv = pytest.importorskip("pyvista")
trimesh = pytest.importorskip("trimesh")

from seamtrack.viz import run as viz_run  # noqa: E402  (after the skip: needs pyvista)
from seamtrack.viz import views as viz  # noqa: E402

CACHE = Path(__file__).parent / "image_cache"
UPDATE_ENV = "SEAMTRACK_UPDATE_IMAGES"
#: Largest accepted ``pv.compare_images`` error, measured on the mesh view: re-rendering on the
#: same machine gives 0; without the stripe 90; the sensor 1 mm further 255; without the laser
#: fan 490. Another OpenGL driver or font set may need new references (see above).
IMAGE_ERROR_MAX = 50.0
WINDOW = (600, 400)


@pytest.fixture(autouse=True)
def _off_screen(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(pv, "OFF_SCREEN", True)


def check_image(rendered: Path, name: str) -> None:
    """Compare a rendered PNG with ``tests/image_cache/<name>.png`` (or replace it on demand)."""
    reference = CACHE / f"{name}.png"
    if os.environ.get(UPDATE_ENV) == "1":
        CACHE.mkdir(exist_ok=True)
        shutil.copyfile(rendered, reference)
        return
    if not reference.is_file():
        pytest.fail(
            f"no reference image {reference}; create it with "
            f"{UPDATE_ENV}=1 python -m pytest tests/test_viz.py, look at it, and commit it"
        )
    error = pv.compare_images(str(reference), str(rendered))
    assert error <= IMAGE_ERROR_MAX, (
        f"{rendered} differs from {reference} (error {error:.1f} > {IMAGE_ERROR_MAX}); if the "
        f"change is intended: {UPDATE_ENV}=1 python -m pytest tests/test_viz.py"
    )


def v_groove_mesh(
    length_mm: float = 200.0,
    half_width_mm: float = 50.0,
    thickness_mm: float = 10.0,
    root_face_mm: float = 1.0,
    groove_angle_deg: float = 60.0,
) -> trimesh.Trimesh:
    """A V-groove butt joint built analytically (no CadQuery): two bevelled plates along X, the
    V bottom (the seam) on the X axis at z = 0, plates from z = -root_face to the top."""
    top = thickness_mm - root_face_mm
    bevel = top * math.tan(math.radians(0.5 * groove_angle_deg))
    left = np.array(
        [
            [-half_width_mm, -root_face_mm],
            [0.0, -root_face_mm],
            [0.0, 0.0],
            [-bevel, top],
            [-half_width_mm, top],
        ]
    )
    # (u, v, w) -> (x, y, z) = (w, u, v): the section in the y-z plane, extruded along x.
    to_world = np.eye(4)
    to_world[:3, :3] = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    plates = []
    for section in (left, left[::-1] * [-1.0, 1.0]):  # the mirror, kept counter-clockwise
        faces = np.array([[0, k, k + 1] for k in range(1, len(section) - 1)])
        plate = trimesh.creation.extrude_triangulation(section, faces, length_mm)
        plates.append(plate.apply_transform(to_world))
    return trimesh.util.concatenate(plates)


@pytest.fixture(scope="module")
def v_groove_view() -> viz.SceneView:
    seam = st.Seam.from_points([[0.0, 0.0, 0.0], [200.0, 0.0, 0.0]], [[0, 0, 1], [0, 0, 1]])
    return viz.SceneView(seam=seam, sensor=preset("paper"), name="v-groove", mesh=v_groove_mesh())


def test_analytic_v_groove_is_a_closed_outward_solid() -> None:
    mesh = v_groove_mesh()
    # Closed: every edge shared by exactly two faces, wound the same way on both; outward:
    # the enclosed volume is positive.
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert np.allclose(mesh.bounds, [[0, -50, -1], [200, 50, 9]])


def test_seam_mode_view_matches_cache(tmp_path: Path) -> None:
    out = viz.render_png(
        "paper-verification", tmp_path / "seam.png", at_mm=100.0, window_size=WINDOW
    )
    check_image(out, "seam_mode_view")


@pytest.mark.embree
def test_mesh_view_with_stripe_and_fov_matches_cache(
    v_groove_view: viz.SceneView, tmp_path: Path
) -> None:
    profile, feature = v_groove_view.stripe(v_groove_view.pose_at(100.0))
    assert profile is not None and np.count_nonzero(profile.valid) > 0.9 * len(profile)
    assert feature and abs(feature.point_world[1]) < 0.05  # the V bottom, under the laser
    out = viz.render_png(v_groove_view, tmp_path / "mesh.png", at_mm=100.0, window_size=WINDOW)
    check_image(out, "mesh_view_v_groove")


def test_profile_plot_matches_cache(tmp_path: Path) -> None:
    from seamtrack.features.synthetic import synthetic_profile
    from seamtrack.viz.plots import plot_profile_2d

    profile, truth = synthetic_profile("v-groove", preset("paper"), rays=300, roll_deg=10.0)
    feature = st.extractor("v-groove")(profile)
    assert feature
    out = plot_profile_2d(profile, tmp_path / "profile.png", truth=truth, feature=feature, dpi=80)
    check_image(out, "profile_v_groove")


def test_missing_reference_fails_and_says_how_to_make_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(UPDATE_ENV, raising=False)
    png = tmp_path / "x.png"
    png.write_bytes(b"")
    with pytest.raises(pytest.fail.Exception, match=f"{UPDATE_ENV}=1"):
        check_image(png, "no_such_reference")


def test_view_command_writes_png_without_display(tmp_path: Path) -> None:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("DISPLAY", "WAYLAND_DISPLAY", "PYVISTA_OFF_SCREEN")
    }
    out = tmp_path / "view.png"
    code = (
        "from seamtrack.viz.views import has_display\n"
        "from seamtrack.viz.run import view_command\n"
        "assert not has_display()\n"
        f"print(view_command('paper-corner', 50.0, {str(out)!r}, window_size=(320, 240)))\n"
    )
    res = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    # VTK chooses an off-screen window itself (EGL or OSMesa): no "bad X server connection"
    assert "X server" not in res.stderr and "WARN" not in res.stderr, res.stderr
    assert res.stdout.strip().endswith("view.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert pv.read(str(out)).dimensions[:2] == (320, 240)


def legend_labels(plotter: pv.Plotter) -> list[str]:
    legend = plotter.legend
    assert legend is not None, "the view has no legend"
    return [legend.GetEntryString(i) for i in range(legend.GetNumberOfEntries())]


def test_the_view_names_every_part_it_draws_in_a_legend() -> None:
    plotter = viz.scene_plotter("paper-corner", at_mm=100.0, off_screen=True, window_size=WINDOW)
    try:
        labels = legend_labels(plotter)
    finally:
        plotter.close()
    for part in (
        "true seam",
        "sensor housing (box)",
        "laser emitter (red sphere)",
        "camera centre (blue sphere)",
        "laser fan",
        "field of view",
        "torch (cone)",
        "seam point found (yellow sphere)",
    ):
        assert part in labels, (part, labels)


@pytest.mark.embree
def test_the_legend_counts_the_stripe_points_by_reason(v_groove_view: viz.SceneView) -> None:
    profile, _ = v_groove_view.stripe(v_groove_view.pose_at(100.0))
    assert profile is not None and profile.reason is not None
    plotter = viz.scene_plotter(v_groove_view, at_mm=100.0, off_screen=True, window_size=WINDOW)
    try:
        labels = legend_labels(plotter)
    finally:
        plotter.close()
    assert "workpiece" in labels
    stripe = [label for label in labels if label.startswith("stripe: ")]
    counted = sum(int(label.rsplit("(", 1)[1].rstrip(")")) for label in stripe)
    assert counted == len(profile)  # every ray in one entry
    assert f"stripe: valid ({np.count_nonzero(profile.valid)})" in stripe


def test_view_command_rejects_a_position_off_the_seam(tmp_path: Path) -> None:
    with pytest.raises(st.SeamtrackError, match="--at"):
        viz_run.view_command("paper-corner", 1e4, tmp_path / "x.png")


def test_render_run_writes_scene_png_and_animated_gif(tmp_path: Path) -> None:
    from PIL import Image

    scene = st.load_scene("paper-verification", {"seam.length_mm": 20.0})
    result = st.simulate(scene)
    png, gif = viz_run.render_run(scene, result, tmp_path, frames=4)
    assert png.name == "scene.png" and png.stat().st_size > 1000
    with Image.open(gif) as image:
        assert image.format == "GIF" and image.n_frames == 4


def test_missing_pyvista_names_the_fix(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pyvista", None)
    with pytest.raises(ImportError, match="pip install pyvista"):
        viz.scene_plotter("paper-verification")
