"""`passes` in the dataset spec (issue 25): V-grooves partly filled with beads, their 7 points
stored as labels. Oracle: the section the stripe is cast on (the labels must lie on the
measured stripe, noise off) and the empty groove's own root corners."""

from __future__ import annotations

import numpy as np
import pytest

import seamtrack as st
from seamtrack.datasets.generate import generate
from seamtrack.datasets.spec import NOISE_OFF, SpecError, parse_spec

SPEC = {
    "joint": {"families": ["v-groove"], "passes": [0, 3], "thickness_mm": [10.0, 14.0]},
    "noise": NOISE_OFF,
    "rays": 512,
}


def test_filled_grooves_carry_their_7_points_on_the_stripe(tmp_path):
    st.datasets.write(SPEC, 12, tmp_path / "ds")
    data = st.datasets.open(tmp_path / "ds")
    sample = data[0]
    assert sample["groove_points_laser"].shape == (7, 2)
    layers = data[:]["layers"]
    assert set(layers.tolist()) <= {0, 1, 2, 3} and layers.max() >= 1
    near = []
    for i in range(len(data)):
        s = data[i]
        if s["layers"] == 0:  # empty: the bottom corners are the root corners
            assert s["groove_points_laser"][[1, 5]] == pytest.approx(
                s["features_laser"][[2, 3]], abs=1e-9
            )
            continue
        p = s["points_laser"][s["valid"]]
        g = s["groove_points_laser"][1:6]  # the bottom corners and points: on the beads
        d = np.min(np.hypot(g[:, None, 0] - p[None, :, 0], g[:, None, 1] - p[None, :, 1]), 1)
        near += (d <= 0.1).tolist()
    assert np.mean(near) >= 0.9


def test_without_passes_nothing_changes():
    plain = parse_spec({"joint": {"families": ["v-groove"]}, "noise": NOISE_OFF, "rays": 256})
    out = generate(plain, 0, 3)
    assert "groove_points_laser" not in out and "layers" not in out


def test_too_many_layers_are_refused():
    with pytest.raises(SpecError) as err:
        parse_spec({"joint": {"passes": [0, 40]}})
    assert "passes" in err.value.field


@pytest.mark.parametrize(
    ("section", "key", "wrong", "nearest"),
    [
        ("joint", "families", "v-grove", "v-groove"),
        ("sensor", "presets", "papr", "paper"),
        ("part", "materials", "mill-scale stel", "mill-scale steel"),
    ],
)
def test_an_unknown_name_is_refused_with_the_nearest_known_one(section, key, wrong, nearest):
    with pytest.raises(SpecError) as err:
        parse_spec({section: {key: [wrong]}})
    assert err.value.field.endswith(f"{section}.{key}.0")
    assert f"did you mean {nearest!r}?" in (err.value.fix or "")
