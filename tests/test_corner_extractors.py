"""The corner extractors' (fillet, outside corner) fast path, ``extractors._corner``, against
their Python steps (``ExtractorBase._arms`` and ``_two_faces``, which build a Line per face): the
same feature (point, world point, reason, confidence) and the same explained share, bit for bit,
on noisy, reflected, tilted and wrong-family profiles; and the seam point of a noise-free
fillet within the sensor's resolution of the faces' analytic corner."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.features import extractors as ex_module
from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
RESOLUTION_MM = 0.01  # the paper's sensor (Table 3)
ROUGH = Imperfections(
    noise_mm=0.03, outlier_fraction=0.02, dropout_runs=2, reflection_probability=0.5
)


def _profiles(joint, n, seed):
    """Profiles of ``joint`` (and of other families) at random tilts, some imperfect."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        family = joint if k % 4 else ("v-groove", "lap", "square-butt")[k // 4 % 3]
        profile, _ = synthetic_profile(
            family,
            SENSOR,
            rng=rng,
            pitch_deg=float(rng.uniform(-15.0, 15.0)),
            roll_deg=float(rng.uniform(-15.0, 15.0)),
            lateral_offset_mm=float(rng.uniform(-2.0, 2.0)),
            imperfections=ROUGH if k % 2 else Imperfections(),
        )
        out.append(profile)
    return out


def _same(a, b):
    (fa, sa), (fb, sb) = a, b
    num = lambda x, y: x == y or (math.isnan(x) and math.isnan(y))  # noqa: E731
    return (
        np.array_equal(fa.point_laser, fb.point_laser, equal_nan=True)
        and np.array_equal(fa.point_world, fb.point_world, equal_nan=True)
        and fa.reason == fb.reason
        and fa.joint == fb.joint
        and num(fa.confidence, fb.confidence)
        and num(sa, sb)
    )


@pytest.mark.parametrize("min_explained", [0.5, 0.8])
@pytest.mark.parametrize("joint", ["fillet", "outside-corner"])
def test_fast_path_answers_as_the_python_steps(joint, min_explained, monkeypatch):
    find = extractor(joint, min_explained=min_explained)
    profiles = _profiles(joint, 40, seed=28)
    fast = [find.scored(p) for p in profiles]
    calls = []
    real = ex_module._corner
    monkeypatch.setattr(ex_module, "_corner", lambda *a: calls.append(real(*a)))
    slow = [find.scored(p) for p in profiles]
    assert len(calls) == len(profiles)  # the fast path ran on every profile (and is now off)
    assert sum(c is not None for c in calls) >= len(profiles) // 2  # and answered most itself
    assert all(_same(a, b) for a, b in zip(fast, slow, strict=True))
    assert sum(bool(f) for f, _ in fast) >= len(profiles) // 2  # most found: a real comparison


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), [(0.0, 0.0), (12.0, -9.0), (-10.0, 14.0)])
def test_fast_fillet_point_is_the_faces_corner(pitch_deg, roll_deg):
    profile, truth = synthetic_profile(
        "fillet", SENSOR, pitch_deg=pitch_deg, roll_deg=roll_deg, lateral_offset_mm=0.37
    )
    feature = extractor("fillet")(profile)
    assert feature, feature.reason
    assert float(np.hypot(*(feature.point_laser - truth.seam_laser))) <= RESOLUTION_MM
