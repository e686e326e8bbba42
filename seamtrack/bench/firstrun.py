"""``seamtrack bench firstrun``: what a new user's first mesh-mode run costs in compiling.

The demo's mesh run (``run paper-v-groove --set workpiece.params.seam_length_mm=60``, as
``make demo`` runs it) twice, each from a fresh process: first with an empty numba cache (a
new temporary ``NUMBA_CACHE_DIR``, which numba puts ahead of the package's ``__pycache__``),
then again with the cache that run filled. ``extra_s`` is the first run's wall time minus the
second's: the compiling a first run pays. The CAD mesh cache is left as it is (warm after the
first run of the bench); the 1-minute load is written beside the figures, as the machine may
be busy.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info

#: The demo's mesh-mode run (Makefile ``MESH_DEMO``).
DEMO_ARGS = ("paper-v-groove", "--set", "workpiece.params.seam_length_mm=60")
#: Issue 41 item 1: the first run spends at most this much more than the second.
TARGET_EXTRA_S = 15.0


def timed_run(cache_dir: Path, out: Path, env: dict[str, str] | None = None) -> float:
    """Wall time (s) of the demo's mesh run in a fresh process with numba's cache in
    ``cache_dir``; ``env`` adds variables (e.g. ``SEAMTRACK_PARALLEL_COMPILE=0``)."""
    run_env = {**os.environ, **(env or {}), "NUMBA_CACHE_DIR": str(cache_dir)}
    command = [sys.executable, "-m", "seamtrack.cli", "run", *DEMO_ARGS]
    command += ["--out", str(out), "--force", "--quiet"]
    start = time.perf_counter()
    subprocess.run(command, env=run_env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def measure(env: dict[str, str] | None = None) -> dict[str, Any]:
    """One empty-cache run and one warm run: ``first_s``, ``second_s``, ``extra_s`` and the
    1-minute load before each."""
    with tempfile.TemporaryDirectory(prefix="seamtrack-firstrun-") as tmp:
        cache = Path(tmp) / "numba-cache"
        load_first = os.getloadavg()[0]
        first = timed_run(cache, Path(tmp) / "first", env)
        load_second = os.getloadavg()[0]
        second = timed_run(cache, Path(tmp) / "second", env)
    return {
        "first_s": round(first, 2),
        "second_s": round(second, 2),
        "extra_s": round(first - second, 2),
        "load_1min": round(load_first, 2),
        "load_1min_second": round(load_second, 2),
    }


def firstrun_table(data: dict[str, Any]) -> str:
    """The bench's markdown table: one row per variant measured."""
    lines = [
        "| variant | first run (s) | second run (s) | extra (s) | 1-min load |",
        "|---|---|---|---|---|",
    ]
    for row in data["rows"]:
        lines.append(
            f"| {row['variant']} | {row['first_s']:.1f} | {row['second_s']:.1f} "
            f"| {row['extra_s']:.1f} | {row['load_1min']:.2f} |"
        )
    return "\n".join(lines) + "\n"


#: The variants measured: label -> extra environment.
VARIANTS: dict[str, dict[str, str]] = {
    "parallel warm compile (default)": {},
    "one process (SEAMTRACK_PARALLEL_COMPILE=0)": {"SEAMTRACK_PARALLEL_COMPILE": "0"},
}


def bench_firstrun(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """Measure each of :data:`VARIANTS` (only the default when ``quick``); write
    ``firstrun.json`` (the default's ``first_s``, ``second_s``, ``extra_s``, ``load_1min`` at
    the top, every variant under ``rows``) and ``firstrun.md``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for label, env in list(VARIANTS.items())[: 1 if quick else None]:
        rows.append({"variant": label, **measure(env)})
        print(f"  {label}: {rows[-1]}", flush=True)
    result: dict[str, Any] = {
        **{k: rows[0][k] for k in ("first_s", "second_s", "extra_s", "load_1min")},
        "command": "seamtrack run " + " ".join(DEMO_ARGS),
        "target_extra_s": TARGET_EXTRA_S,
        "rows": rows,
        "machine": machine_info(),
    }
    (out / "firstrun.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "firstrun.md").write_text(firstrun_table(result))
    return result


class CompileTimes:
    """Per-kernel compile CPU seconds from numba's ``numba:compile`` events, while registered
    (:meth:`register`): ``inclusive`` (the kernels compiled on the way counted too),
    ``exclusive`` (not) and ``count`` (compilations: more than one is a kernel compiled for
    more than one signature), each keyed by the kernel's ``module.qualname``."""

    def __init__(self) -> None:
        self.inclusive: dict[str, float] = {}
        self.exclusive: dict[str, float] = {}
        self.count: dict[str, int] = {}
        self._stack: list[list[Any]] = []

    def register(self) -> Any:
        """Start listening; returns the listener (``numba.core.event.unregister`` it)."""
        from numba.core import event

        times = self

        class _Listener(event.Listener):
            def on_start(self, ev: Any) -> None:
                fn = ev.data["dispatcher"].py_func
                times._stack.append(
                    [f"{fn.__module__}.{fn.__qualname__}", time.process_time(), 0.0]
                )

            def on_end(self, ev: Any) -> None:
                name, start, inner = times._stack.pop()
                spent = time.process_time() - start
                times.inclusive[name] = times.inclusive.get(name, 0.0) + spent
                times.exclusive[name] = times.exclusive.get(name, 0.0) + spent - inner
                times.count[name] = times.count.get(name, 0) + 1
                if times._stack:
                    times._stack[-1][2] += spent

        listener = _Listener()
        event.register("numba:compile", listener)
        return listener


def kernel_compile_cpu(top: int = 12) -> None:
    """Build and run the demo's scene in this process (the warming child off; as ``seamtrack
    run`` does, without writing its outputs) and print the compile CPU, in all and of the
    ``top`` kernels by inclusive time, and every kernel compiled more than once. Start it with
    an empty ``NUMBA_CACHE_DIR`` (:func:`main` does)."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    os.environ["SEAMTRACK_PARALLEL_COMPILE"] = "0"
    times = CompileTimes()
    times.register()
    start = time.process_time()
    run(build_parts(load_scene(DEMO_ARGS[0], [DEMO_ARGS[2]])))
    print(f"run {time.process_time() - start:.1f} CPU s, compiling "
          f"{sum(times.exclusive.values()):.1f} CPU s ({len(times.count)} kernels, "
          f"{sum(k.startswith('seamtrack.') for k in times.count)} of them seamtrack's), "
          f"1-min load {os.getloadavg()[0]:.2f}")  # fmt: skip
    for name, spent in sorted(times.inclusive.items(), key=lambda x: -x[1])[:top]:
        print(f"  {spent:6.2f} s inclusive {times.exclusive[name]:6.2f} s own  {name}")
    for name, n in times.count.items():
        if n > 1:
            print(f"  compiled {n} times: {name}")


def main(argv: list[str] | None = None) -> int:
    """``python -m seamtrack.bench.firstrun --kernels``: the demo's compile CPU per kernel, in a
    fresh process with an empty numba cache."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m seamtrack.bench.firstrun")
    parser.add_argument("--kernels", action="store_true", help="compile CPU per kernel")
    parser.add_argument("--top", type=int, default=12, help="kernels listed")
    parser.add_argument("--here", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.here:
        kernel_compile_cpu(args.top)
    elif args.kernels:
        with tempfile.TemporaryDirectory(prefix="seamtrack-kernels-") as tmp:
            env = {**os.environ, "NUMBA_CACHE_DIR": tmp}
            command = [sys.executable, "-m", "seamtrack.bench.firstrun", "--here"]
            subprocess.run([*command, "--top", str(args.top)], env=env, check=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
