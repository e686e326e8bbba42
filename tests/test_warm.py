"""The warming child of a cold first run (seamtrack.features.warm): it compiles the scene's
extractor into the very cache the parent then reads, and SEAMTRACK_PARALLEL_COMPILE=0 stops it.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from seamtrack.features import warm

#: A stand-in extractor with one small cached kernel (the mechanism is the same for the built-in
#: families, whose kernels take a minute to compile: ``seamtrack bench firstrun`` measures that).
PROBE = """
import numba
import numpy as np


@numba.njit(cache=True)
def kernel(y):
    return np.sum(y * y)


class Probe:
    def __call__(self, profile):
        return kernel(np.nan_to_num(profile.points_laser[:, 0]))
"""

#: Run in a fresh process with an empty NUMBA_CACHE_DIR: warm the probe in a child, wait for it
#: (``waitpid``, or ``wait_warmed`` on its reaper when ``reap``), then call it in the parent; print
#: the parent's cache hits and misses.
CHILD_THEN_PARENT = """
import os
from seamtrack.features import warm
from seamtrack.features.synthetic import synthetic_profile
from seamtrack.sensing.sensor import preset
from warm_probe import Probe

sensor = preset("paper")
find = Probe()
assert warm.cache_cold(find), "the cache should start empty"
REAP = {reap}
pid = warm.start_warming(find, "lap", sensor, 64, reap=REAP)
assert pid is not None, "no child started"
if REAP:  # as a run does: its reaper thread waits, the first extraction waits for it
    warm.wait_warmed(pid)
else:
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
assert not warm.cache_cold(find), "the child wrote no cache index"
profile, _ = synthetic_profile("lap", sensor, rays=64)
find(profile)
used = [d for d in warm.extractor_dispatchers(find) if d.signatures]
hits = sum(sum(d.stats.cache_hits.values()) for d in used)
misses = sum(sum(d.stats.cache_misses.values()) for d in used)
print(len(used), hits, misses)
"""


@pytest.mark.parametrize("reap", [False, True])
def test_warm_child_fills_the_cache_the_parent_reads(tmp_path, reap):
    if not hasattr(os, "fork"):
        pytest.skip("no os.fork on this platform")
    (tmp_path / "warm_probe.py").write_text(PROBE)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}  # fmt: skip
    env.pop(warm.SWITCH, None)
    done = subprocess.run(
        [sys.executable, "-c", CHILD_THEN_PARENT.format(reap=reap)],
        env=env,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    used, hits, misses = (int(x) for x in done.stdout.split())
    assert used == 1
    assert hits >= used  # the kernel the parent ran came from the child's cache ...
    assert misses == 0  # ... and was not compiled again


def test_switch_off_starts_no_child(monkeypatch):
    def no_fork() -> int:
        raise AssertionError("forked although switched off")

    monkeypatch.setattr(warm, "cache_cold", lambda find: True)
    monkeypatch.setattr(os, "fork", no_fork)
    monkeypatch.setenv(warm.SWITCH, "0")
    assert not warm.wanted()
    assert warm.start_warming(object(), "lap", None, 256) is None  # type: ignore[arg-type]
    monkeypatch.setenv(warm.SWITCH, "1")
    assert warm.wanted()
    with pytest.raises(AssertionError, match="forked"):
        warm.start_warming(object(), "lap", None, 256)  # type: ignore[arg-type]
