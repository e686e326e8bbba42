"""Datasets with camera images (``--images``): the image truth lies on the drawn section, the
profile measured from an ideal image follows that truth, the geometric samples do not change,
and 1 or 2 workers write the same bytes."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np
import pytest

import seamtrack as st
from seamtrack.cli.main import main
from seamtrack.datasets import joints
from seamtrack.datasets.generate import generate
from seamtrack.datasets.layout import ARRAYS, IMAGE_ARRAYS
from seamtrack.datasets.spec import MAX_CHUNK_PIXELS, parse_spec, with_images
from seamtrack.datasets.store import write_dataset

pytestmark = pytest.mark.embree

#: Every camera noise source off: the optics alone (line width, diffraction, pixels).
IDEAL = {
    "read_noise_e": 0.0,
    "ambient": 0.0,
    "speckle_probability": 0.0,
    "shot_noise_probability": 0.0,
}
V_GROOVE = {
    "families": ["v-groove"],
    "thickness_mm": 8.0,
    "groove_angle_deg": 60.0,
    "root_face_mm": 1.0,
    "gap_mm": 1.0,
    "misalignment_mm": 0.0,
}
#: Small images with every noise source drawn (the template's camera), chunks of 2.
SMALL = {
    "images": True,
    "rays": 128,
    "chunk_size": 2,
    "seed": 11,
    "camera": {"rows": 64, "columns": 128},
}


def _digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def _distance_to_section(points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """(m,) distance of seam-frame (y, z) points (m, 2) to the nearest segment (k, 4)."""
    a, e = segs[:, :2], segs[:, 2:] - segs[:, :2]
    rel = points[:, None, :] - a[None]
    s = np.clip(np.einsum("mkj,kj->mk", rel, e) / np.einsum("kj,kj->k", e, e), 0.0, 1.0)
    gap = rel - s[..., None] * e[None]
    return np.asarray(np.min(np.hypot(gap[..., 0], gap[..., 1]), axis=1))


@pytest.fixture(scope="module")
def ideal_v_groove() -> dict[str, np.ndarray]:
    spec = parse_spec({"images": True, "rays": 256, "joint": V_GROOVE,
                       "part": {"materials": ["white matte"]},
                       "camera": {"rows": 256, "columns": 256, **IDEAL}})  # fmt: skip
    return generate(spec, 0, 6)


def test_image_truth_lies_on_the_drawn_section(ideal_v_groove: dict[str, np.ndarray]) -> None:
    """Every column's ideal stripe point, taken back to the seam frame, is on the V-groove's
    section: exactly (1e-9 mm) between its corners, within a pixel column's width where a
    column straddles a corner (the truth interpolates between fan rays there)."""
    polylines, seam, _ = joints.section(
        "v-groove", thickness_mm=8.0, groove_angle_rad=math.radians(60.0), root_face_mm=1.0,
        gap_mm=1.0, misalignment_mm=0.0, web_angle_rad=1.0, corner_angle_rad=1.0,
    )  # fmt: skip
    assert seam is not None
    segs = joints.segments(polylines, seam)
    for i in range(len(ideal_v_groove["index"])):
        truth = ideal_v_groove["image_truth_laser"][i]
        seen = np.isfinite(truth[:, 0])
        assert seen.sum() > 200  # a stripe across most of the 256 columns
        T = ideal_v_groove["T_seam_sensor"][i]
        laser = np.column_stack([np.zeros(seen.sum()), truth[seen]])
        seam_frame = laser @ T[:3, :3].T + T[:3, 3]
        distance = _distance_to_section(seam_frame[:, 1:], segs)
        assert np.mean(distance < 1e-9) >= 0.97
        assert distance.max() < 0.05


def test_profile_measured_from_an_ideal_image_follows_the_truth(
    ideal_v_groove: dict[str, np.ndarray],
) -> None:
    """The centroid detector on an image without noise finds every column with a truth, and
    its points are within 0.005 mm of the truth (median), 0.06 mm everywhere (at a corner)."""
    measured = ideal_v_groove["image_points_laser"]
    truth = ideal_v_groove["image_truth_laser"]
    valid = ideal_v_groove["image_valid"]
    seen = np.isfinite(truth[..., 0])
    assert valid[seen].all()
    # A column that a piece of the stripe ends in shows light but has no truth (the piece
    # covers less than its centre): such columns border a column with truth.
    extra = valid & ~seen
    next_to_truth = np.zeros_like(seen)
    next_to_truth[:, 1:] |= seen[:, :-1]
    next_to_truth[:, :-1] |= seen[:, 1:]
    assert extra.sum() <= 4 * len(seen) and not (extra & ~next_to_truth).any()
    assert not ideal_v_groove["image_reflection"].any()  # white matte: no specular bounce
    error = np.hypot(*(measured[seen] - truth[seen]).T)
    assert np.median(error) < 0.005
    assert error.max() < 0.06


def test_images_leave_the_geometric_samples_as_they_were() -> None:
    """The camera draws from a generator of its own: the profile and labels of sample i are
    the same bytes with and without images."""
    plain = parse_spec({"rays": 128, "seed": 5})
    both = generate(with_images(parse_spec({"rays": 128, "seed": 5, "camera": SMALL["camera"]})),
                    0, 3)  # fmt: skip
    alone = generate(plain, 0, 3)
    for name in ARRAYS:
        assert np.array_equal(both[name], alone[name], equal_nan=True), name
    assert set(both) == set(ARRAYS) | set(IMAGE_ARRAYS)


def test_one_and_two_workers_write_the_same_image_bytes(tmp_path: Path) -> None:
    """6 images of 64 x 128 in 3 chunks, every camera noise source drawn (speckle, shot and read
    noise, ambient light): the chunk files are identical on 1 and 2 workers."""
    write_dataset(parse_spec(SMALL), 6, tmp_path / "one", workers=1)
    write_dataset(parse_spec(SMALL), 6, tmp_path / "two", workers=2)
    assert _digests(tmp_path / "one") == _digests(tmp_path / "two")
    data = st.datasets.open(tmp_path / "one")
    sample = data[5]
    assert sample["image"].dtype == np.uint16 and sample["image"].shape == (64, 128)
    assert sample["image"].max() <= data.names["image_levels"] == 1023
    assert data[0:6]["image_points_laser"].shape == (6, 128, 2)
    handle = data._file(0)["image"]
    assert handle.chunks == (1, 64, 128) and handle.compression == "gzip"
    data.close()


def test_images_flag_through_the_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "spec.toml"
    spec.write_text(
        'rays = 64\n[joint]\nfamilies = ["fillet"]\n[camera]\nrows = 32\ncolumns = 64\n'
    )
    code = main(["dataset", str(spec), "--n", "2", "--out", str(tmp_path / "d"), "--images", "-q"])
    assert code == 0
    data = st.datasets.open(tmp_path / "d")
    assert data.spec.images and data.spec.chunk_size == min(1024, MAX_CHUNK_PIXELS // (32 * 64))
    assert data[1]["image"].shape == (32, 64)
    assert np.isfinite(data[1]["image_truth_row"]).any()
    assert data.column("image", stop=1).shape == (1, 32, 64)
    data.close()
    capsys.readouterr()
    assert main(["dataset", "--info", str(tmp_path / "d")]) == 0
    assert "images 64 x 32 (uint16, 10 bits)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("material", "shows"), [("bright aluminium", True), ("white matte", False)]
)
def test_the_material_decides_the_false_stripe(material: str, shows: bool) -> None:
    """The drawn material reaches the renderer: with the laser pitched 12-20 deg along a
    V-groove, bright aluminium's specular bounce throws a false stripe into every image (as in
    image mode, README "Camera images"); a white Lambertian part throws none."""
    spec = parse_spec({"images": True, "rays": 128, "joint": V_GROOVE,
                       "part": {"materials": [material]},
                       "sensor": {"tilt_deg": [12.0, 20.0], "roll_deg": 0.0,
                                  "lateral_offset_mm": 0.0},
                       "camera": {"rows": 128, "columns": 256, **IDEAL}})  # fmt: skip
    out = generate(spec, 0, 3)
    reflection = out["image_reflection"]
    assert np.array_equal(np.isfinite(out["image_reflection_row"]), reflection)
    if shows:
        assert (reflection.sum(axis=1) >= 20).all()
    else:
        assert not reflection.any()
