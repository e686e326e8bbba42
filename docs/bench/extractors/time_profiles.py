"""CPU time per profile of every built-in extractor on the extractors bench's profiles (every
imperfection level, N per level and joint; the generic extractor on all five joints): median,
95th percentile and mean of ``time.process_time_ns`` per call, after an untimed warm-up on a
tenth of them. Run old and new code alternately in one session to compare them on a shared
machine::

    python docs/bench/extractors/time_profiles.py 20                      # this checkout
    PYTHONPATH=/path/to/old/checkout python docs/bench/extractors/time_profiles.py 20

(``PYTHONPATH`` puts another checkout's ``seamtrack`` first.) Optional second argument: one
extractor's name.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from seamtrack.bench.extractors import FAMILIES, LEVELS, _profiles
from seamtrack.features.extractors import BUILTIN, extractor
from seamtrack.sensing.sensor import preset


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    names = sorted(BUILTIN) if len(sys.argv) < 3 else [sys.argv[2]]
    sensor = preset("paper")
    cache = {
        (level, joint): _profiles(joint, imp, sensor, n, 1000 * li + j, 1024)
        for li, (level, imp) in enumerate(LEVELS.items())
        for j, joint in enumerate(FAMILIES)
    }
    for name in names:
        ex = extractor(name)
        joints = FAMILIES if name == "generic" else (name,)
        profiles = [p for (_, j), v in cache.items() if j in joints for p, _ in v]
        for p in profiles[:: max(1, len(profiles) // 10)]:
            ex(p)  # warm-up: compiled code loaded, caches filled
        took = []
        for p in profiles:
            t0 = time.process_time_ns()
            ex(p)
            took.append(time.process_time_ns() - t0)
        us = np.array(took) / 1e3
        print(
            f"{name:15s} n={len(us):5d} median {np.median(us):7.0f} us  "
            f"p95 {np.percentile(us, 95):7.0f} us  mean {us.mean():7.0f} us"
        )


if __name__ == "__main__":
    main()
