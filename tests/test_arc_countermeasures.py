"""Countermeasures against the arc (issue 38): blob and streak rejection in the peak detector,
the seam-point gate in time, the tracker's behaviour on an invalid frame, and the one-word
switch that sets them together. Oracles: synthetic images whose stripe row is known, an
ideal render without the arc, and seam points on a known line."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.errors import SceneError
from seamtrack.sensing.peaks import Rejection, detect
from seamtrack.simulation.countermeasures import rejection
from seamtrack.simulation.scene import load_scene

# ----------------------------------------------------------------------------- rejection
ROWS, COLUMNS = 128, 64
STRIPE_SIGMA_PX = 1.2


def _stripe_image(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A Gaussian stripe (sigma 1.2 px, peak 0.3) on a dark, noisy background; its true row in
    each column."""
    rng = np.random.default_rng(seed)
    columns = np.arange(COLUMNS)
    truth = 60.0 + 0.1 * columns + 0.3 * np.sin(columns / 7.0)
    rows = np.arange(ROWS)[:, None]
    image = 0.3 * np.exp(-0.5 * ((rows - truth[None, :]) / STRIPE_SIGMA_PX) ** 2)
    image += 0.01 + 0.002 * rng.standard_normal(image.shape)
    return image.astype(np.float32), truth


def test_a_wide_blob_and_a_saturated_streak_are_rejected_the_stripe_kept() -> None:
    image, truth = _stripe_image()
    rows = np.arange(ROWS)[:, None]
    blob = slice(20, 28)  # the arc's glow or a blob: 7 times the stripe's width, brighter
    image[:, blob] += 0.5 * np.exp(-0.5 * ((rows - 100.0) / (7 * STRIPE_SIGMA_PX)) ** 2)
    streak = slice(40, 43)  # a spatter streak running along the columns, saturated
    image[8:24, streak] = 1.0
    plain = detect(image, threshold=0.05)
    assert np.all(np.abs(plain[blob] - 100.0) < 2)  # without rejection: the blob is chosen
    assert np.all(np.abs(plain[streak] - 15.5) < 1)  # and the streak
    kept = detect(image, threshold=0.05, reject=Rejection())
    np.testing.assert_allclose(kept, truth, atol=0.15)  # the stripe in every column


def test_a_narrow_run_far_brighter_than_the_stripe_is_rejected() -> None:
    image, truth = _stripe_image(1)
    image *= 0.1  # a dim stripe (peak 0.03) ...
    image[30:33, 10] = 1.0  # ... and a droplet seen head-on, 3 px, 30 times brighter
    assert abs(detect(image, threshold=0.01)[10] - 31.0) < 0.5
    rows = detect(image, threshold=0.01, reject=Rejection())
    assert abs(rows[10] - truth[10]) < 0.2
    kept = detect(image, threshold=0.01, reject=Rejection(max_peak=100.0))  # a looser bound
    assert abs(kept[10] - 31.0) < 0.5


def test_a_given_stripe_width_sets_the_bound() -> None:
    image, truth = _stripe_image(2)
    sigma_sqrt_2pi = STRIPE_SIGMA_PX * np.sqrt(2 * np.pi)  # the Gaussian's equivalent width
    rows = detect(image, threshold=0.05, reject=Rejection(stripe_width_px=sigma_sqrt_2pi))
    np.testing.assert_allclose(rows, truth, atol=0.15)
    # A stripe width half the true one over a factor of 1.5: the stripe itself is too wide.
    narrow = Rejection(max_width=1.5, stripe_width_px=0.5 * sigma_sqrt_2pi)
    assert np.isnan(detect(image, threshold=0.05, reject=narrow)).all()


@pytest.mark.embree
@pytest.mark.parametrize(("roll_deg", "method"), [(0.0, "centroid"), (25.0, "gaussian")])
def test_an_ideal_render_without_the_arc_gives_the_same_rows(roll_deg: float, method: str) -> None:
    from seamtrack.bench.camera import plate
    from seamtrack.geometry import frames
    from seamtrack.sensing.camera import Camera
    from seamtrack.sensing.sensor import preset

    sensor = preset("paper")
    T_down = frames.from_xyz_rpy_deg([0.0, 0.0, sensor.range_center_mm], [180.0, 0.0, 0.0])
    image = sensor.render(plate(roll_deg, 0.0), T_down,
                          camera=Camera.ideal(rows=256, columns=512), seed=0)  # fmt: skip
    plain = detect(image.pixels, method=method)
    assert np.isfinite(plain).mean() > 0.9
    np.testing.assert_array_equal(detect(image.pixels, method=method, reject=Rejection()), plain)


def test_the_scene_keys_reach_the_detector() -> None:
    assert rejection(load_scene("v-groove-camera").config) is None
    on = rejection(load_scene("v-groove-camera", {"sensor.camera.reject": "blobs"}).config)
    assert on == Rejection()
    tight = load_scene("v-groove-camera", {"sensor.camera.reject": "blobs",
                                           "sensor.camera.reject_max_width": 2.0,
                                           "sensor.camera.reject_min_peak": 0.2})  # fmt: skip
    assert rejection(tight.config) == Rejection(max_width=2.0, min_peak=0.2)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("sensor.camera.reject", "all"),
        ("sensor.camera.reject_max_width", 0.5),
        ("sensor.camera.reject_max_peak", -3.0),
        ("sensor.camera.reject_min_peak", 1.5),
        ("sensor.camera.reject_stripe_width_px", 0.0),
        ("sensor.camera.laser_power_w", -0.1),
        ("sensor.camera.laser_power_w", 50.0),
    ],
)
def test_bad_rejection_keys_name_the_field(key: str, value: object) -> None:
    with pytest.raises(SceneError) as info:
        load_scene("v-groove-camera", {key: value})
    assert info.value.field == key, str(info.value)
    assert info.value.fix


@pytest.mark.embree
def test_twice_the_laser_power_halves_the_arcs_light_against_the_stripe() -> None:
    """The stripe keeps its level (``exposure``), so the arc's electrons fall as 1 / power
    (an ideal camera: no noise, no quantization)."""
    import dataclasses

    from seamtrack.simulation.assemble import arc_frame, build_parts, scene_arc_light
    from seamtrack.simulation.robots import sensor_pose_at
    from seamtrack.simulation.scene import make_camera

    scene = load_scene("v-groove-arc", {"sensor.camera.exposure_mode": "fixed",
                                        "sensor.camera.ideal": True,
                                        "sensor.camera.bit_depth": 0,
                                        "sensor.camera.laser_power_w": 0.2})  # fmt: skip
    c = scene.config
    camera = make_camera(c.sensor.camera, c.sensor.preset)
    light = scene_arc_light(scene, camera)
    assert light is not None and light.laser_power_w == 0.2
    parts = build_parts(scene)
    T, _ = sensor_pose_at(parts.robot, parts.tool_program, 20.0)
    to_tcp = [np.linalg.inv(parts.robot.T_tcp_sensor)]

    def pixels(arc_light: object) -> np.ndarray:
        extra = {} if arc_light is None else {"arc": arc_frame(arc_light, T, to_tcp)}
        image = parts.sensor.render(parts.mesh, T, camera=camera, seed=5, t_s=0.0, **extra)
        return image.pixels.astype(np.float64)

    dark = pixels(None)
    weak, strong = pixels(light), pixels(dataclasses.replace(light, laser_power_w=0.4))
    # Over the pixels the arc lights at both powers (the renderer leaves out light below 1e-4
    # of the full well, so the dimmer image lights fewer), unsaturated.
    lit = (weak < 0.95) & (strong < 0.95) & (strong > dark)
    assert lit.sum() > 1000
    ratio = (weak - dark)[lit].sum() / (strong - dark)[lit].sum()
    assert ratio == pytest.approx(2.0, rel=1e-3)


# ----------------------------------------------------------------------------- the gate
def _pose(x_mm: float) -> np.ndarray:
    """The laser pointing down from 100 mm above (x_mm, 0, 0): its plane x_L = 0 is X = x_mm
    (x_L = X, y_L = -Y, z_L = -Z + 100)."""
    from seamtrack.geometry import frames

    return frames.from_xyz_rpy_deg([x_mm, 0.0, 100.0], [180.0, 0.0, 0.0])


def _frame(x_mm: float, y_mm: float) -> tuple:  # type: ignore[type-arg]
    """A frame whose seam point is (x_mm, y_mm, 0), and its pose."""
    from seamtrack.sensing.profiles import Feature

    T = _pose(x_mm)
    return Feature.found([-y_mm, 100.0], T, joint="v-groove"), T


def test_the_prediction_is_where_the_line_crosses_the_laser_plane() -> None:
    from seamtrack.control.gate import predict_point

    # Points on the line (s, 1 + 0.1 s, 0.2 s); the plane X = 7 crosses it at s = 7.
    history = np.array([[s, 1 + 0.1 * s, 0.2 * s] for s in (2.0, 3.0, 4.0)])
    np.testing.assert_allclose(predict_point(history, _pose(7.0)), [7.0, 1.7, 1.4], atol=1e-12)
    np.testing.assert_allclose(predict_point(history[-1:], _pose(7.0)), history[-1])


@pytest.mark.parametrize("on_invalid", ["hold", "predict"])
def test_a_false_point_outside_the_window_is_refused(on_invalid: str) -> None:
    from seamtrack.control.gate import OUTSIDE, GateSettings, SeamGate

    gate = SeamGate(GateSettings(window_mm=15.0, reacquire_frames=20, on_invalid=on_invalid))
    for k in range(10):  # a straight seam y = 2 + 0.05 x, a frame every 0.4 mm
        feature, T = _frame(0.4 * k, 2 + 0.02 * k)
        assert gate(feature, T) is feature
    spatter, T = _frame(4.0, 30.0)  # a streak 28 mm off the seam
    out = gate(spatter, T)
    assert gate.refused == 1
    if on_invalid == "hold":
        assert not out and out.reason == OUTSIDE
    else:  # the predicted point: on the seam's line, in this frame's plane
        assert out and out.confidence == 0.0
        np.testing.assert_allclose(out.point_world, [4.0, 2.2, 0.0], atol=1e-9)
    near, T = _frame(4.4, 2.22 + 10.0)  # 10 mm off: inside the window, taken
    assert gate(near, T) is near


def test_a_point_without_a_pose_passes_uncounted() -> None:
    from seamtrack.control.gate import GateSettings, SeamGate
    from seamtrack.sensing.profiles import Feature

    gate = SeamGate(GateSettings())
    gate(*_frame(0.0, 0.0))
    bare = Feature.found([50.0, 100.0])  # no pose, no world point
    assert gate(bare, _pose(0.4)) is bare
    assert (gate.accepted, gate.refused, gate.invalid_run) == (1, 0, 0)


def test_after_n_invalid_frames_the_gate_reacquires() -> None:
    from seamtrack.control.gate import GateSettings, SeamGate

    gate = SeamGate(GateSettings(window_mm=15.0, reacquire_frames=20, on_invalid="hold"))
    for k in range(5):
        gate(*_frame(0.4 * k, 0.0))
    # The seam steps 25 mm sideways (the gate was on a wrong track, or the part moved).
    results = [gate(*_frame(0.4 * k, 25.0)) for k in range(5, 30)]
    assert [bool(r) for r in results] == [False] * 20 + [True] * 5
    assert (gate.refused, gate.reacquired) == (20, 1)


def test_frames_without_a_point_pass_and_count_towards_reacquisition() -> None:
    from seamtrack.control.gate import GateSettings, SeamGate
    from seamtrack.sensing.profiles import Feature

    gate = SeamGate(GateSettings(window_mm=15.0, reacquire_frames=3, on_invalid="predict"))
    for k in range(5):
        gate(*_frame(0.4 * k, 1.0))
    # Frames without a seam point reach the tracker as they are (its own bridge, or the seam's
    # end), whether the stripe left the part or not; they count as invalid.
    off_part = dataclasses_replace(Feature.failed("no stripe"), stripe_points=0)
    assert gate(off_part, _pose(2.0)) is off_part
    lost = Feature.failed("no groove")
    assert gate(lost, _pose(2.4)) is lost
    spatter, T = _frame(2.8, 40.0)  # refused: the third invalid frame, predicted
    predicted = gate(spatter, T)
    assert predicted and gate.predicted == 1
    np.testing.assert_allclose(predicted.point_world, [2.8, 1.0, 0.0], atol=1e-9)
    moved, T = _frame(3.2, 40.0)  # after 3 invalid frames the next point found is taken
    assert gate(moved, T) is moved and gate.reacquired == 1
    assert gate(*_frame(3.6, 40.0)) and gate.refused == 1


def test_a_prediction_far_from_the_last_point_is_not_handed_on() -> None:
    from seamtrack.control.gate import GateSettings, SeamGate

    gate = SeamGate(GateSettings(window_mm=15.0, reacquire_frames=20, on_invalid="predict"))
    gate(*_frame(0.0, 0.0))
    gate(*_frame(0.4, 0.0))
    # A frame 30 mm further on: the line's crossing is 29.6 mm from the last point.
    assert not gate(*_frame(30.0, 20.0)) and gate.refused == 1 and gate.predicted == 0


def dataclasses_replace(feature, **changes):  # type: ignore[no-untyped-def]
    import dataclasses

    return dataclasses.replace(feature, **changes)


# ----------------------------------------------------------------------------- the switch
def test_the_switch_sets_the_countermeasures_and_explicit_keys_win() -> None:
    from seamtrack.control.gate import GateSettings
    from seamtrack.simulation.countermeasures import countermeasures, gate_settings

    plain = load_scene("v-groove-camera").config  # no arc: everything off, as before
    assert countermeasures(plain) == "none"
    assert (rejection(plain), gate_settings(plain)) == (None, None)
    arc = load_scene("v-groove-arc").config  # the arc on: the defaults
    assert countermeasures(arc) == "default"
    assert rejection(arc) == Rejection()
    assert gate_settings(arc) == GateSettings(15.0, 20, "predict")
    off = load_scene("v-groove-arc", {"countermeasures": "none"}).config
    assert (rejection(off), gate_settings(off)) == (None, None)
    mixed = load_scene("v-groove-arc", {"countermeasures": "none", "gate.on_invalid": "predict",
                                        "gate.window_mm": 5.0})  # fmt: skip
    assert rejection(mixed.config) is None
    assert gate_settings(mixed.config) == GateSettings(5.0, 20, "predict")
    no_gate = load_scene("v-groove-arc", {"gate.enabled": False,
                                          "sensor.camera.reject": "none"})  # fmt: skip
    assert (rejection(no_gate.config), gate_settings(no_gate.config)) == (None, None)
    on = load_scene("paper-verification", {"countermeasures": "default"}).config
    assert gate_settings(on) == GateSettings(15.0, 20, "predict")


def test_the_switch_sets_the_sensors_filter_and_exposure() -> None:
    """Under "default" a 10 nm Gaussian band-pass on the laser's line and one fixed exposure;
    under "none" the chip's own band (400-1100 nm: silicon's band gap at 1.12 eV cuts it at
    1,107 nm) and the camera's multiple exposure; explicit keys win; a scene without the arc
    keeps the camera it had."""
    from seamtrack.simulation.countermeasures import band_pass, exposure_mode
    from seamtrack.simulation.scene import scene_camera

    arc = load_scene("v-groove-arc").config
    band = band_pass(arc, 660.0)
    assert (band.centre_nm, band.fwhm_nm, band.shape) == (660.0, 10.0, "gaussian")
    assert band.transmission(660.0 + 5.0) == pytest.approx(0.5 * band.peak)  # half maximum
    assert exposure_mode(arc) == "fixed" == scene_camera(arc).exposure_mode
    off = load_scene("v-groove-arc", {"countermeasures": "none"}).config
    bare = band_pass(off, 660.0)
    assert bare.transmission([401.0, 660.0, 1099.0]).tolist() == [1.0, 1.0, 1.0]
    assert bare.transmission([399.0, 1101.0]).tolist() == [0.0, 0.0]
    assert bare.equivalent_width_nm == pytest.approx(700.0)
    assert exposure_mode(off) == "multi"
    given = load_scene("v-groove-arc", {"countermeasures": "none",
                                        "sensor.camera.filter_fwhm_nm": 3.0,
                                        "sensor.camera.exposure_mode": "auto"}).config  # fmt: skip
    assert (band_pass(given, 660.0).fwhm_nm, exposure_mode(given)) == (3.0, "auto")
    plain = load_scene("v-groove-camera").config
    assert scene_camera(plain).exposure_mode == "multi"


@pytest.mark.embree
def test_without_the_filter_the_arc_outshines_the_stripe_at_30_mm() -> None:
    """250 A, 30 mm ahead: behind the 10 nm band-pass the stripe wins nearly every column;
    with no filter the arc's light (its continuum over 700 nm of band, and argon's
    near-infrared lines) takes a quarter of them and more. The oracle: the same frame without
    the arc, on an ideal camera."""
    from seamtrack.bench.arc import without_arc
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.robots import sensor_pose_at

    short = {"workpiece.params.seam_length_mm": 40.0}
    ideal = build_parts(
        without_arc(load_scene("v-groove-arc", {**short, "sensor.camera.ideal": True}))
    )
    T, _ = sensor_pose_at(ideal.robot, ideal.tool_program, 5.0)
    truth, _ = ideal.scan(T, 0.2, None)

    def on_the_stripe(switch: str) -> float:
        parts = build_parts(load_scene("v-groove-arc", {**short, "countermeasures": switch}))
        profile, _ = parts.scan(T, 0.2, None)
        dz = np.abs(profile.points_laser[:, 1] - truth.points_laser[:, 1])
        return float(np.mean((profile.valid & (dz < 0.5))[truth.valid]))

    assert on_the_stripe("default") > 0.9
    assert on_the_stripe("none") < 0.75  # a quarter of the columns and more are the arc's


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("countermeasures", "all"),
        ("gate.window_mm", -1.0),
        ("gate.reacquire_frames", 0),
        ("gate.on_invalid", "guess"),
        ("gate.enabled", "yes"),
    ],
)
def test_bad_gate_keys_name_the_field(key: str, value: object) -> None:
    with pytest.raises(SceneError) as info:
        load_scene("v-groove-arc", {key: value})
    assert info.value.field == key, str(info.value)
    assert info.value.fix


def test_a_bad_key_on_the_command_line_is_one_line_and_exit_2() -> None:
    import subprocess
    import sys

    res = subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", "check", "v-groove-arc-mag", "--set",
         "gate.window_mm=-1"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "gate.window_mm" in lines[0] and "fix:" in lines[0], lines


def test_a_gate_that_refuses_nothing_leaves_the_run_unchanged() -> None:
    """A window wider than any step and ``hold``: the same trace as no gate at all."""
    from seamtrack.simulation.loop import simulate

    short = {"seam.length_mm": 40.0}
    plain = simulate(load_scene("paper-verification", short))
    gated = simulate(load_scene("paper-verification", {**short, "gate.window_mm": 1000.0}))
    np.testing.assert_array_equal(plain.trace.tcp_world, gated.trace.tcp_world)
    np.testing.assert_array_equal(
        plain.trace.frames["point_world"], gated.trace.frames["point_world"]
    )
    assert len(plain.trace.t_s) > 100


# ----------------------------------------------------------------------------- the MAG scene
@pytest.mark.embree
def test_the_mag_scene_tracks_within_0_3_mm_with_the_countermeasures() -> None:
    """v-groove-arc-mag (MAG short-circuit, 250 A, spatter; the seam 2 deg off the robot's
    axis) on a 40 mm seam: the issue's goal for the shipped arc scenes, a closed-loop max
    error of 0.3 mm with the default countermeasures."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.countermeasures import countermeasures
    from seamtrack.simulation.loop import run

    scene = load_scene("v-groove-arc-mag", {"workpiece.params.seam_length_mm": 40.0})
    assert countermeasures(scene.config) == "default"
    assert scene.config.arc is not None and scene.config.arc.current_a == 250.0
    parts = build_parts(scene)
    assert parts.settings.gate is not None
    s = run(parts, seed=scene.config.simulation.seed).summary
    assert s["status"] == "completed", s
    assert s["max_error_mm"] <= 0.3
    # Every frame the gate saw is counted once: accepted, or invalid (refused or without a
    # point), and a prediction only for an invalid one.
    assert s["gate_accepted"] > 0
    assert s["gate_accepted"] + s["gate_predicted"] <= s["frames"]
    assert s["gate_refused"] + s["gate_accepted"] <= s["frames"]


def test_check_says_what_the_switch_resolved_to() -> None:
    from seamtrack.simulation.countermeasures import describe

    assert describe(load_scene("paper-verification").config) == "none: off"
    text = describe(load_scene("v-groove-arc-mag").config)
    assert text.startswith("default: reject blobs") and "gate 15 mm" in text
    assert "re-acquire after 20 frames, predict" in text
