"""Image mode in scenes and the loop: [sensor.camera], sensor.source, workpiece.material, and
``seamtrack render``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from cli_helpers import run_cli

import seamtrack as st
from seamtrack.errors import SceneError, SensorGeometryError
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.scene import CameraConfig, load_scene, make_camera

pytestmark = [pytest.mark.cad, pytest.mark.embree]

SHORT = {"workpiece.params.seam_length_mm": 30.0}


def test_camera_table_maps_onto_the_camera() -> None:
    camera = make_camera(CameraConfig(f_number=4.0, bit_depth=0, line_divergence_mrad=3.0))
    assert camera.f_number == 4.0 and camera.bit_depth is None
    assert camera.line_divergence_rad == pytest.approx(3e-3)
    ideal = make_camera(CameraConfig(ideal=True, rows=100))
    assert ideal.is_ideal and ideal.rows == 100
    assert make_camera(None) == st.Camera()


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"sensor.camera.f_number": 0.0}, "sensor.camera.f_number"),
        ({"sensor.camera.wavelength_nm": 2500.0}, "sensor.camera.wavelength_nm"),
        ({"sensor.camera.line_thickness_mm": 30.0}, "sensor.camera.line_thickness_mm"),
        ({"sensor.camera.bit_depth": True}, "sensor.camera.bit_depth"),
        ({"sensor.camera.choose": "last"}, "sensor.camera.choose"),
        ({"workpiece.material": "chrome"}, "workpiece.material"),
        ({"sensor.source": "image", "sensor.mode": "seam"}, "sensor.source"),
    ],
)
def test_bad_camera_keys_are_refused_with_their_field(overrides, field) -> None:
    with pytest.raises((SceneError, SensorGeometryError)) as info:
        load_scene("v-groove-camera", overrides)
    assert str(info.value).splitlines()[0].split(": ")[1].startswith(field) or (
        info.value.field == field
    ), str(info.value)


def test_image_mode_measures_each_frame_from_pixels_and_agrees_with_geometry() -> None:
    """At the same poses, the seam point found in the camera's image and in the ray-cast stripe
    agree within one camera row (the image's depth step: the depth of field over the rows,
    60 mm / 512 = 0.12 mm; the stripe's centroid is sub-pixel); the image-mode profile has one
    point per camera column."""
    image_parts = build_parts(load_scene("v-groove-camera", SHORT))
    geometry = {**SHORT, "sensor.source": "geometry", "sensor.rays": 1024}
    geometry_parts = build_parts(load_scene("v-groove-camera", geometry))
    assert image_parts.scan is not None and geometry_parts.scan is not None
    gaps = []
    for arc in np.linspace(2.0, 18.0, 6):  # the laser looks 10 mm ahead of the torch
        tcp = image_parts.seam.interpolate([arc])[0]
        T = image_parts.robot.T_world_sensor(image_parts.robot.q_from_world(tcp))
        image_profile, image_point = image_parts.scan(T, 0.0)
        _, geometry_point = geometry_parts.scan(T, 0.0)
        assert len(image_profile) == 1024 and image_point and geometry_point
        gaps.append(float(np.linalg.norm(image_point.point_world - geometry_point.point_world)))
    camera = load_scene("v-groove-camera", SHORT).config.sensor.camera
    assert image_parts.sensor is not None and camera is not None
    row_mm = image_parts.sensor.depth_of_field_mm / camera.rows
    assert max(gaps) < row_mm, gaps


def test_image_mode_is_seeded_by_the_scene() -> None:
    def first_profile(seed: int) -> np.ndarray:
        parts = build_parts(load_scene("v-groove-camera", {**SHORT, "simulation.seed": seed}))
        assert parts.scan is not None
        tcp = parts.seam.interpolate([10.0])[0]
        T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
        return parts.scan(T, 0.0)[0].points_laser

    a, b, c = first_profile(0), first_profile(0), first_profile(1)
    assert np.array_equal(a, b, equal_nan=True) and not np.array_equal(a, c, equal_nan=True)


@pytest.mark.slow
def test_the_image_mode_scene_tracks_the_groove() -> None:
    s = st.simulate(load_scene("v-groove-camera", SHORT)).summary
    assert s["status"] == "completed" and s["max_error_mm"] < 0.3, s


def test_render_command_writes_the_picture_and_reports(tmp_path) -> None:
    out = tmp_path / "img" / "frame.png"
    res = run_cli("render", "v-groove-camera", "--at", "10", "--out", str(out),
                  "--set", 'workpiece.material="bright aluminium"')  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert out.stat().st_size > 10_000
    assert "1024 columns" in res.stdout and "from the true seam" in res.stdout
    rms = float(res.stdout.split("RMS ")[1].split(" mm")[0])
    assert math.isfinite(rms) and rms < 0.3


def test_render_refuses_a_seam_mode_scene_and_an_arc_off_the_seam(tmp_path) -> None:
    res = run_cli("render", "paper-verification", "--out", str(tmp_path / "x.png"))
    assert res.returncode == 2 and "sensor.mode" in res.stderr
    res = run_cli("render", "v-groove-camera", "--at", "-3", "--out", str(tmp_path / "y" / "x.png"))
    assert res.returncode == 2 and "--at" in res.stderr and not (tmp_path / "y").exists()
