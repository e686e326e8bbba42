"""The scene's [arc] reaches image mode: the filter's keys, the arc at the torch's tip, no arc
without the section, bad input refused naming the field."""

import numpy as np
import pytest

from seamtrack.errors import SceneError
from seamtrack.simulation.assemble import arc_frame, scene_arc_light
from seamtrack.simulation.scene import load_scene, make_camera


def _light(name: str, overrides: dict | None = None):  # type: ignore[no-untyped-def]
    scene = load_scene(name, overrides or {})
    c = scene.config
    return scene_arc_light(scene, make_camera(c.sensor.camera, c.sensor.preset))


def test_no_arc_without_the_section_and_profile_model() -> None:
    assert _light("v-groove-camera") is None
    assert _light("v-groove-arc", {"arc.model": "profile"}) is None


def test_filter_defaults_to_the_laser_and_takes_the_keys() -> None:
    light = _light("v-groove-arc")
    assert light is not None and light.band.centre_nm == 660.0
    assert (light.process, light.current_a) == ("mag-spray", 250.0)
    light = _light("v-groove-arc", {"sensor.camera.wavelength_nm": 808.0,
                                    "sensor.camera.filter_shape": "top-hat",
                                    "sensor.camera.filter_fwhm_nm": 3.0})  # fmt: skip
    assert light is not None
    assert (light.band.centre_nm, light.band.fwhm_nm, light.band.shape) == (808.0, 3.0, "top-hat")


@pytest.mark.parametrize(
    ("key", "value"),
    [("sensor.camera.filter_fwhm_nm", 0.05), ("arc.current_a", -250.0)],
)
def test_bad_input_names_the_field(key: str, value: float) -> None:
    with pytest.raises(SceneError) as info:
        load_scene("v-groove-arc", {key: value})
    assert info.value.field == key, str(info.value)


def test_the_arc_sits_at_the_torch_tip() -> None:
    light = _light("v-groove-arc")
    T_tcp_sensor = np.eye(4)
    T_tcp_sensor[:3, 3] = [30.0, 0.0, 91.0]  # the sensor 30 mm ahead and 91 mm up the torch
    T_world_sensor = np.eye(4)
    T_world_sensor[:3, 3] = [100.0, 5.0, 91.0]
    frame = arc_frame(light, T_world_sensor, [np.linalg.inv(T_tcp_sensor)])
    np.testing.assert_allclose(frame.arc_mm, [70.0, 5.0, 0.0])
    np.testing.assert_allclose(frame.up, [0.0, 0.0, 1.0])  # towards the sensor's side


def test_a_frame_with_the_arc_is_seeded_and_adds_light() -> None:
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.robots import sensor_pose_at

    scene = load_scene("v-groove-arc", {"arc.process": "mag-short",
                                        "sensor.camera.exposure_mode": "fixed"})  # fmt: skip
    c = scene.config
    parts = build_parts(scene)
    camera = make_camera(c.sensor.camera, c.sensor.preset)
    light = scene_arc_light(scene, camera)
    T, _ = sensor_pose_at(parts.robot, parts.tool_program, 30.0)
    frame = arc_frame(light, T, [np.linalg.inv(parts.robot.T_tcp_sensor)])
    a, b = (parts.sensor.render(parts.mesh, T, camera=camera, seed=5, arc=frame, t_s=0.0)
            for _ in range(2))  # fmt: skip
    np.testing.assert_array_equal(a.pixels, b.pixels)
    dark = parts.sensor.render(parts.mesh, T, camera=camera, seed=5, t_s=0.0)
    assert a.pixels.sum() > dark.pixels.sum()  # the arc only adds light
