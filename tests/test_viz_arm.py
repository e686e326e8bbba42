"""The articulated arm in the 3D views and the run animation: the drawn links end at the joint
origins of the maker's DH table, the torch at the TCP, and the views pose the arm (and the
sensor on it) where the kinematics and the run put them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from arm_oracles import UR10E_DH, dh

import seamtrack as st
from seamtrack.control.arm import ArticulatedRobot
from seamtrack.control.kinematics import ArmKinematics
from seamtrack.geometry import frames

pv = pytest.importorskip("pyvista")

from seamtrack.viz import arm as viz_arm  # noqa: E402  (after the skip: needs pyvista)
from seamtrack.viz import run as viz_run  # noqa: E402
from seamtrack.viz import views as viz  # noqa: E402

TOOL = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 300.0], [0, 0, 0, 1.0]])


#: A UR10e beside the paper's verification curve (seam mode), short.
ARM_SCENE = {
    "robot.model": "ur10e",
    "tracker.name": "trajectory",
    "robot.base_origin_mm": [200.0, -700.0, 0.0],
    "sensor.frame_rate_hz": 50.0,
    "simulation.welding_speed_mm_s": 10.0,
    "seam.length_mm": 30.0,
}


@pytest.fixture(autouse=True)
def _off_screen(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(pv, "OFF_SCREEN", True)


def _world(actor, point: np.ndarray) -> np.ndarray:
    return frames.apply(np.asarray(actor.user_matrix), point)


def test_drawn_ur10e_links_end_at_the_dh_joint_origins_and_the_torch_at_the_tcp() -> None:
    T_world_base = frames.from_xyz_rpy_deg([150.0, -700.0, -100.0], [0.0, 0.0, 90.0])
    robot = ArticulatedRobot(
        kinematics=ArmKinematics.named("ur10e", TOOL), T_world_base=T_world_base
    )
    rng = np.random.default_rng(11)
    plotter = pv.Plotter(off_screen=True)
    try:
        arm = viz_arm.ArmActors(plotter, robot, np.zeros(6))
        radius = viz_arm._size_mm(robot)
        for _ in range(5):
            q = rng.uniform(-math.pi, math.pi, 6)
            arm.move(q)
            # The DH frame origins 1..6: joint 2..6's origins, then the flange.
            T, origins = T_world_base.copy(), []
            for qi, (d, a, alpha) in zip(q, UR10E_DH, strict=True):
                T = T @ dh(qi, d, a, alpha)
                origins.append(T[:3, 3].copy())
            tcp = (T @ TOOL)[:3, 3]
            links = [k for k, kind in enumerate(arm.segments.kind) if kind == "link"]
            assert len(links) == 6
            for k, origin in zip(links, origins, strict=True):
                actor = plotter.actors[f"arm-link-{k}"]
                end = _world(actor, arm.segments.points[k][-1])
                assert np.linalg.norm(end - origin) <= 1e-9
                # The drawn tube (its vertices, placed by the actor) closes round that end.
                vertices = _world(actor, np.asarray(actor.mapper.dataset.points))
                assert np.min(np.linalg.norm(vertices - origin, axis=1)) <= radius
            k_torch = arm.segments.kind.index("torch")
            torch = plotter.actors["arm-torch"]
            tip = _world(torch, arm.segments.points[k_torch][-1])
            base = _world(torch, arm.segments.points[k_torch][0])
            assert np.linalg.norm(tip - tcp) <= 1e-9
            assert np.linalg.norm(base - origins[-1]) <= 1e-9
            flange = plotter.actors["arm-flange"]
            assert np.linalg.norm(flange.center - origins[-1]) <= 0.2 * radius
    finally:
        plotter.close()


def test_arm_scene_view_poses_the_arm_for_the_program_and_draws_it() -> None:
    view = viz.scene_view("paper-verification", overrides=ARM_SCENE)
    assert view.is_arm
    program = view.tool_program
    robot = view.robot
    s = 12.0
    tcp = view.tcp_at(s)
    joints = view.joints_at_tcp(tcp)
    T_tcp = robot.T_world_base @ robot.kinematics.fk(joints)
    assert np.linalg.norm(T_tcp[:3, 3] - tcp) <= 1e-6
    assert np.allclose(T_tcp[:3, :3], program.rotations([s])[0], atol=1e-9)
    assert np.allclose(view.pose_at_tcp(tcp), T_tcp @ robot.T_tcp_sensor, atol=1e-9)
    plotter = viz.scene_plotter(view, at_mm=s, off_screen=True, window_size=(400, 300))
    try:
        with_arm = np.asarray(plotter.screenshot(return_img=True), dtype=int)
        arm_actors = [a for name, a in plotter.actors.items() if name.startswith("arm-")]
        assert len(arm_actors) >= 6 + 6 + 3  # motors, links, base, flange, torch
        for actor in arm_actors:
            actor.visibility = False
        plotter.render()
        without = np.asarray(plotter.screenshot(return_img=True), dtype=int)
    finally:
        plotter.close()
    changed = np.any(with_arm != without, axis=2).mean()
    assert changed > 0.02  # the arm is in the picture, not beside it


def test_run_gif_poses_the_arm_at_the_runs_joints(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    scene = st.load_scene("paper-verification", overrides=ARM_SCENE)
    result = st.simulate(scene)
    assert result.summary["status"] == "completed"
    moved: list[np.ndarray] = []
    original = viz_arm.ArmActors.move

    def spy(self, q):  # type: ignore[no-untyped-def]
        moved.append(np.array(q))
        return original(self, q)

    monkeypatch.setattr(viz_arm.ArmActors, "move", spy)
    out = viz_run.animate_run(scene, result, tmp_path / "run.gif", frames=3, window_size=(320, 200))
    from PIL import Image

    with Image.open(out) as gif:
        assert gif.n_frames == 3
    ticks = viz_run._frame_ticks(result, 3)
    joints = result.trace.joints_rad
    # The last three poses are the frames' ticks, from the run's own joints.
    assert np.array_equal(np.array(moved[-3:]), joints[ticks])
    assert not np.allclose(joints[ticks[0]], joints[ticks[-1]])
