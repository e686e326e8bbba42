"""Sweeps give the same numbers on one process, a process pool and a Dask cluster; resume after
a kill without redoing finished cases; record a failing case and go on; and report 95 %
confidence intervals over seeds."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from seamtrack.batch.sweep import markdown_table, run_sweep, summarize
from seamtrack.errors import SeamtrackError

SCENE = "paper-corner"
#: paper-corner shortened to a 20 mm leg and a 14 mm leg after the 45 deg turn (~0.3 s a run).
SHORT_CORNER = {"seam.points_mm": [[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [30.0, 10.0, 0.0]]}
RADII = [6.0, 3.0, 1.0, 0.5, 0.2, 0.1]


def _numbers(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Each case's summary without its wall-clock timings (the only thing that may differ)."""
    out = {}
    for row in rows:
        summary = {k: v for k, v in row["summary"].items() if not k.endswith("wall_time_s")}
        out[row["case"]] = summary
    return out


def _assert_same_numbers(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> None:
    numbers_a, numbers_b = _numbers(a), _numbers(b)
    assert list(numbers_a) == list(numbers_b)  # same cases, in case order
    for case, summary in numbers_a.items():
        other = numbers_b[case]
        assert summary.keys() == other.keys()
        for key, value in summary.items():
            if isinstance(value, float) and math.isnan(value):
                assert math.isnan(other[key]), (case, key)
            else:
                assert other[key] == value, (case, key)  # bit for bit: same seeds, same code


@pytest.fixture(scope="module")
def serial_rows() -> list[dict[str, Any]]:
    return run_sweep(SCENE, "tracker.radius_mm", RADII, overrides=SHORT_CORNER, workers=1)


def test_serial_sweep_runs_every_case(serial_rows: list[dict[str, Any]]) -> None:
    assert [row["value"] for row in serial_rows] == RADII
    assert all("summary" in row for row in serial_rows)
    errors = [row["summary"]["max_error_mm"] for row in serial_rows]
    assert all(math.isfinite(e) and e > 0 for e in errors)
    # Table 4's trend on the short corner: the largest radius cuts the corner the most.
    assert errors[0] > errors[-1]


def test_process_pool_gives_the_serial_numbers(serial_rows: list[dict[str, Any]]) -> None:
    rows = run_sweep(SCENE, "tracker.radius_mm", RADII, overrides=SHORT_CORNER, workers=2)
    _assert_same_numbers(serial_rows, rows)


def test_dask_cluster_gives_the_serial_numbers(serial_rows: list[dict[str, Any]]) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with warnings.catch_warnings():
        # Closing a LocalCluster while its nanny processes shut down can warn that the
        # workers' heartbeats went unanswered; that is cluster teardown, not a result.
        warnings.filterwarnings("ignore", message=".*heartbeat.*", category=UserWarning)
        cluster = distributed.LocalCluster(
            n_workers=2,
            processes=True,
            threads_per_worker=1,
            dashboard_address=None,  # no web server: no port clash with another cluster
        )
        try:
            rows = run_sweep(
                SCENE,
                "tracker.radius_mm",
                RADII,
                overrides=SHORT_CORNER,
                scheduler=cluster.scheduler_address,
            )
        finally:
            cluster.close(timeout=60)
    _assert_same_numbers(serial_rows, rows)


def test_dask_scheduler_that_cannot_be_reached_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("dask.distributed")
    from seamtrack.batch import sweep
    from seamtrack.errors import SeamtrackError

    monkeypatch.setattr(sweep, "DASK_CONNECT_TIMEOUT_S", 1.0)

    with pytest.raises(SeamtrackError) as info:
        run_sweep(
            SCENE,
            "tracker.radius_mm",
            RADII[:1],
            overrides=SHORT_CORNER,
            scheduler="tcp://127.0.0.1:9",  # the discard port: nothing listens there
        )
    assert info.value.field == "--scheduler"


def _result_lines(path: Path) -> list[dict[str, Any]]:
    rows = []
    for line in path.read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return rows


#: Run in a child: the CLI's sweep, whose third case says so in the file ``argv[1]`` and waits
#: to be killed (the two before it are in results.jsonl by then: a row is written before the
#: next case starts). The parent kills on that state, not on a count it must catch in time.
_HALT_AT_THE_THIRD_CASE = """
import sys, time
from pathlib import Path
from seamtrack.batch import sweep
from seamtrack.cli.main import main

real, started = sweep.run_case, []

def run_case(scene, case, overrides):
    if len(started) == 2:
        Path(sys.argv[1]).touch()
        time.sleep(3600)
    started.append(case)
    return real(scene, case, overrides)

sweep.run_case = run_case
sys.exit(main(sys.argv[2:]))
"""


def test_killed_sweep_resumes_without_redoing_finished_cases(tmp_path: Path) -> None:
    """Kill the CLI once two cases are in results.jsonl; the rerun runs only the rest."""
    out = tmp_path / "sweep"
    radii = [6.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.8, 0.5, 0.3, 0.2, 0.1, 0.05]
    args = [
        "sweep",
        SCENE,
        "--param",
        "tracker.radius_mm",
        "--values",
        ",".join(str(r) for r in radii),
        "--set",
        f"seam.points_mm={SHORT_CORNER['seam.points_mm']}",
        "--out",
        str(out),
        "-q",
    ]
    results = out / "results.jsonl"
    halted = tmp_path / "halted"
    first = subprocess.Popen(
        [sys.executable, "-c", _HALT_AT_THE_THIRD_CASE, str(halted), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 300.0  # bounds the wait; it times nothing
        while not halted.exists() and first.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert halted.exists(), "the sweep never reached its third case"
    finally:
        first.kill()
        first.wait(timeout=30)
    before = {row["case"]: row for row in _result_lines(results)}
    assert len(before) == 2

    second = subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", *args], capture_output=True, text=True, timeout=300
    )
    assert second.returncode == 0, second.stderr
    after = _result_lines(results)
    cases = [row["case"] for row in after]
    assert len(cases) == len(set(cases)) == len(radii)  # each case ran exactly once
    for row in after:
        if row["case"] in before:  # kept as the first run wrote it, not run again
            assert row == before[row["case"]]
    table = json.loads((out / "sweep.json").read_text())
    assert [row["value"] for row in table] == radii
    assert all(row["failed"] == 0 and row["runs"] == 1 for row in table)
    assert (out / "sweep.md").read_text().count("\n") == len(radii) + 2


def test_results_file_cut_mid_line_is_repaired_on_resume(tmp_path: Path) -> None:
    """A kill during a write leaves a partial last line; the resume reruns that case and the
    file stays one JSON object per line."""
    out = tmp_path / "sweep"
    radii = RADII[:3]
    run_sweep(SCENE, "tracker.radius_mm", radii, overrides=SHORT_CORNER, out_dir=out)
    results = out / "results.jsonl"
    lines = results.read_text().splitlines()
    results.write_text("\n".join(lines[:2]) + "\n" + lines[2][: len(lines[2]) // 2])
    rows = run_sweep(SCENE, "tracker.radius_mm", radii, overrides=SHORT_CORNER, out_dir=out)
    assert [row["value"] for row in rows] == radii
    text = results.read_text()
    assert text.endswith("\n")
    stored = [json.loads(line) for line in text.splitlines()]  # every line parses
    assert sorted(row["value"] for row in stored) == sorted(radii)


def test_failing_cases_are_recorded_and_the_sweep_goes_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An invalid value (a negative radius) and a user tracker that raises mid-run are both
    recorded with their error; the good cases around them still run, in a process pool."""
    module = tmp_path / "bad_trackers.py"
    module.write_text(
        textwrap.dedent(
            """
            class Explodes:
                def reset(self, context):
                    pass

                def update(self, measurement):
                    raise RuntimeError("tracker blew up on its first frame")

                def command(self, t_s, tcp_world, tcp_velocity_world):
                    return None
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))  # forked workers inherit it
    names = ["II", "bad_trackers:Explodes", "I"]
    rows = run_sweep(
        SCENE, "tracker.name", names, overrides=SHORT_CORNER, workers=2, out_dir=tmp_path / "a"
    )
    assert [row["value"] for row in rows] == names
    assert "summary" in rows[0] and "summary" in rows[2]
    assert "RuntimeError: tracker blew up" in rows[1]["error"]

    assert "update() raised" in rows[1]["error"] and "bad_trackers:Explodes" in rows[1]["error"]
    table = summarize(rows)
    assert table[1]["failed"] == 1 and "error" in table[1]
    assert "error: " in markdown_table(table, "tracker.name")


def test_an_invalid_value_refuses_the_sweep_before_anything_runs_or_is_written(
    tmp_path: Path,
) -> None:
    """A negative radius among the values is a user error: refused up front, naming the
    field, and no output folder is left behind."""
    with pytest.raises(SeamtrackError) as info:
        run_sweep(
            SCENE,
            "tracker.radius_mm",
            [1.0, -1.0, 0.5],
            overrides=SHORT_CORNER,
            out_dir=tmp_path / "never",
        )
    assert "tracker.radius_mm" in str(info.value)
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [({"workers": 0}, "--workers"), ({"seeds": [-1]}, "--seeds"), ({"values": []}, "--values")],
)
def test_meaningless_sweep_settings_are_refused(kwargs: dict[str, Any], field: str) -> None:
    settings: dict[str, Any] = {"values": [1.0], **kwargs}
    values = settings.pop("values")
    with pytest.raises(SeamtrackError) as info:
        run_sweep(SCENE, "tracker.radius_mm", values, overrides=SHORT_CORNER, **settings)
    assert info.value.field == field


def test_monte_carlo_over_seeds_reports_95_percent_confidence_intervals() -> None:
    """Noisy sensor, three seeds per value: the table's means and CI half-widths are those of
    the per-seed runs (1.96 s / sqrt(n)), and differ from zero because the seeds differ."""
    over = {**SHORT_CORNER, "sensor.noise_range_mm": 0.05, "sensor.noise_lateral_mm": 0.05}
    seeds = [0, 1, 2]
    rows = run_sweep(SCENE, "tracker.radius_mm", [1.0, 0.2], overrides=over, seeds=seeds)
    assert [(row["value"], row["seed"]) for row in rows] == [
        (v, s) for v in (1.0, 0.2) for s in seeds
    ]
    table = summarize(rows)
    assert len(table) == 2
    for entry in table:
        runs = [r["summary"] for r in rows if r["value"] == entry["value"]]
        assert [r["seed"] for r in runs] == seeds
        errors = np.array([r["max_error_mm"] for r in runs])
        assert len(set(errors)) == len(seeds)  # each seed drew its own noise
        assert entry["runs"] == len(seeds) and entry["failed"] == 0
        assert entry["max_error_mm"] == pytest.approx(errors.mean())
        assert entry["max_error_mm_ci95"] == pytest.approx(
            1.96 * errors.std(ddof=1) / math.sqrt(len(seeds))
        )
        assert all(entry[f"{k}_ci95"] >= 0 for k in ("rms_error_mm", "mean_speed_mm_s"))
    assert "±" in markdown_table(table, "tracker.radius_mm")


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (Linux /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_sigkilled_sweep_takes_its_workers_with_it(tmp_path: Path) -> None:
    """SIGKILL runs no clean-up in the parent; the workers end themselves (PR_SET_PDEATHSIG,
    and a watcher thread) instead of living on as orphans holding the terminal's pipe."""
    out = tmp_path / "sweep"
    radii = [6.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.8, 0.5, 0.3, 0.2, 0.1, 0.05] * 4
    args = [
        sys.executable, "-m", "seamtrack.cli", "sweep", SCENE,
        "--param", "simulation.seed", "--values", ",".join(str(i) for i in range(len(radii))),
        "--set", f"seam.points_mm={SHORT_CORNER['seam.points_mm']}",
        "--workers", "2", "--out", str(out), "-q",
    ]  # fmt: skip
    parent = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline and parent.poll() is None:
            workers = _children(parent.pid)
            if len(workers) >= 2 and (out / "results.jsonl").exists():
                break
            time.sleep(0.05)
        assert parent.poll() is None and len(workers) >= 2, "the workers never started"
        parent.kill()
    finally:
        parent.wait(timeout=30)
    deadline = time.monotonic() + 60.0  # generous: this bounds a wait, it times nothing
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    assert not [w for w in workers if _alive(w)]


def test_sweep_csv_is_one_pandas_line_per_case_and_seed(tmp_path: Path) -> None:
    """``pandas.read_csv`` of sweep.csv gives every case and seed with every summary key,
    equal to results.jsonl."""
    pandas = pytest.importorskip("pandas")
    from seamtrack.batch.sweep import write_sweep

    over = {**SHORT_CORNER, "sensor.noise_range_mm": 0.05}
    rows = run_sweep(
        SCENE, "tracker.radius_mm", [1.0, 0.2], overrides=over, seeds=[0, 1], out_dir=tmp_path
    )
    write_sweep(summarize(rows), "tracker.radius_mm", tmp_path, plot=False, rows=rows)
    frame = pandas.read_csv(tmp_path / "sweep.csv")
    assert len(frame) == 4
    assert list(frame["tracker.radius_mm"]) == [1.0, 1.0, 0.2, 0.2]
    assert list(frame["seed"]) == [0, 1, 0, 1]
    assert set(rows[0]["summary"]) <= set(frame.columns)
    for row, (_, line) in zip(rows, frame.iterrows(), strict=True):
        assert line["max_error_mm"] == pytest.approx(row["summary"]["max_error_mm"], rel=1e-12)
        assert line["status"] == row["summary"]["status"]
