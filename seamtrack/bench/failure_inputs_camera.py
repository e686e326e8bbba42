"""Bad inputs for the camera (image mode) and its chip, and datasets: entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`, with the files they need.

Every camera value has a physical range (:data:`seamtrack.sensing.camera.RANGES`) and an image
a memory bound (:data:`seamtrack.sensing.camera.MAX_IMAGE_BYTES`); each reproducer of issue 23
is here with neighbours: other values, other commands (run, render, check, dataset --images),
other scenes and presets. All are refused while the scene or spec is read, so all are quick.
"""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import (
    CAMERA,
    MESH,
    Entry,
    dataset_args,
    naming_key,
    run_args,
    set_args,
)

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {
    "camera_f_number.toml": b"[camera]\nf_number = [4.0, 1e9]\n",
    "camera_f_number_1e4.toml": b"[camera]\nf_number = 1e4\n",
    "camera_full_well.toml": b"[camera]\nfull_well_e = 1e-300\n",
    "camera_full_well_big.toml": b"images = true\n[camera]\nfull_well_e = [1e4, 1e300]\n",
    "camera_ambient.toml": b"[camera]\nambient = [0.0, 1e300]\n",
    "camera_exposure.toml": b"[camera]\nexposure = 1e300\n",
    "camera_read_noise.toml": b"[camera]\nread_noise_e = [0.0, 1e300]\n",
    "camera_thickness.toml": b"[camera]\nline_thickness_mm = [1e-9, 0.3]\n",
    "camera_wavelength.toml": b"[camera]\nwavelength_nm = [100.0, 660.0]\n",
    # 4096 x 4096 at f/0.95 and 405 nm: 4 sub-pixels per pixel, more than an image may take
    "camera_fast_lens.toml": b"images = true\n[camera]\nrows = 4096\ncolumns = 4096\n"
    b"f_number = [0.95, 8.0]\nwavelength_nm = 405.0\n",
    "offsets_1000.toml": b"[sensor]\nstandoff_offset_mm = [-1000.0, 1000.0]\n"
    b"lateral_offset_mm = [-1000.0, 1000.0]\n",
    "offsets_lateral.toml": b"[sensor]\nlateral_offset_mm = [-50.0, 50.0]\n",
    "offsets_far.toml": b"images = true\n[sensor]\nstandoff_offset_mm = [0.0, 45.0]\n",
    # the Cognex DS910B's depth of field is 8 mm: the default +-15 mm leaves it
    "offsets_small_preset.toml": b'[sensor]\npresets = ["paper", "cognex-ds910b"]\n',
}
#: Files made when the workspace is (name -> a function of the path).
GENERATED: dict[str, Any] = {}

F = "sensor.camera."


def _render(*pairs: str) -> tuple[str, ...]:
    """``seamtrack render v-groove-camera --at 10 --out OUT/image.png --set ...``"""
    return ("render", *CAMERA, *set_args(*pairs))


def _image_run(*pairs: str) -> tuple[str, ...]:
    """``seamtrack run v-groove-camera --set ... --out OUT``"""
    return run_args("v-groove-camera", *set_args(*pairs))


def _check(*pairs: str) -> tuple[str, ...]:
    """``seamtrack check v-groove-camera --set ...``"""
    return ("check", "v-groove-camera", *set_args(*pairs))


def _spec(name: str, spec: str, field: str, images: bool = False, key: str = "camera") -> Entry:
    """``seamtrack dataset SPEC`` (``images``: with ``--images``), its error naming the spec's
    ``key.field``."""
    return Entry(name, dataset_args(spec, images=images), field=f"{key}.{field}")


#: paper-v-groove (a mesh scene) in image mode: the camera on another scene.
IMAGE_MESH = (*MESH, *set_args('sensor.source="image"'))

ENTRIES: tuple[Entry, ...] = (
    # --- issue 23.1: camera values checked for size, not only sign
    naming_key("camera f-number 1e9", _render(f"{F}f_number=1e9")),
    naming_key("camera f-number 1e4", _image_run(f"{F}f_number=1e4")),
    naming_key("camera f-number 0.5", _check(f"{F}f_number=0.5")),
    naming_key("camera f-number 100 on paper-v-groove",
               run_args(*IMAGE_MESH, *set_args(f"{F}f_number=100"))),
    Entry("camera focal length 1e-9 mm", _render(f"{F}focal_length_mm=1e-9"), field="focal_length"),
    Entry("camera focal length 1e6 mm", _image_run(f"{F}focal_length_mm=1e6"),
          field="focal_length"),
    naming_key("camera exposure 1e300", _render(f"{F}exposure=1e300")),
    naming_key("camera exposure 1e-9", _check(f"{F}exposure=1e-9")),
    naming_key("camera full well 1e300 e", _render(f"{F}full_well_e=1e300")),
    naming_key("camera full well 1e-300 e", _render(f"{F}full_well_e=1e-300")),
    naming_key("camera full well 10 e", _image_run(f"{F}full_well_e=10")),
    naming_key("camera ambient 1e300", _render(f"{F}ambient=1e300")),
    naming_key("camera ambient 1.5", _check(f"{F}ambient=1.5")),
    naming_key("camera ambient 2 with a gocator",
               run_args(*IMAGE_MESH, *set_args('sensor.preset="gocator-2340"', f"{F}ambient=2"))),
    Entry("camera read noise 1e300 e", _render(f"{F}read_noise_e=1e300"), field="read_noise_e"),
    Entry("camera read noise 500 e", _image_run(f"{F}read_noise_e=500"), field="read_noise_e"),
    Entry("camera line 1e-9 mm thick", _check(f"{F}line_thickness_mm=1e-9"), field="thickness"),
    naming_key("camera line divergence 1e300 mrad", _render(f"{F}line_divergence_mrad=1e300")),
    Entry("camera waist 1e300 mm", _image_run(f"{F}waist_range_mm=1e300"), field="waist_range"),
    naming_key("camera bit depth -1", _check(f"{F}bit_depth=-1")),
    naming_key("camera wavelength nan", _render(f"{F}wavelength_nm=nan")),
    naming_key("camera rows 2.5", _check(f"{F}rows=2.5")),
    # --- issue 27.1: exposure control and the detector's relative threshold
    Entry("camera exposure mode hdr", _check(f'{F}exposure_mode="hdr"'), field="exposure_mode"),
    naming_key("camera target peak 1.5", _render(f"{F}target_peak=1.5")),
    naming_key("camera target peak 0", _check(f"{F}target_peak=0")),
    naming_key("camera exposure set rising", _check(f"{F}exposure_set=[1.0, 2.0]")),
    naming_key("camera exposure set not from 1", _render(f"{F}exposure_set=[0.5, 0.1]")),
    naming_key("camera exposure set empty", _check(f"{F}exposure_set=[]")),
    naming_key("camera exposure set 1e-9", _image_run(f"{F}exposure_set=[1.0, 1e-9]")),
    naming_key("detector relative 1", _check(f"{F}relative=1.0")),
    Entry("detector noise sigmas -1", _check(f"{F}noise_sigmas=-1.0"), field="noise_sigmas"),
    # --- issue 23.2: chip size x supersampling within the memory a run may take
    Entry("camera chip 20000 x 20000",
          _render(f"{F}rows=20000", f"{F}columns=20000"), field=f"{F}rows"),
    naming_key("camera columns 16385", _check(f"{F}columns=16385")),
    Entry("camera chip 16384 x 16384",
          _image_run(f"{F}rows=16384", f"{F}columns=16384"), field=f"{F}rows"),
    Entry("camera chip 4096 x 8192 supersample 8",
          _render(f"{F}rows=4096", f"{F}columns=8192", f"{F}supersample=8"), field=f"{F}columns"),
    Entry("camera chip 4096 x 8192 supersample 1",
          _check(f"{F}rows=4096", f"{F}columns=8192", f"{F}supersample=1"), field=f"{F}columns"),
    naming_key("camera chip 4096 x 4096 supersample 8",
               _check(f"{F}rows=4096", f"{F}columns=4096", f"{F}supersample=8")),
    naming_key("camera roi of 16384 x 4000",
               _image_run(f"{F}rows=16384", f"{F}columns=16384", f"{F}roi=[0, 16384, 0, 4000]")),
    # --- the same values through dataset specs: refused before dataset.json or spec.toml
    _spec("dataset --images camera f-number 1e9", "camera_f_number.toml", "f_number", True),
    _spec("dataset camera f-number 1e4", "camera_f_number_1e4.toml", "f_number"),
    _spec("dataset --images full well 1e-300", "camera_full_well.toml", "full_well_e", True),
    _spec("dataset images full well 1e300", "camera_full_well_big.toml", "full_well_e"),
    _spec("dataset --images ambient 1e300", "camera_ambient.toml", "ambient", True),
    _spec("dataset --images exposure 1e300", "camera_exposure.toml", "exposure", True),
    _spec("dataset --images read noise 1e300", "camera_read_noise.toml", "read_noise_e", True),
    _spec("dataset --images line 1e-9 mm thick", "camera_thickness.toml", "line_thickness_mm",
          True),
    _spec("dataset wavelength 100 nm", "camera_wavelength.toml", "wavelength_nm"),
    _spec("dataset images 4096 x 4096 at f/0.95", "camera_fast_lens.toml", "rows"),
    # --- issue 23.8: the seam within the sensor's range and field of view
    _spec("dataset offsets of 1000 mm", "offsets_1000.toml", "standoff_offset_mm", key="sensor"),
    _spec("dataset lateral offset 50 mm", "offsets_lateral.toml", "lateral_offset_mm",
          key="sensor"),
    _spec("dataset images standoff 45 mm beyond the range", "offsets_far.toml",
          "standoff_offset_mm", key="sensor"),
    _spec("dataset standoff beyond a small preset's range", "offsets_small_preset.toml",
          "standoff_offset_mm", key="sensor"),
)  # fmt: skip
