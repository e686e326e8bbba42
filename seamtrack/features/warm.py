"""Compile the scene's extractor kernels on the second core while the run compiles the rest.

A first run after an install (an empty numba cache) compiles its kernels one after another:
the control ticks and the tracker's update (the loop compiles them before its first frame),
ray casting and the stripe's profile, then the extractor at the first frame.
:func:`start_warming` forks a child that calls the scene's extractor once on a synthetic
profile of its joint, so numba compiles the extractor's kernels there and writes them to its
on-disk cache (``cache=True``, the same cache directory: the child inherits the parent's
environment), while the parent compiles the rest (about as much). When the parent reaches its first
frame's extraction it waits for the child (:func:`wait_warmed`, at most :data:`WAIT_S`), then
numba's dispatchers find the child's kernels in the cache and load them instead of compiling.

Without that wait the parent compiled, at its first frame, every extractor kernel the child had
not saved yet: the same kernels twice at once (the child, which started first, still finished
first, so the parent gained nothing), and two processes saving the same cache indexes; numba
saves an index by reading it, adding its entry and writing it back, so an entry the other
process added in between could be lost (a kernel compiled again by the next run). Where the
wait times out the parent compiles as it would have: the results are the same either way, the
kernels being the same code.

The child only warms the cache: it writes no output, prints nothing, and its result is thrown
away. It starts only when the cache is cold (an extractor kernel's cache index is missing) and
``os.fork`` exists; ``SEAMTRACK_PARALLEL_COMPILE=0`` switches it off.
"""

from __future__ import annotations

import os
import sys
import threading
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from seamtrack.sensing.sensor import LaserLineSensor

#: ``SEAMTRACK_PARALLEL_COMPILE=0`` turns the warming child off.
SWITCH = "SEAMTRACK_PARALLEL_COMPILE"

#: How long the parent waits for its warming child at its first extraction (s): the child
#: takes about a minute on a quiet 2-core machine, three on a busy one; past this the parent
#: compiles what it still needs itself.
WAIT_S = 300.0

#: The reaping threads of the warming children this process started, by pid.
_reapers: dict[int, threading.Thread] = {}

#: The synthetic joint whose profile each built-in extractor is warmed on.
WARM_JOINT = {
    "v-groove": "v-groove",
    "square-butt": "square-butt",
    "fillet": "fillet",
    "lap": "lap",
    "outside-corner": "outside-corner",
    "generic": "v-groove",
    "groove": "v-groove",
}


def wanted() -> bool:
    """Whether warming may start: not switched off, and ``os.fork`` exists (POSIX)."""
    return os.environ.get(SWITCH) != "0" and hasattr(os, "fork")


def extractor_dispatchers(find: Any) -> list[Any]:
    """The cached numba dispatchers of the module defining ``find``'s class and of the
    modules of its package (``seamtrack.features.vgroove`` for the v-groove extractor)."""
    from numba.core.registry import CPUDispatcher

    module = type(find).__module__
    package = module.rpartition(".")[0] if module.count(".") > 2 else module
    found = []
    for name, mod in list(sys.modules.items()):
        if mod is None or not (name == package or name.startswith(package + ".")):
            continue
        for value in list(vars(mod).values()):
            if isinstance(value, CPUDispatcher) and getattr(value, "_cache", None) is not None:
                found.append(value)
    return found


def cache_cold(find: Any) -> bool:
    """True when a cached kernel of the extractor has no index in numba's on-disk cache yet."""
    for dispatcher in extractor_dispatchers(find):
        cache_file = getattr(dispatcher._cache, "_cache_file", None)
        index = getattr(cache_file, "_index_path", None)
        if index is not None and not Path(index).exists():
            return True
    return False


def warm(find: Callable[..., Any], sensor: LaserLineSensor, joint: str, rays: int | None) -> None:
    """Call ``find`` once on a synthetic ``joint`` profile of ``rays`` rays (its kernels
    compile and go to numba's cache); an extractor that refuses the profile still compiled."""
    from seamtrack.features.synthetic import synthetic_profile

    profile, _ = synthetic_profile(joint, sensor, rays=rays)
    try:
        find(profile)
    except Exception:  # warming only: the run itself reports any failure
        pass


def start_warming(
    find: Any, name: str, sensor: LaserLineSensor, rays: int | None, reap: bool = True
) -> int | None:
    """Fork a child that runs :func:`warm` when the extractor's cache is cold; return its pid
    (a daemon thread reaps it unless ``reap`` is False: then the caller waits for it), or None
    when nothing started."""
    joint = WARM_JOINT.get(name)
    if joint is None or not wanted() or not cache_cold(find):
        return None
    sys.stdout.flush()
    sys.stderr.flush()
    with warnings.catch_warnings():  # Python 3.12 warns of fork() with threads running
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the child: warm, silently, and leave without running any exit handler
        code = 0
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
            warm(find, sensor, joint, rays)
        except BaseException:
            code = 1
        finally:
            os._exit(code)
    if reap:
        reaper = threading.Thread(target=os.waitpid, args=(pid, 0), daemon=True)
        reaper.start()
        _reapers[pid] = reaper
    return pid


def wait_warmed(pid: int | None, timeout_s: float = WAIT_S) -> None:
    """Wait (at most ``timeout_s``) for the warming child ``pid`` that :func:`start_warming`
    started with its reaper; nothing when ``pid`` is None or the child is done."""
    reaper = _reapers.pop(pid, None) if pid is not None else None
    if reaper is not None:
        reaper.join(timeout_s)
