"""The command line: outputs, and one clear line with exit code 2 for every bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest
from cli_helpers import run_cli


def test_run_writes_the_outputs(tmp_path) -> None:
    out = tmp_path / "demo"
    res = run_cli("run", "--set", "seam.length_mm=40", "--out", str(out))
    assert res.returncode == 0, res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    for key in (
        "max_error_mm",
        "min_error_mm",
        "mean_error_mm",
        "rms_error_mm",
        "p95_error_mm",
        "sim_time_s",
        "wall_time_s",
        "frames",
        "frames_without_seam",
        "seam_length_mm",
        "completed_fraction",
        "mean_speed_mm_s",
        "seed",
    ):
        assert key in summary
    header = (out / "trace.csv").read_text().splitlines()[0]
    assert header.startswith(
        "t_s,tcp_x_mm,tcp_y_mm,tcp_z_mm,target_x_mm,target_y_mm,target_z_mm,error_mm"
    )
    assert (out / "error.png").stat().st_size > 10_000
    assert "max_error_mm" in res.stdout


def test_init_writes_a_scene_that_checks(tmp_path) -> None:
    target = tmp_path / "corner.toml"
    assert run_cli("init", "paper-corner", "-o", str(target)).returncode == 0
    assert target.read_text().startswith("#")
    res = run_cli("check", str(target))
    assert res.returncode == 0 and "valid" in res.stdout
    listing = run_cli("init", "--list").stdout
    assert "paper-verification" in listing and "paper-corner" in listing


def test_sensor_reproduces_table3() -> None:
    res = run_cli("sensor", "--preset", "paper", "--json")
    specs = json.loads(res.stdout)["specs"]
    assert specs["depth_of_field_mm"] == pytest.approx(60)
    assert specs["fov_near_mm"] == pytest.approx(18)
    assert specs["fov_far_mm"] == pytest.approx(32)


def test_sweep_prints_the_table(tmp_path) -> None:
    res = run_cli(
        "sweep",
        "paper-corner",
        "--param",
        "tracker.radius_mm",
        "--values",
        "5,0.1",
        "--set",
        "seam.points_mm=[[0,0,0],[30,0,0],[50,20,0]]",
        "--out",
        str(tmp_path),
    )
    assert res.returncode == 0, res.stderr
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("| ")]
    assert lines[0].startswith("| tracker.radius_mm | status | max_error_mm | min_error_mm")
    assert len(lines) == 3 and (tmp_path / "sweep.md").exists()


BAD = [
    (["run", "--set", "sensor.frame_rte_hz=2"], "sensor.frame_rte_hz", "frame_rate_hz"),
    (["run", "--set", "simulation.welding_speed_mm_s=fast"], "welding_speed_mm_s", "number"),
    (["run", "--set", "simulation.welding_speed_mm_s=-5"], "welding_speed_mm_s", "positive"),
    (["run", "--set", "robot.control_period_s=0"], "control_period_s", "positive"),
    (["run", "--set", "sensor.fov_far_mm=10"], "sensor.fov_far_mm", "swap"),
    (["run", "--set", "sensor.angle_deg=95"], "sensor.angle_deg", "(0, 90)"),
    (
        ["run", "--set", "seam.source='points'", "--set", "seam.points_mm=[[0,0,0]]"],
        "seam.points_mm",
        "at least",
    ),
    (
        [
            "run",
            "--set",
            "seam.source='points'",
            "--set",
            "seam.points_mm=[[0,0,0],[5,0,0],[5,0,0],[9,0,0]]",
        ],
        "seam.points_mm",
        "repeated",
    ),
    (["run", "--set", "seam.offset_mm=[500,0,0]"], "seam", "reach"),
    (["run", "--set", "tracker.name='nosuchpkg.mod:Tracker'"], "tracker.name", "PYTHONPATH"),
    (["run", "--set", "tracker.name='json:JSONDecoder'"], "tracker.name", "reset"),
    (["run", "nosuchscene"], "SCENE", "built-in scenes"),
]


@pytest.mark.parametrize("args, field, fix", BAD, ids=[b[1] + "-" + b[2] for b in BAD])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, args, field, fix) -> None:
    out = tmp_path / "out"
    res = run_cli(*args, "--out", str(out), cwd=tmp_path)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("seamtrack: error:") and field in lines[0] and fix in lines[0]
    assert "Traceback" not in res.stderr
    assert not out.exists() or not any(out.iterdir())


def test_nan_in_a_seam_file(tmp_path) -> None:
    (tmp_path / "seam.csv").write_text("x_mm,y_mm,z_mm\n0,0,0\n10,nan,0\n20,0,0\n")
    scene = tmp_path / "scene.toml"
    scene.write_text('[seam]\nsource = "csv"\nfile = "seam.csv"\n')
    res = run_cli("run", str(scene), "--out", str(tmp_path / "out"))
    assert res.returncode == 2
    assert "seam.file" in res.stderr and "not finite" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_several_bad_fields_are_all_reported(tmp_path) -> None:
    res = run_cli(
        "check", "paper-verification", "--set", "sensor.latency_s=-1", "--set", "robot.bogus=1"
    )
    assert res.returncode == 2
    text = res.stderr
    assert "sensor.latency_s" in text and "robot.bogus" in text
    assert len(text.strip().splitlines()) == 2


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write anywhere")
def test_unwritable_output_dir(tmp_path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    res = run_cli("run", "--out", str(locked / "x"))
    assert res.returncode == 2 and "--out" in res.stderr


def test_output_that_is_a_file_is_refused(tmp_path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = run_cli("run", "--set", "seam.length_mm=20", "--out", str(blocker / "sub"))
    assert res.returncode == 2 and "--out" in res.stderr and "Traceback" not in res.stderr


def test_user_tracker_from_the_scene(tmp_path) -> None:
    (tmp_path / "slow_tracker.py").write_text(
        textwrap.dedent("""
        from seamtrack.control.trackers import ConvergenceRadius

        class Half(ConvergenceRadius):
            def reset(self, context):
                super().reset(context)
                self.speed = 0.5 * context.welding_speed_mm_s
    """)
    )
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "seamtrack.cli",
            "run",
            "--set",
            "tracker.name='slow_tracker:Half'",
            "--set",
            "seam.length_mm=30",
            "--out",
            str(out),
            "--no-plot",
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["mean_speed_mm_s"] == pytest.approx(2.5, rel=0.02)


def test_default_outputs_land_under_runs(tmp_path) -> None:
    """A command given no --out writes under runs/ (git-ignored), never loose in the folder."""
    res = run_cli("scan", "paper-verification", "--at", "10", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs"]
    assert (tmp_path / "runs" / "scan-paper-verification-10mm.csv").is_file()
