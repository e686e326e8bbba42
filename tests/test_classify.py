"""st.classify: which joint a profile shows, and every family extractor refusing the others."""

from __future__ import annotations

import numpy as np
import pytest

import seamtrack as st
from seamtrack.bench.extractors import LEVELS
from seamtrack.features.classify import FAMILIES, classify, scores
from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic import synthetic_profile
from seamtrack.sensing.profiles import Profile
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
SHAPES = [*FAMILIES, "flat", "block"]


def test_classify_is_a_lazy_public_name():
    assert "classify" in dir(st)
    assert st.classify is classify


def _profiles(shape, level, n, seed):
    rng = np.random.default_rng(seed)
    return [
        synthetic_profile(
            shape,
            SENSOR,
            rng=rng,
            rays=1024,
            imperfections=LEVELS[level],
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
            lateral_offset_mm=rng.uniform(-3, 3),
        )[0]
        for _ in range(n)
    ]


@pytest.mark.parametrize("shape", SHAPES)
def test_clean_profiles_are_classified_with_confidence(shape):
    for profile in _profiles(shape, "clean", 10, 31):
        joint, confidence = classify(profile)
        assert joint == (shape if shape in FAMILIES else "none")
        assert confidence > 0.5


@pytest.mark.parametrize("level", ["noise-0.05", "outliers+reflection", "dropouts"])
@pytest.mark.parametrize("shape", SHAPES)
def test_other_families_refuse_with_a_reason(shape, level):
    """The bench's imperfection levels: every family but the shape's own finds nothing in
    >= 95 % of 20 profiles, and says why; the classifier names the shape in >= 90 %."""
    profiles = _profiles(shape, level, 20, 32)
    for name in FAMILIES:
        if name == shape:
            continue
        answers = [extractor(name)(p) for p in profiles]
        assert np.mean([bool(f) for f in answers]) <= 0.05, name
        assert all(f.reason for f in answers if not f)
    want = shape if shape in FAMILIES else "none"
    assert np.mean([classify(p)[0] == want for p in profiles]) >= 0.9


def test_a_raised_block_is_no_groove_and_says_so():
    """The foot of a raised block is a concave corner and its top two convex ones: the groove
    needs plates beside its bevels, the corners faces that run to the profile's ends."""
    profile, _ = synthetic_profile("block", SENSOR, roll_deg=8.0, height_mm=6.0, width_mm=4.0)
    for name in FAMILIES:
        feature = extractor(name)(profile)
        assert not feature
    assert "not a" in extractor("outside-corner")(profile).reason
    s = scores(profile)
    assert all(v <= 0 for v in s.values())
    assert classify(profile)[0] == "none"


def test_scores_are_shares_of_the_profile():
    profile, _ = synthetic_profile("v-groove", SENSOR, roll_deg=5.0)
    s = scores(profile)
    assert s["v-groove"] == pytest.approx(1.0, abs=0.01)
    assert all(-1.0 <= v <= 1.0 for v in s.values())


_bad = [
    np.empty((0, 2)),
    np.array([[0.0, 90.0]]),
    np.full((50, 2), np.nan),
    np.full((500, 2), 90.0),
    np.column_stack([np.linspace(-1e6, 1e6, 300), np.full(300, 1e6)]),
]


@pytest.mark.parametrize("points", _bad)
def test_classify_says_none_on_degenerate_profiles(points):
    joint, confidence = classify(Profile(points))
    assert joint == "none" and confidence == 1.0
