"""The bad-input catalogue: every way a user has broken seamtrack so far, run through the real
command line, and what each gave back.

Each entry is a ``seamtrack`` command line (with the files it needs: a binary scene, a seam
with NaN, trackers and extractors that raise or return garbage) and passes when the command
exits 2 with one ``seamtrack: error:`` line naming a field (and, for an error inside user code,
the user's own frames after it), prints no Python traceback, leaves no output folder behind,
and peaks under 2 GB. ``seamtrack bench failures`` runs it all in fresh processes and measures
memory and time; the test suite runs the quick entries in-process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info
from seamtrack.bench.failure_inputs import CATALOGUE, Entry, set_args, workspace
from seamtrack.simulation.compiling import MESSAGE as COMPILING_MESSAGE

__all__ = [
    "CATALOGUE",
    "Entry",
    "Outcome",
    "bench_failures",
    "run_entry",
    "run_measured",
    "workspace",
]


@dataclass(frozen=True)
class Outcome:
    name: str
    exit_code: int
    stderr: str
    out_left: bool
    peak_mb: float
    wall_s: float

    def problems(self, field: str) -> list[str]:
        """What makes this outcome fall short (empty: it passed)."""
        found = []
        # the first run's compiling notice is not an error line
        lines = [line for line in self.stderr.splitlines() if line != COMPILING_MESSAGE]
        if self.exit_code != 2:
            found.append(f"exit {self.exit_code}")
        if "Traceback (most recent call last)" in self.stderr:
            found.append("traceback")
        if not lines or not lines[0].startswith("seamtrack: error: "):
            found.append("no error line")
        elif field and field not in lines[0]:
            found.append(f"error line does not name {field!r}")
        errors = [line for line in lines if line.startswith("seamtrack: error: ")]
        if len(errors) != 1:
            found.append(f"{len(errors)} error lines")
        if self.out_left:
            found.append("output folder left behind")
        if self.peak_mb > 2048:
            found.append(f"peak {self.peak_mb:.0f} MB")
        return found


def run_entry(entry: Entry, root: Path) -> Outcome:
    """Run one entry in a fresh process, in ``root`` (which holds the files)."""
    out = root / f"out-{abs(hash(entry.name))}"
    args = [str(out) if a == "OUT" else a.replace("OUT/", f"{out}/") for a in entry.args]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), *sys.path])}
    start = time.perf_counter()
    code, stderr, peak = run_measured(args, root, env)
    wall = time.perf_counter() - start
    return Outcome(entry.name, code, stderr, out.exists(), peak, wall)


def run_measured(
    args: list[str], cwd: Path, env: dict[str, str] | None = None
) -> tuple[int, str, float]:
    """Run ``seamtrack args`` in a fresh process; its exit code, its stderr and its own peak
    resident memory in MB.

    The child writes its peak down itself (:mod:`seamtrack.cli.peak_memory`, ``VmHWM``): its
    rusage would carry the caller's high-water mark across ``exec``, a pytest worker's 2 GB
    included. Where there is no ``/proc`` the rusage is all there is.
    """
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "peak_mb"
        command = [sys.executable, "-m", "seamtrack.cli.peak_memory", str(report), *args]
        proc = subprocess.Popen(
            command, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        assert proc.stderr is not None
        stderr = proc.stderr.read()  # the only pipe: reading it to its end cannot deadlock
        proc.stderr.close()
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        peak = float(report.read_text()) if report.exists() else usage.ru_maxrss / 1024
    return proc.returncode, stderr, peak


#: The largest run the size limits allow: 3.99e6 control ticks (0.2 ms over 799 s), a slow
#: weld that lasts to its time limit. Measured for its memory, not refused.
LARGEST_RUN = (
    "run", *set_args("robot.control_period_s=2e-4", "simulation.time_limit_s=799",
                 "simulation.welding_speed_mm_s=0.4", "simulation.trace_period_s=0.01"),
    "--out", "OUT", "--no-plot", "-q",
)  # fmt: skip


def _largest_run(root: Path) -> dict[str, Any]:
    out = root / "largest"
    start = time.perf_counter()
    code, _, peak = run_measured([str(out) if a == "OUT" else a for a in LARGEST_RUN], root)
    wall = time.perf_counter() - start
    summary = json.loads((out / "summary.json").read_text()) if code == 0 else {}
    return {
        "command": "seamtrack " + " ".join(LARGEST_RUN),
        "exit": code,
        "ticks": int(round(summary.get("sim_time_s", 0.0) / 2e-4)) + 1,
        "status": summary.get("status"),
        "peak_mb": peak,
        "wall_s": wall,
    }


def bench_failures(out_dir: str | Path, *, quick: bool = False) -> dict[str, Any]:
    """Run the catalogue (``quick``: its quick entries) in fresh processes, then the largest
    run the limits allow; write ``failures.json`` and ``failures.md``."""
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        root = workspace(Path(tmp))
        largest = None if quick else _largest_run(root)
        for entry in CATALOGUE:
            if quick and not entry.quick:
                continue
            outcome = run_entry(entry, root)
            rows.append(
                {
                    "name": entry.name,
                    "command": "seamtrack " + " ".join(entry.args),
                    "exit": outcome.exit_code,
                    "first_line": (outcome.stderr.splitlines() or [""])[0],
                    "problems": outcome.problems(entry.field),
                    "peak_mb": outcome.peak_mb,
                    "wall_s": outcome.wall_s,
                }
            )
    result = {"machine": machine_info(), "rows": rows, "largest_run": largest}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "failures.json").write_text(json.dumps(result, indent=2) + "\n")
    bad = [r for r in rows if r["problems"]]
    lines = [
        f"{len(rows)} bad inputs, {len(bad)} falling short; "
        f"tracebacks: {sum('traceback' in r['problems'] for r in rows)}, "
        f"output folders left: {sum('output folder left behind' in r['problems'] for r in rows)}, "
        f"largest peak: {max(r['peak_mb'] for r in rows):.0f} MB.",
        "",
        "| input | exit | s | first line of the answer | problems |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        text = r["first_line"].removeprefix("seamtrack: error: ").replace("|", "/")
        lines.append(
            f"| {r['name']} | {r['exit']} | {r['wall_s']:.1f} | {text[:140]} | "
            f"{', '.join(r['problems']) or 'ok'} |"
        )
    if largest is not None:
        lines += [
            "",
            f"The largest run the limits allow (`{largest['command']}`): {largest['ticks']:,} "
            f"control ticks, {largest['status']}, exit {largest['exit']}, "
            f"{largest['wall_s']:.0f} s, peak {largest['peak_mb']:.0f} MB.",
        ]
    (out / "failures.md").write_text("\n".join(lines) + "\n")
    return result
