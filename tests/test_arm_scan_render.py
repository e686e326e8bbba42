"""``seamtrack scan`` and ``render`` on the articulated-arm scenes: the sensor is posed as the arm
would place it at that arc length (its plan's joints, whose forward kinematics give the program's
tool pose), and the seam point found in the stripe lies on the true seam where the laser plane
crosses it, look_ahead_mm ahead of the torch."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import seamtrack as st
from seamtrack.cli.main import main
from seamtrack.sensing.profiles import laser_to_world
from seamtrack.sensing.scan import laser_plane_crossings
from seamtrack.sensing.sensor import preset
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.robots import plan_along, sensor_pose_at

pytestmark = [pytest.mark.slow, pytest.mark.cad, pytest.mark.embree]

ARM_SCENES = ("pipe-saddle", "pipe-on-plate", "v-groove-corner-arm")

#: A small chip for the render tests (the paper's 6000 x 2500 takes ~40 s a frame here).
SMALL_CHIP = (
    "--set", "sensor.camera.rows=1000", "--set", "sensor.camera.columns=400",
    "--set", "sensor.camera.supersample=1",
)  # fmt: skip


@pytest.fixture(scope="module", params=ARM_SCENES)
def arm(request: pytest.FixtureRequest) -> tuple[Any, Any]:
    scene = st.load_scene(request.param)
    return scene, build_parts(scene)


def _tolerance_mm(scene: Any, parts: Any) -> float:
    """Where the seam point may lie from the true seam: each wall's line is fitted to points
    within the mesh's chordal tolerance of the CAD surface, quantized at the sensor's lateral
    resolution; where the two lines meet, both errors can add for each line: twice their sum."""
    return 2.0 * (scene.config.workpiece.tolerance_mm + parts.sensor.lateral_resolution_mm)


@pytest.mark.parametrize("at_mm", [0.0, 10.0, 61.3])
def test_the_sensor_pose_is_the_arms_placement_of_the_tool_there(
    arm: tuple[Any, Any], at_mm: float
) -> None:
    _, parts = arm
    robot, program = parts.robot, parts.tool_program
    T_world_sensor, joints = sensor_pose_at(robot, program, at_mm)
    kin = robot.kinematics
    # The joints are inside their ranges, and their forward kinematics (an independent
    # product of the URDF's joint transforms) put the torch tip on the seam, turned as the
    # robot program says there.
    assert ((joints >= kin.lower_rad - 1e-9) & (joints <= kin.upper_rad + 1e-9)).all()
    T_world_tcp = robot.T_world_base @ kin.fk(joints)
    np.testing.assert_allclose(T_world_tcp[:3, 3], parts.seam.interpolate([at_mm])[0], atol=1e-3)
    np.testing.assert_allclose(T_world_tcp[:3, :3], program.rotations([at_mm])[0], atol=1e-6)
    np.testing.assert_allclose(T_world_sensor, T_world_tcp @ robot.T_tcp_sensor, atol=1e-6)
    # The same branch of the inverse kinematics as the run's plan of the whole seam (another
    # branch differs by tens of degrees in some joint).
    s_plan, plan = plan_along(robot, program)
    expected = np.array([np.interp(at_mm, s_plan, plan[:, k]) for k in range(kin.dof)])
    assert np.degrees(np.abs(joints - expected)).max() < 2.0
    if at_mm == 0.0:  # the run starts there (0.5 mm off the seam): nearly the same joints
        assert np.degrees(np.abs(joints - parts.start_joints)).max() < 1.0


def test_the_scan_finds_the_true_seam_where_the_laser_crosses_it(arm: tuple[Any, Any]) -> None:
    scene, parts = arm
    at_mm = 10.0
    T_world_sensor, _ = sensor_pose_at(parts.robot, parts.tool_program, at_mm)
    profile, feature = parts.scan(T_world_sensor, 0.0)
    assert profile.valid is not None and profile.valid.mean() > 0.9  # the stripe is on the part
    assert feature, feature.reason
    # The true seam's crossings with the laser plane (the CAD edge cut by the plane): the
    # found point lies on the one look_ahead_mm ahead of the torch.
    crossings = laser_plane_crossings(parts.seam, T_world_sensor)
    distance = np.linalg.norm(crossings - feature.point_laser, axis=1)
    nearest = int(np.argmin(distance))
    assert distance[nearest] <= _tolerance_mm(scene, parts)
    s_crossing = parts.seam.closest(laser_to_world(T_world_sensor, crossings[nearest])[None])
    look_ahead = scene.config.sensor.look_ahead_mm
    # Along a chord of the seam look_ahead_mm long: on the pipes (radius >= 50 mm) the arc is
    # at most 2 r asin(a / 2r) - a = 0.02 mm longer; the saddle's climb adds a little.
    assert s_crossing.arc_length_mm[0] - at_mm == pytest.approx(look_ahead, abs=0.2)


def _cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    code = main(args)
    out, err = capsys.readouterr()
    assert code == 0, err
    assert err == ""
    return out


def _distance_printed(out: str) -> float:
    found = re.search(r"seam point: .* ([0-9.]+) mm from the true seam", out)
    assert found, out
    return float(found.group(1))


def test_scan_on_the_command_line_pipe_saddle(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The issue's reproducer: ``seamtrack scan pipe-saddle --at 10``."""
    out = _cli(["scan", "pipe-saddle", "--at", "10", "--out", str(tmp_path / "s.csv")], capsys)
    assert _distance_printed(out) <= 2.0 * (0.01 + 0.01)  # the scene's mesh tolerance, sensor's
    valid = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, usecols=6)
    assert len(valid) == 1024 and valid.sum() > 900  # the stripe lies on the part
    assert (tmp_path / "s.png").is_file()


@pytest.mark.parametrize("name", ARM_SCENES)
def test_render_on_the_command_line(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The camera's seam point, measured from the image, within a pixel column's footprint on
    the laser plane (at the far end of the field) of the true seam."""
    png = tmp_path / "r.png"
    out = _cli(["render", name, "--at", "10", "--out", str(png), *SMALL_CHIP], capsys)
    assert png.is_file()
    column_mm = preset("paper").fov_far_mm / 400  # the arm scenes' sensor
    assert _distance_printed(out) <= column_mm
    assert "false stripe in 0 columns" in out
    assert not math.isnan(_distance_printed(out))


def test_check_on_an_arm_sees_the_seam_at_the_start(capsys: pytest.CaptureFixture[str]) -> None:
    out = _cli(["check", "v-groove-corner-arm"], capsys)
    assert re.search(r"seam seen at start\s+True", out), out
