"""The camera's physical ranges (issue 23): one definition (:data:`RANGES`) that the camera, a
scene's ``[sensor.camera]`` and a dataset spec's ``[camera]`` all check against; the image's
memory bound; and cameras at the edges of those ranges still see the seam."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.datasets.spec import SpecError, parse_spec
from seamtrack.errors import SceneError, SensorGeometryError
from seamtrack.sensing.camera import (
    BYTES_PER_PIXEL,
    MAX_IMAGE_BYTES,
    RANGES,
    Camera,
    image_bytes,
)
from seamtrack.sensing.sensor import preset
from seamtrack.simulation.scene import load_scene

#: Camera keys whose value is a float (the integers and the divergence, kept in rad by the
#: camera, are tested on their own).
FLOATS = ("focal_length_mm", "f_number", "wavelength_nm", "line_thickness_mm", "waist_range_mm",
          "exposure", "full_well_e", "read_noise_e", "ambient")  # fmt: skip
INTEGERS = ("rows", "columns", "bit_depth", "supersample")


def _outside(key: str) -> list[float]:
    bound = RANGES[key]
    below = [bound.lo * 0.5] if bound.lo > 0 else [-1.0]
    return [*below, bound.hi * 2 + 1, math.inf, math.nan]


@pytest.mark.parametrize("key", FLOATS + INTEGERS)
def test_each_camera_field_takes_its_whole_range_and_nothing_beyond(key: str) -> None:
    bound = RANGES[key]
    for value in (bound.lo, bound.hi):
        value = int(value) if key in INTEGERS else value
        Camera(**{key: value})  # the edges are allowed
    for value in _outside(key):
        if key in INTEGERS and not math.isfinite(value):
            continue
        value = int(value) if key in INTEGERS else value
        with pytest.raises(SensorGeometryError) as info:
            Camera(**{key: value})
        assert info.value.field == f"sensor.camera.{key}"
        assert f"{bound.lo:g}"[:3] in str(info.value).replace(",", "")


def test_the_divergence_is_checked_in_mrad_as_the_scene_gives_it() -> None:
    Camera(line_divergence_rad=0.5)
    with pytest.raises(SensorGeometryError) as info:
        Camera(line_divergence_rad=0.6)
    assert info.value.field == "sensor.camera.line_divergence_mrad"


@pytest.mark.parametrize("key", FLOATS)
def test_a_scene_refuses_what_the_camera_refuses_naming_the_field(key: str) -> None:
    big = RANGES[key].hi * 10 + 1
    with pytest.raises((SceneError, SensorGeometryError)) as info:
        load_scene("v-groove-camera", {f"sensor.camera.{key}": big})
    assert info.value.field == f"sensor.camera.{key}", str(info.value)


@pytest.mark.parametrize(
    "key", ["f_number", "wavelength_nm", "line_thickness_mm", "exposure", "full_well_e",
            "read_noise_e", "ambient"],
)  # fmt: skip
def test_a_dataset_spec_checks_its_camera_ranges_against_the_same_definition(key: str) -> None:
    bound = RANGES[key]
    parse_spec({"camera": {key: [bound.lo, bound.hi]}})  # the whole physical range is allowed
    with pytest.raises(SpecError) as info:
        parse_spec({"camera": {key: [bound.lo, bound.hi * 10 + 1]}})
    assert info.value.field == f"spec: camera.{key}"


def test_the_memory_bound_grows_with_pixels_and_supersampling() -> None:
    """The estimate is the measured bytes per pixel plus a block's box of cells; a chip that fits
    at supersample 1 may not at 8, and then the error names the supersampling."""
    assert image_bytes(1000, 1000, 1, 0) >= BYTES_PER_PIXEL * 1_000_000
    assert image_bytes(1000, 1000, 8, 16) > image_bytes(1000, 1000, 1, 2)
    sensor = preset("paper")
    Camera(rows=4096, columns=4096, supersample=1).check(sensor)
    with pytest.raises(SensorGeometryError) as info:
        Camera(rows=4096, columns=4096, supersample=8).check(sensor)
    assert info.value.field == "sensor.camera.supersample"
    with pytest.raises(SensorGeometryError) as info:
        Camera(rows=4096, columns=8192, supersample=1).check(sensor)
    assert info.value.field == "sensor.camera.columns"
    # A region of interest is what is rendered: a small one of a large chip fits.
    Camera(rows=16384, columns=16384, roi=(0, 16384, 0, 512), supersample=1).check(sensor)
    most = MAX_IMAGE_BYTES // BYTES_PER_PIXEL
    assert 4096 * 4096 <= most < 4096 * 8192


def test_dataset_offsets_keep_the_seam_in_range_and_view() -> None:
    """The allowed offsets come from the preset's geometry: its range about the centre and the
    field of view's half width at the nearest standoff drawn."""
    sensor = preset("paper")
    centre = sensor.range_center_mm
    low, high = sensor.range_near_mm - centre, sensor.range_far_mm - centre
    parse_spec({"sensor": {"standoff_offset_mm": [low + 0.01, high - 0.01]}})
    with pytest.raises(SpecError) as info:
        parse_spec({"sensor": {"standoff_offset_mm": [low - 1.0, 0.0]}})
    assert info.value.field == "spec: sensor.standoff_offset_mm"
    half = float(sensor.half_width_mm(centre - 15.0))
    parse_spec({"sensor": {"standoff_offset_mm": [-15.0, 15.0],
                           "lateral_offset_mm": [-0.99 * half, 0.99 * half]}})  # fmt: skip
    with pytest.raises(SpecError) as info:
        parse_spec({"sensor": {"standoff_offset_mm": [-15.0, 15.0],
                               "lateral_offset_mm": [0.0, 1.01 * half]}})  # fmt: skip
    assert info.value.field == "spec: sensor.lateral_offset_mm"
    # the same lateral range is fine when the nearest standoff is farther (a wider field)
    parse_spec({"sensor": {"standoff_offset_mm": [0.0, 15.0],
                           "lateral_offset_mm": [0.0, 1.01 * half]}})  # fmt: skip


# --------------------------------------------------------------------------- edges that work
EDGES = [
    pytest.param({"f_number": 0.95}, id="f/0.95"),
    pytest.param({"f_number": 22.0}, id="f/22"),
    pytest.param({"f_number": 64.0}, id="f/64"),
    pytest.param({"full_well_e": 1000.0}, id="full well 1000 e"),
    pytest.param({"full_well_e": 1e6, "read_noise_e": 100.0}, id="full well 1e6 e, read 100 e"),
    # A 5 um waist diverges by 0.17 rad: off the waist the line spreads over many rows, so it
    # needs more light than the default exposure gives to clear the threshold.
    pytest.param({"line_thickness_mm": 0.005, "exposure": 20.0}, id="line 5 um"),
    pytest.param({"wavelength_nm": 405.0, "focal_length_mm": 500.0}, id="405 nm, 500 mm lens"),
    pytest.param({"focal_length_mm": 1.0}, id="1 mm lens"),
    pytest.param({"exposure": 100.0}, id="exposure 100"),
    # One bit: a pixel reads 1 above half the full well; the stripe must be exposed past that.
    pytest.param({"bit_depth": 1, "exposure": 10.0}, id="1 bit"),
]


def _seam_error_mm(camera_keys: dict[str, float], rows: int, columns: int) -> tuple[float, float]:
    """Render v-groove-camera's frame at 10 mm with these camera keys and measure the seam point
    from the pixels: (its distance from the CAD seam, the tolerance). The tolerance is twice the
    sensor's resolution at the seam's range, depth or lateral, whichever is coarser, where a
    resolved spot on the chip is a pixel or the speckle grain lambda N (the optics' resolution),
    whichever is larger."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.scene import make_camera

    overrides = {"workpiece.params.seam_length_mm": 20.0, "sensor.camera.rows": rows,
                 "sensor.camera.columns": columns}  # fmt: skip
    overrides |= {f"sensor.camera.{k}": v for k, v in camera_keys.items()}
    scene = load_scene("v-groove-camera", overrides)
    parts = build_parts(scene)
    c = scene.config
    assert parts.sensor is not None and c.workpiece is not None and c.sensor.camera is not None
    tcp = parts.seam.interpolate([10.0])[0]
    T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
    camera = make_camera(c.sensor.camera, c.sensor.preset)
    image = parts.sensor.render(parts.mesh, T, camera=camera, seed=0, material=c.workpiece.material)
    profile = image.profile(c.sensor.camera.method, threshold=c.sensor.camera.threshold)
    assert profile.valid.sum() > 0.5 * columns, "the stripe is found in most columns"
    feature = parts.extract(profile)
    assert feature, feature.reason
    world = T[:3, :3] @ np.array([0.0, *feature.point_laser]) + T[:3, 3]
    imaging = camera.imaging_sensor(parts.sensor)
    z = float(feature.point_laser[1])
    pitch_h, pitch_v = imaging.pixel_pitch_mm
    spot = camera.speckle_size_mm
    resolution = max(
        float(imaging.local_depth_resolution_mm(z)) * max(1.0, spot / pitch_h),
        float(imaging.local_lateral_resolution_mm(z)) * max(1.0, spot / pitch_v),
    )
    return float(parts.seam.closest(world).distance_mm[0]), 2.0 * resolution


@pytest.mark.cad
@pytest.mark.embree
@pytest.mark.parametrize("camera_keys", EDGES)
def test_a_camera_at_the_edge_of_its_ranges_still_finds_the_seam(camera_keys) -> None:
    error, tolerance = _seam_error_mm(camera_keys, rows=256, columns=512)
    assert error <= tolerance, (error, tolerance)


@pytest.mark.cad
@pytest.mark.embree
@pytest.mark.slow
def test_the_largest_allowed_chip_renders_and_finds_the_seam() -> None:
    """4096 x 4096 at supersample 1 is within the memory bound (a peak of 1.5 GB measured with
    seamtrack render); the seam is found to two of its (finer) pixels."""
    error, tolerance = _seam_error_mm({"supersample": 1}, rows=4096, columns=4096)
    assert error <= tolerance, (error, tolerance)


# --------------------------------------------------------------------------- datasets
def test_a_refused_dataset_images_run_leaves_nothing_behind(tmp_path, capsys) -> None:
    """The camera's values are checked with the spec, before dataset.json or spec.toml."""
    from seamtrack.cli.main import main

    spec = tmp_path / "spec.toml"
    for text in ("[camera]\nf_number = [4.0, 1e9]\n", "[camera]\nfull_well_e = 1e-300\n",
                 "[camera]\nambient = [0.0, 1e300]\n",
                 "[sensor]\nstandoff_offset_mm = [-1000.0, 1000.0]\n"):  # fmt: skip
        spec.write_text(text)
        out = tmp_path / "data"
        code = main(["dataset", str(spec), "--images", "--n", "8", "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and err.count("seamtrack: error: ") == 1, err
        assert not out.exists()


def test_asking_for_fewer_samples_than_there_are_does_nothing_and_says_so(tmp_path, capsys):
    from seamtrack.cli.main import main

    spec = tmp_path / "spec.toml"
    spec.write_text('rays = 16\n[joint]\nfamilies = ["v-groove"]\n')
    out = tmp_path / "data"
    assert main(["dataset", str(spec), "--n", "8", "--out", str(out)]) == 0
    capsys.readouterr()
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert main(["dataset", str(spec), "--n", "4", "--out", str(out)]) == 0
    assert capsys.readouterr().out.strip() == "8 samples already there; nothing to do"
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before  # nothing rewritten
    from seamtrack.datasets.reader import info

    assert ": 8 samples of 16 rays" in info(out)
