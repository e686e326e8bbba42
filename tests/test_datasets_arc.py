"""Datasets with the welding arc in their images (``[arc]`` of a dataset spec): the arc only adds
light (an ideal camera: no noise to redraw), its labels stay the arc-free truth, the camera's
draws do not change, a higher current lights more, the draws stay within their ranges, and 1 or
2 workers write the same bytes."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

import seamtrack as st
from seamtrack.datasets.generate import generate
from seamtrack.datasets.images import ARC_PARAM_NAMES
from seamtrack.datasets.spec import SpecError, parse_spec
from seamtrack.datasets.store import write_dataset

pytestmark = pytest.mark.embree

IDEAL = {"read_noise_e": 0.0, "ambient": 0.0, "speckle_probability": 0.0,
         "shot_noise_probability": 0.0}  # fmt: skip
V_GROOVE = {"families": ["v-groove"], "thickness_mm": 8.0, "groove_angle_deg": 60.0,
            "root_face_mm": 1.0, "gap_mm": 1.0, "misalignment_mm": 0.0}  # fmt: skip
BASE = {"images": True, "rays": 128, "joint": V_GROOVE, "part": {"materials": ["mill-scale steel"]},
        "camera": {"rows": 128, "columns": 128, **IDEAL}}  # fmt: skip
N = 4


def _with_arc(**arc: object) -> dict[str, np.ndarray]:
    return generate(parse_spec({**BASE, "arc": arc}), 0, N)


@pytest.fixture(scope="module")
def without() -> dict[str, np.ndarray]:
    return generate(parse_spec(BASE), 0, N)


def test_the_arc_only_adds_light_and_leaves_the_labels(without: dict[str, np.ndarray]) -> None:
    with_arc = _with_arc(probability=1.0, current_a=[250.0, 350.0], look_ahead_mm=20.0)
    assert "arc_params" not in without  # a spec without the arc stores nothing of it
    brighter = with_arc["image"].astype(np.int64) - without["image"].astype(np.int64)
    assert brighter.min() >= 0  # light adds up; an ideal camera draws nothing else
    assert np.count_nonzero(brighter) > 0.1 * brighter.size
    for key in ("image_truth_row", "image_truth_laser", "camera_params", "points_laser"):
        assert np.array_equal(with_arc[key], without[key], equal_nan=True), key
    on = dict(zip(ARC_PARAM_NAMES, with_arc["arc_params"].T, strict=True))
    assert np.all(on["arc"] == 1.0) and np.all(on["process"] == 0.0)
    assert np.all((250.0 <= on["current_a"]) & (on["current_a"] <= 350.0))
    assert np.all(on["look_ahead_mm"] == 20.0)


def test_a_sample_without_the_arc_is_the_arc_free_image(without: dict[str, np.ndarray]) -> None:
    """The coin draws about half the samples with the arc; the others are the spec's images
    without it, byte for byte, and store NaN for the ranges they did not draw."""
    half = _with_arc(probability=0.5, processes=["tig", "mag-short"])
    off = half["arc_params"][:, 0] == 0.0
    assert 0 < np.count_nonzero(off) < N  # seed 0 draws both (a coin at 0.5 per sample)
    assert np.array_equal(half["image"][off], without["image"][off])
    assert np.isnan(half["arc_params"][off, 1:]).all()
    assert set(half["arc_params"][~off, 1]) <= {0.0, 1.0}


def test_a_higher_current_lights_the_image_more(without: dict[str, np.ndarray]) -> None:
    """The arc's radiance, the plate it lights and its glow rise with the current (docs/arc.md):
    the same samples at 350 A gather more light than at 100 A."""
    light = {}
    for amps in (100.0, 350.0):
        arc = _with_arc(probability=1.0, current_a=amps, spatter=False)
        light[amps] = (arc["image"].astype(np.int64) - without["image"].astype(np.int64)).sum()
    assert light[350.0] > light[100.0] > 0


def test_one_and_two_workers_write_the_same_arc_bytes(tmp_path: Path) -> None:
    spec = parse_spec({**BASE, "chunk_size": 2, "seed": 3, "arc": {"probability": 1.0}})
    for workers, name in ((1, "one"), (2, "two")):
        write_dataset(spec, 4, tmp_path / name, workers=workers)

    def digests(folder: Path) -> dict[str, str]:
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.glob("*.h5")}

    assert digests(tmp_path / "one") == digests(tmp_path / "two")
    assert len(digests(tmp_path / "one")) == 2
    data = st.datasets.open(tmp_path / "one")
    assert data.names["arc_param_names"] == list(ARC_PARAM_NAMES)
    assert data.names["arc_process_names"] == ["mag-spray"]
    assert data[0:4]["arc_params"].shape == (4, len(ARC_PARAM_NAMES))
    data.close()


@pytest.mark.parametrize(
    ("arc", "images", "field"),
    [
        ({"probability": 1.0}, False, "arc.probability"),
        ({"probability": 1.0, "current_a": 2000.0}, True, "arc.current_a"),
        ({"probability": 1.0, "filter_fwhm_nm": 0.05}, True, "arc.filter_fwhm_nm"),
        ({"probability": 1.0, "processes": ["laser"]}, True, "arc.processes"),
    ],
)
def test_a_bad_arc_is_named(arc: dict[str, object], images: bool, field: str) -> None:
    with pytest.raises(SpecError) as err:
        parse_spec({**BASE, "images": images, "arc": arc})
    assert field in err.value.field
