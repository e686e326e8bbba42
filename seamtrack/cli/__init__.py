"""The ``seamtrack`` command.

One process uses one core: its arrays are small (a profile, a 4 x 4 pose), and parallel work
runs in processes (``--workers``, Dask). The BLAS library's worker threads would only spin
beside it: after a large product they busy-wait, and on the 2-core machine they inflated the
extractors' CPU time per profile by 1.3-1.6x (``seamtrack extractors bench``) and took the
other core from a sweep's second worker. So the command starts with one BLAS thread unless the
environment says otherwise (set ``OPENBLAS_NUM_THREADS`` and friends to choose).
"""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

from seamtrack.cli.main import main  # noqa: E402  (after the thread settings, before numpy)

__all__ = ["main"]
