"""The robust front end (range quantum, noise, spikes and reflections) and the extractors on
synthetic profiles with the artefacts of a real laser line sensor (features.artefacts), at
several range units and pitches."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from seamtrack.features.artefacts import SensorArtefacts, real_sensor_profile
from seamtrack.features.classify import classify
from seamtrack.features.extractors import extractor
from seamtrack.features.lines import segment_profile
from seamtrack.features.refusal import Refusal
from seamtrack.features.robust import front_end, range_quantum, reject
from seamtrack.features.synthetic import synthetic_profile
from seamtrack.sensing.profiles import Profile, Reason
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
IDEAL = dataclasses.replace(SENSOR, quantize=False)
FAMILIES = ("v-groove", "square-butt", "fillet", "lap", "outside-corner")
# The LDS V-groove: about 63 deg, no gap, no root face, 6-7 mm deep.
LDS_V = {"included_angle_deg": 63.0, "gap_mm": 0.0, "root_face_mm": 0.0, "thickness_mm": 7.0}
DETECTED_MM = 0.5


# ----------------------------------------------------------------- the front end
@pytest.mark.parametrize("unit", [0.05, 0.01, 0.001])
def test_range_quantum_finds_an_integer_range_unit(unit):
    rng = np.random.default_rng(1)
    y = np.linspace(-10, 10, 2000)
    z = np.round((90.0 + 0.17 * y + rng.normal(0, 0.4 * unit, y.size)) / unit) * unit
    assert range_quantum(z) == pytest.approx(unit, rel=1e-6)


def test_range_quantum_is_zero_for_unquantized_ranges_and_for_one_step():
    rng = np.random.default_rng(2)
    assert range_quantum(90.0 + rng.normal(0, 0.01, 1000)) == 0.0
    # Two flat plates 2 mm apart: one step between repeated values is no unit.
    assert range_quantum(np.r_[np.full(500, 91.0), np.full(500, 89.0)]) == 0.0


def test_quantized_profile_is_split_at_corners_not_at_every_count():
    """Integer range units of 0.05 mm on a V-groove with plates tilted 10 deg: the old
    noise estimate (median second difference) read 0 and split every step; the tolerance now
    covers the unit and the profile is five straight pieces."""
    rng = np.random.default_rng(3)
    art = SensorArtefacts(spike_runs=0.0, dropout_groove=0.0, dropout_plate=0.0)
    profile, _ = real_sensor_profile("v-groove", rng, artefacts=art, roll_deg=10.0, **LDS_V)
    fe = front_end(profile)
    assert not isinstance(fe, Refusal)
    assert fe.quantum == pytest.approx(0.05, rel=1e-6)
    assert fe.tol >= 2.0 * fe.quantum
    seg = segment_profile(profile)
    assert not isinstance(seg, Refusal)
    assert len([ln for ln in seg.lines if ln.count >= 50]) == 4  # plates and bevels


def _plate_with(kind: str, side: float = 1.0) -> tuple[Profile, np.ndarray]:
    """A flat plate (roll 5 deg) with a spike or a multipath streak on columns 400-429
    (``side`` > 0: behind the plate, < 0: in front), and the columns changed."""
    profile, _ = synthetic_profile("flat", IDEAL, rays=1024, roll_deg=5.0)
    pts = profile.points_laser.copy()
    cols = np.array([500]) if kind == "spike" else np.arange(400, 430)
    r = np.hypot(*pts[cols].T)
    dr = side * (3.0 if kind == "spike" else np.linspace(2.0, 4.0, len(cols)))
    pts[cols] *= ((r + dr) / r)[:, None]  # along the rays
    return Profile(pts, T_world_sensor=profile.T_world_sensor), cols


@pytest.mark.parametrize(
    ("kind", "reason"), [("spike", Reason.SPIKE), ("streak", Reason.REFLECTION)]
)
def test_spikes_and_streaks_are_rejected_with_their_reason(kind, reason):
    profile, cols = _plate_with(kind)
    cleaned = reject(profile)
    # A streak's last point may go first, as an isolated spike.
    assert np.isin(cleaned.reason[cols], (Reason.SPIKE, Reason.REFLECTION)).all()
    assert np.mean(cleaned.reason[cols] == reason) >= 0.9
    assert not cleaned.valid[cols].any()
    others = np.setdiff1d(np.flatnonzero(profile.valid), cols)
    assert (cleaned.reason[others] == Reason.VALID).all()
    # Reasons of the input (lost columns) are kept.
    assert (cleaned.reason[~profile.valid] == profile.reason[~profile.valid]).all()


def test_a_streak_on_a_plate_makes_no_joint():
    """In front of a plate a streak is no joint for any family. Behind it, a steep streak
    looks like the wall of a gap (the square butt reads one there); the others refuse."""
    profile, _ = _plate_with("streak", side=-1.0)
    assert all(not extractor(name)(profile) for name in FAMILIES)
    assert classify(profile)[0] == "none"
    behind, _ = _plate_with("streak")
    assert all(not extractor(name)(behind) for name in FAMILIES if name != "square-butt")


# ----------------------------------------------------------------- the artefact model
def test_artefact_model_matches_its_calibration():
    """Integer units, dropouts mostly in the groove, spikes inside it: the statistics the
    defaults were measured as (docs/extractors.md), within sampling error. The oracle is the
    same pose drawn without artefacts."""
    rng = np.random.default_rng(4)
    art = SensorArtefacts()
    none = SensorArtefacts(
        noise_units=0.0, dropout_groove=0.0, dropout_plate=0.0, dead_fraction=0.0, spike_runs=0.0
    )
    lost_in, lost_out, off_in = [], [], []
    for _ in range(40):
        pose = {"roll_deg": rng.uniform(-11, 11), "lateral_offset_mm": rng.uniform(-2, 2)}
        profile, truth = real_sensor_profile("v-groove", rng, **pose, **LDS_V)
        clean, _ = real_sensor_profile(
            "v-groove", np.random.default_rng(0), artefacts=none, **pose, **LDS_V
        )
        z = profile.valid_points[:, 1]
        assert np.allclose(z / art.range_unit_mm, np.round(z / art.range_unit_mm), atol=1e-6)
        dead = len(profile) - round(art.dead_fraction * len(profile))
        assert not profile.valid[dead:].any()
        seen = clean.valid[:dead]
        y = clean.points_laser[:dead, 0]
        lo, hi = np.sort(truth.edges_laser[:, 0])
        groove = seen & (y >= lo) & (y <= hi)
        lost = profile.reason[:dead] == Reason.DROPOUT
        lost_in.append(lost[groove].mean())
        lost_out.append(lost[seen & ~groove].mean())
        both = groove & profile.valid[:dead]
        dz = np.abs(profile.points_laser[:dead, 1] - clean.points_laser[:dead, 1])
        off_in.append((dz[both] > 0.5).mean())
    assert np.mean(lost_in) == pytest.approx(art.dropout_groove, abs=0.02)
    assert np.mean(lost_out) < 0.01
    assert 0.1 < np.mean(off_in) < 0.4  # a quarter on the LDS scans


def _campaign(shape, n, seed, unit=0.05, rays=2048, **params):
    """Profiles of ``shape`` with the LDS's artefacts at range ``unit``, tilted as its plates
    (up to 11 deg) and pitched and offset a little."""
    rng = np.random.default_rng(seed)
    art = dataclasses.replace(SensorArtefacts(), range_unit_mm=unit)
    return [
        real_sensor_profile(
            shape,
            rng,
            artefacts=art,
            rays=rays,
            roll_deg=rng.uniform(-11, 11),
            pitch_deg=rng.uniform(-5, 5),
            lateral_offset_mm=rng.uniform(-2, 2),
            **params,
        )
        for _ in range(n)
    ]


def _errors(name, profiles):
    ex = extractor(name)
    out = []
    for profile, truth in profiles:
        f = ex(profile)
        out.append(float(np.hypot(*(f.point_laser - truth.seam_laser))) if f else np.inf)
    return np.array(out)


@pytest.mark.parametrize(
    ("unit", "rays"),
    [(0.05, 2048), (0.01, 2048), (0.05, 460), (0.005, 4600)],
    ids=["0.05mm-2048", "0.01mm-2048", "pitch-0.05mm", "pitch-0.005mm"],
)
def test_v_groove_with_real_sensor_artefacts_detects_90_percent(unit, rays):
    """The same extractor, no parameter changed, at range units of 0.005-0.05 mm and pitches
    of 0.005-0.05 mm (460-4600 columns over the paper sensor's field of view)."""
    e = _errors("v-groove", _campaign("v-groove", 30, 21, unit, rays, **LDS_V))
    assert np.mean(e <= DETECTED_MM) >= 0.9
    assert np.percentile(e[np.isfinite(e)], 95) <= _cell_mm(unit, rays)


def _cell_mm(unit: float, rays: int) -> float:
    """The sampling cell of a profile: the range unit, or the column pitch (the field of view
    at its widest over the columns), whichever is coarser. The seam point is where lines fitted
    over many samples meet, so 95 % of them lie within one cell of the truth (the fit
    averages the quantization and the noise of 0.45 units; what is left is the corner's own
    sampling)."""
    return max(unit, SENSOR.fov_far_mm / rays)


#: The lap's seam is the corner under the top sheet's edge. Where a stray line (a spike run,
#: geometric in length with a mean of ``spike_mean_run_mm``) covers the corner, the extractor
#: takes the lower sheet's visible end or the edge's foot: off by up to the covered length. Of
#: geometric runs, 95 % are shorter than ln(20) ~ 3 of their means.
LAP_P95_MM = 3.0 * SensorArtefacts().spike_mean_run_mm


@pytest.mark.parametrize("shape", ["square-butt", "fillet", "lap", "outside-corner"])
def test_other_families_with_real_sensor_artefacts_detect_90_percent(shape):
    """At the LDS's range unit (0.05 mm) and 2048 columns; the seam points within one sampling
    cell, the lap's within what a stray line over its corner can cover (LAP_P95_MM)."""
    e = _errors(shape, _campaign(shape, 30, 22))
    assert np.mean(e <= DETECTED_MM) >= 0.9
    bound = LAP_P95_MM if shape == "lap" else _cell_mm(0.05, 2048)
    assert np.percentile(e[np.isfinite(e)], 95) <= bound


@pytest.mark.parametrize("shape", ["v-groove", *FAMILIES[1:], "flat", "block"])
def test_wrong_joint_extractors_and_the_classifier_say_not_my_joint(shape):
    """On profiles of one shape (a raised block and a flat plate included), every other
    family's extractor finds nothing in >= 90 % and the classifier names the shape ("none"
    for no joint) in >= 90 %."""
    profiles = _campaign(shape, 30, 23, **(LDS_V if shape == "v-groove" else {}))
    for name in FAMILIES:
        if name != shape:
            found = np.mean([bool(extractor(name)(p)) for p, _ in profiles])
            assert found <= 0.1, name
    want = shape if shape in FAMILIES else "none"
    kinds = [classify(p) for p, _ in profiles]
    assert np.mean([k == want for k, _ in kinds]) >= 0.9
    assert all(0.0 <= c <= 1.0 for _, c in kinds)
