"""What every benchmark shares: the machine it ran on, a best-of-N rate, and its markdown
tables."""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np


def best_rate(fn: Callable[[], object], calls: int, repeats: int) -> float:
    """Profiles per second: best of ``repeats`` runs of ``calls`` calls."""
    fn()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - start) / calls)
    return 1.0 / best


def machine_info() -> dict[str, Any]:
    """CPU model (from /proc/cpuinfo), core count, Python and library versions."""
    import embreex
    import numba
    import trimesh

    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "embreex": getattr(embreex, "__version__", "?"),
        "trimesh": trimesh.__version__,
        "numba": numba.__version__,
    }


def reset_peak_rss() -> int:
    """Reset this process's peak resident size to its current size (Linux); return it (bytes)."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:  # not Linux: the peak is the process's so far
        pass
    return peak_rss(field="VmRSS")


def peak_rss(field: str = "VmHWM") -> int:
    """This process's peak (or, with ``field="VmRSS"``, current) resident size in bytes."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def markdown_table(
    header: Sequence[str], rows: Iterable[Sequence[str]], right: Sequence[bool] = ()
) -> list[str]:
    """The lines of a markdown table: the header, its rule (a column right-aligned where
    ``right`` says so), one line per row of cells (formatted by the caller)."""
    rule = "|" + "".join("---:|" if r else "---|" for r in right or [False] * len(header))
    return [
        "| " + " | ".join(header) + " |",
        rule,
        *("| " + " | ".join(row) + " |" for row in rows),
    ]
