"""The ``seamtrack`` command.

One process uses one core: its arrays are small (a profile, a 4 x 4 pose), and parallel work
runs in processes (``--workers``, Dask). The BLAS library's worker threads would only spin
beside it: after a large product they busy-wait, taking the core a sweep's other worker needs,
and the benchmarks' CPU time counts their spinning (0.8 ms of Python right after a 400 x 400
product measured 5.0 ms of CPU time on the 2-core machine). So the command starts with one
BLAS thread unless the environment says otherwise (set ``OPENBLAS_NUM_THREADS`` and friends).
"""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

from seamtrack.cli.main import main  # noqa: E402  (after the thread settings, before numpy)

__all__ = ["main"]
