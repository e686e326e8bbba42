"""A run on a part that distorts while it is welded (``[distortion]``, issue 39)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

from seamtrack.cli.main import main
from seamtrack.simulation.loop import simulate
from seamtrack.simulation.scene import load_scene


def test_butt_distortion_is_tracked_where_the_taught_path_misses() -> None:
    # 80 mm of the shipped scene: the seam sinks as the weld locks its angle in.
    scene = load_scene("butt-distortion", {"workpiece.params.seam_length_mm": 80.0,
                                           "distortion.tacks": []})  # fmt: skip
    result = simulate(scene)
    s = result.summary
    tr = result.trace
    assert s["status"] == "completed"
    # the taught path errs by the seam's move at the torch; the tracker follows the moved seam
    assert s["untracked_max_error_mm"] > 0.5
    assert s["max_error_mm"] < 0.5 * s["untracked_max_error_mm"]
    assert s["max_seam_shift_mm"] >= s["untracked_max_error_mm"] - 1e-9
    assert len(tr.seam_shift_mm) == len(tr.t_s)
    # at the start the seam has not moved yet
    assert tr.seam_shift_mm[0] < 0.05
    assert np.all(np.isfinite(tr.error_mm))


def test_a_tack_outside_the_seam_is_one_line_exit_2(tmp_path) -> None:
    res = subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", "run", "butt-distortion", "--set",
         "distortion.tacks=[{position_mm = 500.0}]", "--out", str(tmp_path / "o")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert res.returncode == 2, res.stderr
    assert "distortion.tacks[0].position_mm" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_a_distortion_run_draws_the_seam_moving(tmp_path: Path) -> None:
    """``seamtrack run`` of a [distortion] scene writes distortion.png beside error.png, whose
    lines are the motion's own shifts (the snapshot at the run's end: the permanent angle
    locked in along the whole seam); a scene without [distortion] writes none."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.viz.distortion import seam_snapshots

    scene = load_scene("butt-distortion", {"workpiece.params.seam_length_mm": 40.0,
                                           "distortion.tacks": []})  # fmt: skip
    moving = build_parts(scene).moving
    length = moving.seam.length_mm
    end = length / scene.config.simulation.welding_speed_mm_s
    t, s, lateral, vertical = seam_snapshots(moving.motion, length, end)
    expect_lat, expect_ver = moving.motion.shift_mm(s, np.full_like(s, t[-1]))
    assert np.array_equal(vertical[-1], expect_ver) and np.array_equal(lateral[-1], expect_lat)
    assert t[0] == 0.0 and t[-1] == end and s[-1] == length
    short = ["--set", "workpiece.params.seam_length_mm=40", "--set", "distortion.tacks=[]"]
    for name, args, pictures in (("butt-distortion", short, {"error.png", "distortion.png"}),
                                 ("paper-verification", [], {"error.png"})):  # fmt: skip
        out = tmp_path / name
        assert main(["run", name, *args, "--out", str(out), "-q"]) == 0
        assert {p.name for p in out.glob("*.png")} == pictures


def test_a_pass_path_over_the_fill_s_end_sinks_with_the_plates_as_one_body() -> None:
    # A multi-pass job's pass path (the fill surface's reference point) turns up over the
    # fill's end; the plates turning about their pinned edges sink every point of the
    # section by the same vector, along the weld line's normal, not the path's local one.
    import dataclasses
    import math

    from seamtrack.geometry.seam import Seam
    from seamtrack.heat.materials import thermal_material
    from seamtrack.heat.motion import joint_motion
    from seamtrack.multipass.distortion import into_the_part
    from seamtrack.simulation.distorted import MovingSeam

    x = np.linspace(0.0, 100.0, 201)
    joint = Seam.from_points(np.column_stack([x, np.zeros_like(x), np.zeros_like(x)]))
    bump = 0.6 * np.clip((x - 98.5) / 1.0, 0.0, 1.0)  # 0.6 mm up over the last 1.5 mm
    path = Seam.from_points(np.column_stack([x, 3.8 + 0.2 * bump, 11.0 + bump]))
    still = joint_motion(
        power_w=0.0, speed_mm_s=5.0, material=thermal_material("carbon_steel"),
        thickness_mm=20.0, plate_width_mm=50.0, seam_length_mm=100.0,
        angle_peak_rad=math.radians(1.0), angle_peak_q_per_h2=20.0, fixed_plate="none",
    )  # fmt: skip
    motion = dataclasses.replace(still, prior_rad=math.radians(3.77))
    sink = np.array([0.0, 0.0, -50.0 * math.radians(3.77) / 2])
    t = np.zeros(len(x))
    moving = MovingSeam(path, motion, joint)
    d = moving.shift_world(moving.station_mm(path.points), t)
    np.testing.assert_allclose(d, np.broadcast_to(sink, d.shape), atol=1e-9)
    np.testing.assert_allclose(into_the_part(moving, path.points + sink, t), path.points,
                               atol=1e-9)  # fmt: skip
    # the path taken as its own weld line tilts the move where it turns up (0.8 mm along it)
    own = MovingSeam(path, motion)
    tilted = own.shift_world(path.arc_length_mm, t)
    assert np.max(np.abs(tilted[:, 0])) > 0.5
