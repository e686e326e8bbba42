"""The compile-CPU listener of ``python -m seamtrack.bench.firstrun --kernels``
(:class:`seamtrack.bench.firstrun.CompileTimes`), and the literal dispatch it finds: numba
compiles a kernel called with a literal once more for that literal, not for an int64."""

from __future__ import annotations

import numba
import numpy as np
from numba.core import event

from seamtrack.bench.firstrun import CompileTimes


def test_compile_times_nest_and_count_the_literal_signature():
    @numba.njit
    def callee(x, k):
        return x * k

    @numba.njit
    def caller(x):
        return callee(x, 3) + callee(x, np.int64(3))  # a Literal[int](3), then an int64

    times = CompileTimes()
    listener = times.register()
    try:
        assert caller(2.0) == 12.0
    finally:
        event.unregister("numba:compile", listener)
    name = {k.rpartition(".")[2]: k for k in times.count}
    assert times.count[name["caller"]] == 1
    assert times.count[name["callee"]] == 2  # one signature for the literal, one for int64
    assert len(callee.signatures) == 2
    inner = times.inclusive[name["callee"]]
    outer = times.inclusive[name["caller"]]
    assert 0.0 < inner < outer
    assert abs(times.exclusive[name["caller"]] - (outer - inner)) < 1e-9
