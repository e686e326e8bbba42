"""Issue 43, items 16, 18, 19, 20 and 24 (in part): units, labels and values that completed a
wrong run or were blamed on the wrong field; sweeps that started processes without bound or
waited forever; a full disk; and the small slips of check, the summary, frames.csv and
sweep.png. (Each bad input is also an entry of the catalogue: seamtrack.bench.
failure_inputs_units, run by tests/test_failures.py.)"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from seamtrack.bench import real_input
from seamtrack.bench.extractors import load_real_set
from seamtrack.cli.main import main
from seamtrack.cli.tables import _fmt
from seamtrack.errors import SceneError, SeamtrackError
from seamtrack.geometry.seam import Seam
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.scene import load_scene

PAPER = "paper-verification"


# --------------------------------------------------------------------------- item 16: units
def _seam_csv(path: Path, scale: float) -> np.ndarray:
    """A 300 mm seam with a 2 mm sine across it, written at ``scale`` (1e-3: in metres)."""
    x = np.linspace(0.0, 300.0, 151)
    pts = np.column_stack([x, 2.0 * np.sin(x / 30.0), np.zeros_like(x)])
    body = "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in (scale * pts).tolist())
    path.write_text("x_mm,y_mm,z_mm\n" + body)
    return pts


def test_a_seam_csv_in_metres_is_named_with_its_length_in_mm(tmp_path: Path) -> None:
    pts = _seam_csv(tmp_path / "m.csv", 1e-3)
    length_mm = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())  # independent
    scene = load_scene(PAPER, {"seam.source": "csv", "seam.file": str(tmp_path / "m.csv")})
    with pytest.raises(SceneError) as info:
        build_parts(scene)
    text = str(info.value)
    assert info.value.field == "seam.file" and "looks like metres" in text
    assert f"x1000: {length_mm:.4g} mm" in text
    # The same seam in mm builds, and its length is the one the message gave.
    _seam_csv(tmp_path / "mm.csv", 1.0)
    ok = build_parts(
        load_scene(PAPER, {"seam.source": "csv", "seam.file": str(tmp_path / "mm.csv")})
    )
    assert ok.seam.length_mm == pytest.approx(length_mm, rel=1e-9)


def test_a_seam_shorter_than_the_look_ahead_but_not_metres_says_so(tmp_path: Path) -> None:
    """0.005 mm x 1000 is still shorter than 10 mm: not metres, just too short."""
    tiny = [[0, 0, 0], [0.002, 0, 0], [0.005, 0, 0]]
    scene = load_scene(PAPER, {"seam.source": "points", "seam.points_mm": tiny})
    with pytest.raises(SceneError) as info:
        build_parts(scene)
    assert info.value.field == "seam.points_mm" and "metres" not in str(info.value)
    assert "look-ahead" in str(info.value)


def _write_set(d: Path, z: np.ndarray, labels: list[str] | None, y: np.ndarray | None = None,
               joint: str = "v-groove") -> Path:  # fmt: skip
    d.mkdir(parents=True)
    (d / "set.json").write_text(json.dumps({"joint": joint}))
    width = z.shape[1]
    np.savez_compressed(d / "profiles.npz", y_mm=np.linspace(-10, 10, width) if y is None else y,
                        z_mm=z)  # fmt: skip
    if labels is not None:
        rows = "".join(f"{i},{row}\n" for i, row in enumerate(labels))
        (d / "labels.csv").write_text("index,y_mm,z_mm\n" + rows)
    return d


def _v(n: int = 3, scale: float = 1.0) -> np.ndarray:
    y = np.linspace(-10.0, 10.0, 201)
    return np.tile(scale * (110.0 - np.minimum(np.abs(y), 10.0)), (n, 1))


def test_a_real_set_in_mm_loads_with_its_labels(tmp_path: Path) -> None:
    rs = load_real_set(_write_set(tmp_path / "ok", _v(), ["0.0,110.0", "0.5,109.5", "-1,109"]))
    assert rs.labels is not None
    np.testing.assert_array_equal(rs.labels, [[0.0, 110.0], [0.5, 109.5], [-1.0, 109.0]])
    assert len(rs.profiles) == 3


@pytest.mark.parametrize(
    ("what", "z", "labels", "y", "needle"),
    [
        ("metres", _v(scale=1e-3), ["0,0.11"] * 3, 1e-3 * np.linspace(-10, 10, 201),
         "looks like metres"),
        ("labels in metres", _v(), ["0,0.11"] * 3, None, "labels look like metres"),
        ("text label", _v(), ["0,110", "seam,here", "0,110"], None, "line 3"),
        ("NaN label", _v(), ["0,110", "nan,nan", "0,110"], None, "line 3"),
        ("inf label", _v(), ["0,110", "0,inf", "0,110"], None, "not finite"),
        ("all NaN", np.full((3, 201), np.nan), ["0,110"] * 3, None, "NaN or inf"),
        ("no profile", np.zeros((0, 201)), [], None, "0 profiles"),
    ],
)  # fmt: skip
def test_a_real_set_that_would_be_miscounted_is_refused(tmp_path, what, z, labels, y, needle):
    with pytest.raises(SeamtrackError) as info:
        load_real_set(_write_set(tmp_path / "s", z, labels, y))
    assert info.value.field == "--real" and needle in str(info.value), str(info.value)


def test_an_npz_too_large_once_loaded_is_refused_from_its_headers(tmp_path, monkeypatch) -> None:
    """0.5 MB on disk, 4.1e7 values: refused from the .npy header, before numpy loads a byte
    (numpy.load is made to fail: it is never reached)."""
    d = _write_set(tmp_path / "bomb", np.full((20_000, 2048), np.nan), None, joint="none")
    assert (d / "profiles.npz").stat().st_size < 1_000_000
    import seamtrack.bench.extractors as ex

    def never(*args, **kwargs):
        raise AssertionError("numpy.load reached")

    monkeypatch.setattr(ex.np, "load", never)
    with pytest.raises(SeamtrackError) as info:
        load_real_set(d)
    assert f"{20_000 * 2048:.3g} values (20000, 2048)" in str(info.value)
    assert 20_000 * 2048 > real_input.MAX_REAL_POINTS


# --------------------------------------------------------------------------- item 18: sweeps
def test_workers_are_capped_at_the_cpus_this_process_may_use() -> None:
    from seamtrack.batch.sweep import usable_workers

    cpus = len(os.sched_getaffinity(0))
    workers, note = usable_workers(100_000, 1_000)
    assert 1 <= workers <= cpus
    assert note.startswith("--workers 100000 capped at") and str(workers) in note
    assert usable_workers(1, 1_000) == (1, "")
    assert usable_workers(100_000, 1)[0] == 1  # never more than the cases


@pytest.fixture
def stranger() -> Iterator[tuple[int, int]]:
    """Two loopback servers that are not Dask: one accepts and says nothing, one answers
    HTTP. Yields their ports."""
    servers, conns, stop = [], [], threading.Event()
    for reply in (b"", b"HTTP/1.0 200 OK\r\nContent-Length: 2\r\n\r\nhi"):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        s.listen(4)
        s.settimeout(0.2)
        servers.append((s, reply))

    def serve() -> None:
        while not stop.is_set():
            for s, reply in servers:
                try:
                    c, _ = s.accept()
                except OSError:
                    continue
                conns.append(c)
                if reply:
                    c.sendall(reply)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield servers[0][0].getsockname()[1], servers[1][0].getsockname()[1]
    stop.set()
    thread.join()
    for c in conns:
        c.close()
    for s, _ in servers:
        s.close()


def test_a_scheduler_address_where_no_dask_listens_ends_in_one_line(
    stranger, monkeypatch, capsys, tmp_path
) -> None:
    pytest.importorskip("dask.distributed")
    from seamtrack.batch import sweep

    monkeypatch.setattr(sweep, "DASK_CONNECT_TIMEOUT_S", 1.0)
    silent, http = stranger
    for address, needle in (
        (f"tcp://127.0.0.1:{silent}", "answered nothing"),
        (f"tcp://127.0.0.1:{http}", "not a Dask scheduler"),
        ("not a url", "not a scheduler address"),
        ("tcp://127.0.0.1:99999", "port 99999"),
    ):
        out = tmp_path / "sweep"
        code = main(["sweep", "paper-corner", "--param", "tracker.radius_mm", "--values", "1",
                     "--scheduler", address, "--out", str(out)])  # fmt: skip
        err = capsys.readouterr().err
        assert code == 2, err
        assert err.count("\n") == 1 and err.startswith("seamtrack: error: --scheduler: "), err
        assert needle in err and "Traceback" not in err
        assert not out.exists()


# --------------------------------------------------------------------------- item 19
@pytest.mark.parametrize(
    ("scene", "key", "value", "field"),
    [
        ("pipe-on-plate", "workpiece.tolerance_mm", 1e308, "workpiece.tolerance_mm"),
        (PAPER, "seam.rotation_deg", [1e308, 0.0, 0.0], "seam.rotation_deg.0"),
        (PAPER, "simulation.welding_speed_mm_s", 1e6, "simulation.welding_speed_mm_s"),
        (PAPER, "robot.velocity_max_mm_s", [1e7, 10.0, 10.0], "robot.velocity_max_mm_s.0"),
        (PAPER, "sensor.mount_rotation_deg", [0.0, 0.0, 1e308], "sensor.mount_rotation_deg.2"),
    ],
)
def test_values_that_completed_a_wrong_run_are_refused(scene, key, value, field) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(scene, {key: value})
    assert info.value.field == field


def test_the_bounds_keep_what_is_physical() -> None:
    """A turn, the 1 mm tolerance and a laser-weld speed with raised axis limits load."""
    load_scene(PAPER, {"seam.rotation_deg": [360.0, -360.0, 0.0]})
    load_scene("pipe-on-plate", {"workpiece.tolerance_mm": 1.0})
    load_scene(PAPER, {"robot.velocity_max_mm_s": [1e3, 1e3, 1e3],
                       "robot.position_max_mm": [800.0, 150.0, 150.0],
                       "simulation.welding_speed_mm_s": 150.0})  # fmt: skip


def test_check_says_the_seam_is_never_in_view(capsys) -> None:
    """The paper sensor measures 46-106 mm from its emitter: at 300 mm the seam is out of its
    depth of field from every pose; at its own range it is seen from most of them."""
    code = main(["check", PAPER, "--set", "sensor.range_mm=300"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("seamtrack: error: sensor.range_mm: the seam is never in view")
    assert main(["check", PAPER]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "seam in view along the path" in x)
    seen, total = [int(w) for w in line.split() if w.isdigit()][:2]
    assert 0 < seen <= total == 81  # 400 mm, a pose every 5 mm


def test_the_geometric_view_test_agrees_with_the_sensor_at_each_pose() -> None:
    """check_seam_in_view counts exactly the poses at which the seam model's sensing finds
    the seam (an independent count through the sensor's own call)."""
    from seamtrack.sensing.scan import sense_seam
    from seamtrack.simulation.assemble import planned_tcp_poses
    from seamtrack.simulation.checks import check_seam_in_view

    parts = build_parts(load_scene(PAPER, {"sensor.look_ahead_mm": 40.0}))
    path = planned_tcp_poses(parts.seam.length_mm, parts.tool_program, parts.robot, False)
    poses = path @ parts.robot.T_tcp_sensor
    assert parts.sensor is not None
    expected = sum(bool(sense_seam(parts.seam, T, parts.sensor)) for T in poses)
    assert check_seam_in_view(poses, parts.sensor, parts.seam) == expected
    # 40 mm ahead on a 400 mm seam: the last 40 mm of torch poses see past the end.
    assert expected <= len(poses) - 40 // 5


# --------------------------------------------------------------------------- item 20
def test_the_slow_weld_and_the_fast_sensor_blame_their_own_fields() -> None:
    with pytest.raises(SceneError) as info:
        load_scene(PAPER, {"simulation.welding_speed_mm_s": 1e-300})
    assert info.value.field == "simulation.welding_speed_mm_s"
    # The bound it gives: 3 L / v + 60 s = MAX_TICKS frame periods, v = 3 L / (4e6 s - 60 s).
    assert f"{3 * 400 / (4e6 - 60):.3g} mm/s" in str(info.value)
    # 1e-3 mm/s can still be held at a control period under the 1 s frame period: the period.
    with pytest.raises(SceneError) as info:
        load_scene(PAPER, {"simulation.welding_speed_mm_s": 1e-3})
    assert info.value.field == "robot.control_period_s"
    with pytest.raises(SceneError) as info:
        load_scene(PAPER, {"sensor.frame_rate_hz": 1e308})
    assert info.value.field == "sensor.frame_rate_hz"


def test_a_scene_with_a_utf8_bom_reads_as_without(tmp_path: Path) -> None:
    text = "[simulation]\nwelding_speed_mm_s = 7.5\n[seam]\nlength_mm = 100.0\n"
    (tmp_path / "plain.toml").write_text(text)
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_scene(tmp_path / "bom.toml").config == load_scene(tmp_path / "plain.toml").config


def test_a_ragged_csv_row_is_named_by_file_and_line(tmp_path: Path) -> None:
    path = tmp_path / "ragged.csv"
    path.write_text("# a comment\nx_mm,y_mm,z_mm\n0,0,0\n10,0\n20,0,0\n")
    with pytest.raises(SeamtrackError) as info:
        Seam.from_csv(path)
    assert "ragged.csv, line 4: 2 cells where line 3 has 3" in str(info.value)
    assert "inhomogeneous" not in str(info.value)
    path.write_bytes(b"\xef\xbb\xbf0,0,0\n10,0,0\n")  # a BOM before bare numbers
    assert Seam.from_csv(path).length_mm == 10.0


def _mount_tmpfs(where: Path, size: str) -> bool:
    """A small tmpfs at ``where`` (root, where mounting is allowed), else False."""
    where.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        return False
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                          capture_output=True)  # fmt: skip
    return done.returncode == 0


@pytest.fixture
def full_disk(tmp_path: Path) -> Iterator[Path]:
    where = tmp_path / "full"
    if not _mount_tmpfs(where, "160k"):
        pytest.skip("cannot mount a small tmpfs here (not root, or mount not allowed)")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


def test_a_full_disk_ends_a_run_in_one_line_and_leaves_nothing(full_disk, capsys) -> None:
    """A 60 mm run writes ~0.3 MB of trace: on a 160 kB disk it cannot."""
    out = full_disk / "run"
    code = main(["run", PAPER, "--set", "seam.length_mm=60", "--out", str(out), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith("seamtrack: error: --out: the disk is full")
    assert list(full_disk.iterdir()) == []


def test_a_full_disk_ends_a_dataset_in_one_line_and_keeps_its_chunks(full_disk) -> None:
    """In a fresh process (HDF5 writing to a full disk crashed it, exit 139): exit 2, one
    line, the finished chunks whole and readable, no temporary file left."""
    import h5py

    spec = full_disk.parent / "spec.toml"
    spec.write_text('rays = 256\nchunk_size = 16\n[joint]\nfamilies = ["v-groove"]\n')
    out = full_disk / "data"
    command = ["dataset", str(spec), "--n", "256", "--out", str(out), "-q"]
    done = subprocess.run([sys.executable, "-m", "seamtrack.cli", *command],
                          capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("seamtrack: error: --out: the disk is full")
    assert done.stderr.count("\n") == 1
    chunks = sorted(out.glob("chunk-*.h5"))
    assert chunks and not list(out.glob(".*.tmp"))  # something finished, nothing half-written
    for path in chunks:
        with h5py.File(path) as f:
            assert f.attrs["count"] == 16 and len(f["index"]) == 16


# --------------------------------------------------------------------------- item 24 (part)
def test_check_prints_the_mounts_values_not_its_key(capsys) -> None:
    assert main(["check", PAPER, "--set", "sensor.mount_rotation_deg=[5,0,0]"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "sensor mount" in x)
    assert "[5.0, 0.0, 0.0] deg" in line


def test_a_negative_zero_prints_as_zero() -> None:
    assert _fmt(-0.0) == "0" and _fmt(0.0) == "0" and _fmt(-1e-9) == "-1e-09"
    assert math.copysign(1.0, -0.0) < 0  # the value itself stays as computed


def test_frames_csv_writes_found_as_an_integer(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["run", PAPER, "--set", "seam.length_mm=40", "--out", str(out), "-q",
                 "--no-plot"]) == 0  # fmt: skip
    lines = (out / "frames.csv").read_text().splitlines()
    assert lines[0] == "t_capture_s,found,x_mm,y_mm,z_mm"
    found = [row.split(",")[1] for row in lines[1:]]
    assert set(found) <= {"0", "1"} and "1" in found
    table = np.genfromtxt(out / "frames.csv", delimiter=",", names=True)
    # A frame that found the seam has a point; one that did not has none.
    assert np.array_equal(table["found"] == 1, np.isfinite(table["x_mm"]))


def test_sweep_png_draws_the_max_and_p95_errors(monkeypatch, tmp_path: Path) -> None:
    """What the plot draws: per value, the mean over seeds of the runs' max and p95 errors
    (not the min error, 0 wherever the torch crosses the seam)."""
    from seamtrack.batch.sweep import PLOT_KEYS, summarize, write_sweep
    from seamtrack.viz import plots

    rows = [
        {"case": f"v={v}|{s}", "value": v, "seed": s,
         "summary": {"status": "completed", "max_error_mm": v + s, "p95_error_mm": 0.5 * v + s,
                     "min_error_mm": 0.0, "rms_error_mm": 0.1, "mean_speed_mm_s": 5.0,
                     "completed_fraction": 1.0}}
        for v in (1.0, 2.0) for s in (0, 1)
    ]  # fmt: skip
    drawn: dict[str, np.ndarray] = {}
    real = plots.save_figure

    def capture(fig, path):
        for container in fig.axes[0].containers:
            drawn[container.get_label()] = np.asarray(container.lines[0].get_ydata())
        return real(fig, path)

    monkeypatch.setattr(plots, "save_figure", capture)
    write_sweep(summarize(rows), "x", tmp_path / "s", rows=rows)
    assert set(drawn) == set(PLOT_KEYS) == {"max_error_mm", "p95_error_mm"}
    np.testing.assert_allclose(drawn["max_error_mm"], [1.5, 2.5])
    np.testing.assert_allclose(drawn["p95_error_mm"], [1.0, 1.5])


def test_a_recordings_profiles_and_labels_meet_a_sets_checks(tmp_path: Path) -> None:
    """What a recording gives (profiles of several lengths, labels) is held to the same checks:
    in mm it passes; in metres, or with a label that is NaN, it is refused."""
    from seamtrack.sensing.profiles import Profile

    y = np.linspace(-10.0, 10.0, 201)
    mm = [Profile(np.column_stack([y[: 201 - k], _v(1)[0][: 201 - k]])) for k in (0, 20)]
    labels = np.array([[0.0, 110.0], [0.0, 110.0]])
    real_input.check_recorded(mm, labels, tmp_path)
    metres = [Profile(1e-3 * p.points_laser) for p in mm]
    with pytest.raises(SeamtrackError, match="looks like metres"):
        real_input.check_recorded(metres, 1e-3 * labels, tmp_path)
    with pytest.raises(SeamtrackError, match="label of profile 1"):
        real_input.check_recorded(mm, np.array([[0.0, 110.0], [np.nan, 110.0]]), tmp_path)


def test_sweep_and_dataset_say_in_one_line_that_they_cap_the_workers(capsys, tmp_path) -> None:
    """One case: one worker, whatever --workers asks; the line says why, and the run goes on.
    A dataset of 2 chunks: at most 2 workers, and no more than this process's CPUs."""
    points = "seam.points_mm=[[0,0,0],[20,0,0],[30,10,0]]"
    code = main(["sweep", "paper-corner", "--param", "tracker.radius_mm", "--values", "1",
                 "--workers", "100000", "--set", points])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 0
    assert err.splitlines() == ["seamtrack: --workers 100000 capped at 1 (1 case to run)"]
    spec = tmp_path / "spec.toml"
    spec.write_text('rays = 64\nchunk_size = 8\n[joint]\nfamilies = ["v-groove"]\n')
    code = main(["dataset", str(spec), "--n", "16", "--out", str(tmp_path / "d"), "--workers",
                 "100000", "-q"])  # fmt: skip
    (line,) = capsys.readouterr().err.splitlines()
    assert code == 0 and line.startswith("seamtrack: --workers 100000 capped at ")
    assert 1 <= int(line.split()[5]) <= min(2, len(os.sched_getaffinity(0)))
