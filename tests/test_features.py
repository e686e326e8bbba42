"""Feature extractors on synthetic profiles with known ground truth, and the registry."""

from __future__ import annotations

import ast
import math
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import seamtrack.features
from seamtrack.errors import PluginError
from seamtrack.features.classify import classify
from seamtrack.features.extractors import BUILTIN, FeatureExtractor, extractor
from seamtrack.features.robust import reject
from seamtrack.features.synthetic import Imperfections, ray_angles, synthetic_profile
from seamtrack.sensing.profiles import Feature, Profile
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
RESOLUTION_MM = 0.01  # the paper's sensor (Table 3)
FAMILIES = ["square-butt", "v-groove", "fillet", "lap", "outside-corner"]
TILTS = [(p, r) for p in (-15.0, 0.0, 15.0) for r in (-15.0, 0.0, 15.0)]
DETECTED_MM = 0.5  # a seam point this close counts as a detection


def _lap_shear_bound(truth, step_mm):
    """How far the top edge's normal projection can miss the corner when the corner is in
    shadow: the face y_J = 0 and the sheets z_J = c cut the tilted laser plane in lines that
    are not perpendicular when the sensor is both pitched and rolled."""
    R = truth.T_world_sensor[:3, :3]
    face = np.array([R[1, 2], -R[1, 1]])
    sheet = np.array([R[2, 2], -R[2, 1]])
    cos = abs(face @ sheet) / (np.linalg.norm(face) * np.linalg.norm(sheet))
    return step_mm * math.tan(math.asin(min(1.0, cos)))


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), TILTS)
@pytest.mark.parametrize("joint", FAMILIES)
def test_noise_free_seam_within_resolution(joint, pitch_deg, roll_deg):
    profile, truth = synthetic_profile(
        joint, SENSOR, pitch_deg=pitch_deg, roll_deg=roll_deg, lateral_offset_mm=0.37
    )
    feature = extractor(joint)(profile)
    assert feature, feature.reason
    error = float(np.hypot(*(feature.point_laser - truth.seam_laser)))
    bound = RESOLUTION_MM
    if joint == "lap":
        bound += _lap_shear_bound(truth, 2.0)
    if joint == "v-groove":
        # The root corners end the bevels between two rays: on a bevel as steep as 75 deg in
        # the laser plane, half a ray spacing along it is 0.018 mm (see the README).
        bound = 2 * RESOLUTION_MM
    assert error <= bound
    assert feature.point_world == pytest.approx(truth.seam_world, abs=bound * 1.01)


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), [(0.0, 0.0), (15.0, -15.0), (-15.0, 10.0)])
def test_gapless_v_groove_apex_within_resolution(pitch_deg, roll_deg):
    profile, truth = synthetic_profile(
        "v-groove", SENSOR, pitch_deg=pitch_deg, roll_deg=roll_deg, gap_mm=0.0, root_face_mm=0.0
    )
    feature = extractor("v-groove")(profile)
    assert float(np.hypot(*(feature.point_laser - truth.seam_laser))) <= RESOLUTION_MM
    assert feature.gap_mm == 0.0


def _campaign(joint, imperfections, n, seed):
    rng = np.random.default_rng(seed)
    ex = extractor(joint)
    errors = []
    for _ in range(n):
        profile, truth = synthetic_profile(
            joint,
            SENSOR,
            rng=rng,
            imperfections=imperfections,
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
            lateral_offset_mm=rng.uniform(-3, 3),
        )
        f = ex(profile)
        errors.append(float(np.hypot(*(f.point_laser - truth.seam_laser))) if f else math.inf)
    return np.array(errors)


@pytest.mark.parametrize("joint", FAMILIES)
def test_noise_005_detects_99_percent_with_p95_under_01_mm(joint):
    errors = _campaign(joint, Imperfections(noise_mm=0.05), 100, seed=11)
    assert np.mean(errors <= DETECTED_MM) >= 0.99
    assert np.percentile(errors[np.isfinite(errors)], 95) <= 0.1


OUTLIERS_AND_REFLECTION = Imperfections(
    noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0
)


@pytest.mark.parametrize("joint", FAMILIES)
def test_outliers_and_false_reflection_detect_95_percent(joint):
    errors = _campaign(joint, OUTLIERS_AND_REFLECTION, 100, seed=12)
    assert np.mean(errors <= DETECTED_MM) >= 0.95


@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_flat_plate_gives_no_seam_point(name):
    rng = np.random.default_rng(13)
    ex = extractor(name)
    found = 0
    for _ in range(100):
        profile, _ = synthetic_profile(
            "flat",
            SENSOR,
            rng=rng,
            rays=1024,
            imperfections=Imperfections(noise_mm=0.05),
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
        )
        found += bool(ex(profile))
    assert found <= 1


# The generic extractor has no joint model: it reports the jump to a reflection as a gap.
@pytest.mark.parametrize("name", FAMILIES)
def test_flat_plate_with_a_false_reflection_gives_no_seam_point(name):
    """A reflection behind a plate looks like the bottom of a gap, one in front like a plate
    edge: neither makes a joint (>= 99 % of 200 plates give no seam point)."""
    rng = np.random.default_rng(14)
    ex = extractor(name)
    found = 0
    for _ in range(200):
        profile, _ = synthetic_profile(
            "flat",
            SENSOR,
            rng=rng,
            rays=1024,
            imperfections=OUTLIERS_AND_REFLECTION,
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
        )
        found += bool(ex(profile))
    assert found <= 2


def _with_stripe(profile, truth, y0_mm, y1_mm, dz_mm, slope):
    """The profile with the columns aimed at y in [y0, y1] (at the seam's range) replaced by a
    straight false stripe: through the first column's surface point moved ``dz_mm`` along
    z_L (> 0: behind the surface), ``slope`` = dz/dy."""
    phi = ray_angles(SENSOR, len(profile.points_laser))
    zs = float(truth.seam_laser[1]) if truth.has_seam else float(SENSOR.range_center_mm)
    cols = np.flatnonzero((zs * np.tan(phi) >= y0_mm) & (zs * np.tan(phi) <= y1_mm))
    points, valid = profile.points_laser.copy(), profile.valid.copy()
    anchor = cols[0] if valid[cols[0]] else cols[0] - 1
    y_a, z_a = points[anchor]
    z_a += dz_mm
    t = (z_a - slope * y_a) / (np.cos(phi[cols]) - slope * np.sin(phi[cols]))
    points[cols] = np.column_stack([t * np.sin(phi[cols]), t * np.cos(phi[cols])])
    valid[cols] = True
    return Profile(points, valid=valid, T_world_sensor=profile.T_world_sensor)


def _error(feature, truth):
    return float(np.hypot(*(feature.point_laser - truth.seam_laser)))


@pytest.mark.parametrize(("dz_mm", "slope"), [(2.0, 0.3), (-2.0, -0.5), (3.0, 0.0)])
def test_square_butt_edge_under_a_reflection_is_estimated_under_it(dz_mm, slope):
    """A stripe replaces the left plate's edge (-0.5 mm) and the first 0.2 mm of the gap: the
    edge lies somewhere under it; the extractor takes the middle, with halved confidence."""
    clean, truth = synthetic_profile("square-butt", SENSOR, roll_deg=5.0)
    sure = extractor("square-butt")(clean)
    feature = extractor("square-butt")(_with_stripe(clean, truth, -1.0, -0.3, dz_mm, slope))
    assert feature and _error(feature, truth) <= 0.2
    assert feature.confidence <= 0.5 * sure.confidence + 1e-9


@pytest.mark.parametrize("dz_mm", [2.0, -2.0])
def test_square_butt_plate_stub_beyond_a_reflection_stays_on_its_plate(dz_mm):
    """A stripe 0.5 mm before the left edge cuts a 0.5 mm stub off the plate: the stub is
    plate, so the edge stays exact (it was taken for a gap 1 mm too wide)."""
    clean, truth = synthetic_profile("square-butt", SENSOR, roll_deg=-5.0)
    profile = _with_stripe(clean, truth, -1.7, -1.0, dz_mm, 0.2)
    feature = extractor("square-butt")(profile)
    assert feature and _error(feature, truth) <= RESOLUTION_MM


@pytest.mark.parametrize(("dz_mm", "slope"), [(2.0, 0.3), (-2.0, 0.0), (4.0, -0.8)])
def test_flat_plate_with_a_stripe_is_no_square_butt(dz_mm, slope):
    clean, truth = synthetic_profile("flat", SENSOR, pitch_deg=10.0, roll_deg=-8.0)
    profile = _with_stripe(clean, truth, 0.5, 1.2, dz_mm, slope)
    assert not extractor("square-butt")(profile)


@pytest.mark.parametrize(("roll_deg", "pitch_deg"), [(-6.0, 4.0), (0.0, 0.0), (-12.0, 8.0)])
@pytest.mark.parametrize("covered", ["lower end", "top edge", "both"])
def test_lap_corner_under_a_reflection(covered, roll_deg, pitch_deg):
    """A 0.7 mm stripe over the lower sheet's end or the top sheet's edge: the intact side
    gives the seam; over both, the middle of the stripe does (within half its width)."""
    clean, truth = synthetic_profile("lap", SENSOR, roll_deg=roll_deg, pitch_deg=pitch_deg)
    seam, edge = truth.seam_laser[0], truth.edges_laser[0, 0]
    y0, y1 = {
        "lower end": (seam - 0.75, seam - 0.05),
        "top edge": (edge + 0.05, edge + 0.75),
        "both": (seam - 0.35, edge + 0.35),
    }[covered]
    sure = extractor("lap")(clean)
    feature = extractor("lap")(_with_stripe(clean, truth, y0, y1, 1.5, 0.3))
    assert feature and _error(feature, truth) <= (0.35 if covered == "both" else 0.02)
    assert feature.confidence <= 0.5 * sure.confidence + 1e-9


# ----------------------------------------------------------------- never raise
_values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.sampled_from([0.0, 1e300, -1e300, 91.0, 1e-300]),
)


@st.composite
def _profiles(draw):
    n = draw(st.integers(0, 300))
    kind = draw(
        st.sampled_from(
            ["random", "constant", "line", "nan", "huge", "1e6", "unsorted", "quantized", "spiky"]
        )
    )
    if kind == "random":
        pts = draw(arrays(np.float64, (n, 2), elements=_values))
    elif kind == "constant":
        pts = np.full((n, 2), draw(_values))
    elif kind in ("line", "unsorted", "quantized", "spiky"):
        y = np.linspace(-10, 10, n)
        pts = np.column_stack([y, 90 + draw(st.floats(-5, 5)) * np.abs(y)])
        if kind == "unsorted":  # columns in no order
            pts = pts[np.random.default_rng(draw(st.integers(0, 99))).permutation(n)]
        elif kind == "quantized":  # integer range units
            unit = draw(st.sampled_from([0.005, 0.05, 1.0]))
            pts[:, 1] = np.round(pts[:, 1] / unit) * unit
        elif kind == "spiky":  # every k-th point far off, behind or in front
            k = draw(st.integers(2, 20))
            pts[::k, 1] += draw(st.sampled_from([-30.0, 15.0, 1e5]))
    elif kind == "nan":
        pts = np.full((n, 2), np.nan)
    elif kind == "1e6":  # at the bound of what counts as a measurement
        pts = np.column_stack(
            [np.linspace(-1e6, 1e6, n), np.full(n, draw(st.sampled_from([1e6, 999999.0])))]
        )
    else:
        pts = np.column_stack([np.linspace(-1e200, 1e200, n), np.full(n, 1e250)])
    valid = draw(arrays(bool, (n,))) if draw(st.booleans()) else None
    return Profile(pts, valid=valid)


@settings(max_examples=60, deadline=None)
@given(profile=_profiles())
@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_extractors_never_raise(name, profile):
    feature = extractor(name)(profile)
    assert isinstance(feature, Feature)
    if not feature:
        assert feature.reason and feature.confidence == 0.0
    else:
        assert np.isfinite(feature.point_laser).all()


@settings(max_examples=60, deadline=None)
@given(profile=_profiles(), expect=st.sampled_from([None, {"angle_deg": 60.0, "gap_mm": 0.0}]))
def test_v_groove_with_expectations_never_raises(profile, expect):
    feature = extractor("v-groove", expect=expect)(profile)
    assert isinstance(feature, Feature)
    assert bool(feature) or feature.reason


@settings(max_examples=60, deadline=None)
@given(profile=_profiles())
def test_classify_and_reject_never_raise(profile):
    joint, confidence = classify(profile)
    assert joint in (*FAMILIES, "none") and 0.0 <= confidence <= 1.0
    cleaned = reject(profile)
    assert cleaned.points_laser.shape == profile.points_laser.shape
    assert (cleaned.valid <= profile.valid).all()  # only ever takes points out


@pytest.mark.parametrize("name", sorted(BUILTIN))
@pytest.mark.parametrize(
    "points",
    [np.empty((0, 2)), np.array([[0.0, 90.0]]), np.full((50, 2), np.nan), np.full((500, 2), 90.0)],
)
def test_degenerate_profiles_fail_with_a_reason(name, points):
    feature = extractor(name)(Profile(points))
    assert not feature and feature.reason


# ----------------------------------------------------------------- registry
class _Mine:
    name = "mine"

    def __init__(self, offset_mm: float = 0.0):
        self.offset_mm = offset_mm

    def __call__(self, profile: Profile) -> Feature:
        return Feature.found([self.offset_mm, 90.0])


@pytest.fixture
def user_module(monkeypatch):
    module = types.ModuleType("mypkg_st_test")
    module.MyExtractor = _Mine  # type: ignore[attr-defined]
    module.NotAnExtractor = object  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "mypkg_st_test", module)
    return module


def test_registry_builds_builtins_with_params():
    ex = extractor("v-groove", max_gap_mm=3.0)
    assert isinstance(ex, FeatureExtractor) and ex.name == "v-groove"


def test_registry_loads_a_user_class(user_module):
    ex = extractor("mypkg_st_test:MyExtractor", offset_mm=1.5)
    assert ex(Profile(np.empty((0, 2)))).point_laser[0] == 1.5


@pytest.mark.parametrize(
    ("name", "field"),
    [
        ("no-such-extractor", "extractor.name"),
        ("mypkg_st_test:Missing", "extractor.name"),
        ("no_such_pkg_xyz.mod:Cls", "extractor.name"),
        ("mypkg_st_test:NotAnExtractor", "extractor.name"),
    ],
)
def test_registry_bad_names_raise_plugin_error(user_module, name, field):
    with pytest.raises(PluginError) as info:
        extractor(name)
    assert info.value.field == field and info.value.fix


def test_registry_bad_params_raise_plugin_error():
    with pytest.raises(PluginError) as info:
        extractor("fillet", no_such_param=1)
    assert info.value.field == "extractor.params"


def test_features_has_one_line_point_and_corner_class() -> None:
    """One line geometry in features/ (issue 40): walking every module's syntax tree finds
    exactly one class named ``Line`` (its compiled form is ``LineThrough``, next to it), one
    ``Point`` and one ``Corner``."""
    root = Path(seamtrack.features.__file__).parent
    found: dict[str, list[str]] = {"Line": [], "Point": [], "Corner": []}
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ClassDef) and node.name in found:
                found[node.name].append(str(path.relative_to(root)))
    assert {name: len(where) for name, where in found.items()} == {
        "Line": 1,
        "Point": 1,
        "Corner": 1,
    }, found
