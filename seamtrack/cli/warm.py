"""``seamtrack warm``: compile the kernels and mesh the CAD parts of scenes ahead of their runs.

After an install numba's on-disk cache is empty: a scene's first run compiles the kernels it
uses (ray casting, its extractor, its robot's ticks; about a minute of CPU on a 2-core machine)
and meshes its CAD part. ``seamtrack warm`` does that work ahead of time, so the runs that
follow start at once. It runs each scene for :data:`SIMULATED_S` of simulated time
(``simulation.time_limit_s``), in memory: nothing is written but numba's cache (beside the
package, or ``$NUMBA_CACHE_DIR``) and the workpiece cache (``$SEAMTRACK_CACHE_DIR``).

``make test`` runs it over every built-in scene beside the linters: the suite's two workers
then load the kernels where each compiled them itself on a fresh clone (the same kernels twice,
at once), and the suite's time is the tests' own (docs/speed.md, "The first run").
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from seamtrack.cli.parsing import add_command
from seamtrack.errors import SeamtrackError

HELP = "compile the kernels and mesh the CAD parts of scenes, so that their runs start at once"

#: Simulated seconds each scene runs for: a few sensor frames and a few hundred control
#: ticks, enough to reach every kernel its run calls.
SIMULATED_S = 0.5


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the command on the ``seamtrack`` subparsers."""
    p = add_command(sub, "warm", cmd_warm, HELP, scene=False)
    p.add_argument(
        "scenes",
        nargs="*",
        metavar="SCENE",
        help="built-in scene names or .toml files (default: every built-in scene)",
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="processes to share the scenes among (default 1; each compiles what it meets)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print only the total")
    return p


def warm_scene(name: str) -> float:
    """Run ``name`` for :data:`SIMULATED_S` in memory; return the seconds it took."""
    from seamtrack.features.warm import SWITCH
    from seamtrack.multipass.job import run_job
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    before = os.environ.get(SWITCH)
    os.environ[SWITCH] = "0"  # this process compiles everything itself: no warming child
    try:
        start = time.perf_counter()
        scene = load_scene(name, {"simulation.time_limit_s": SIMULATED_S})
        if scene.config.passes is not None:
            run_job(scene)
        else:
            run(build_parts(scene))
        return time.perf_counter() - start
    finally:  # the caller's process as it was (a notebook's later runs warm as usual)
        if before is None:
            del os.environ[SWITCH]
        else:
            os.environ[SWITCH] = before


#: A row of the report: the scene, its seconds (None when it did not run) and why not.
Row = tuple[str, float | None, str]


def warm_share(names: list[str], skip_missing_extras: bool) -> list[Row]:
    """Warm ``names`` in turn. A scene that needs an extra not installed (its error's fix
    says ``pip install 'seamtrack[...]'``) is skipped when ``skip_missing_extras``; any other
    input error ends the share, as the row's text (an error crosses a process as text)."""
    rows: list[Row] = []
    for name in names:
        try:
            rows.append((name, warm_scene(name), ""))
        except SeamtrackError as exc:
            if not (skip_missing_extras and "seamtrack[" in (exc.fix or "")):
                return [*rows, (name, None, f"error: {exc}")]
            rows.append((name, None, f"skipped: {exc}"))
    return rows


def cmd_warm(args: argparse.Namespace) -> int:
    from seamtrack.simulation.scene import load_scene
    from seamtrack.simulation.templates import builtin_scenes

    if args.jobs < 1:
        raise SeamtrackError(f"{args.jobs} processes", field="--jobs", fix="give 1 or more")
    names = list(args.scenes) or list(builtin_scenes())
    skip = not args.scenes  # every built-in: skip those whose extra is not installed
    for name in names:  # a bad name or file fails here, before any compiling
        load_scene(name)
    forks = "fork" in multiprocessing.get_all_start_methods()
    jobs = min(args.jobs, len(names)) if forks else 1
    print(
        f"seamtrack: warming {len(names)} scene{'s' * (len(names) != 1)} on {jobs} "
        f"process{'es' * (jobs != 1)} (compiling numba kernels, meshing CAD parts)...",
        file=sys.stderr,
        flush=True,
    )
    start = time.perf_counter()
    if jobs == 1:
        done = warm_share(names, skip)
    else:  # round robin: each process meets a different extractor family first
        shares = [names[k::jobs] for k in range(jobs)]
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(jobs, mp_context=context) as pool:
            parts = pool.map(warm_share, shares, [skip] * jobs)
            done = [row for share in parts for row in share]
    for name, _, note in done:
        if note.startswith("error: "):
            raise SeamtrackError(f"{name}: {note[len('error: ') :]}")
    warmed = [(name, seconds) for name, seconds, _ in done if seconds is not None]
    for name, seconds, note in done:
        if seconds is None:
            print(f"{name:32s} {note}")
        elif not args.quiet:
            print(f"{name:32s} {seconds:6.1f} s")
    print(
        f"warmed {len(warmed)} scene{'s' * (len(warmed) != 1)} in "
        f"{time.perf_counter() - start:.1f} s ({jobs} process{'es' * (jobs != 1)})"
    )
    sys.stdout.flush()
    return 0
