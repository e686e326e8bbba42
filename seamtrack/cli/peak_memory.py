"""Run the ``seamtrack`` command line and, as it exits, write down its own peak memory.

``python -m seamtrack.cli.peak_memory REPORT ARGS...`` runs ``seamtrack ARGS...`` and writes its
peak resident memory in MB (``VmHWM`` of ``/proc/self/status``) to the file ``REPORT``.

Why not the child's rusage: Linux carries the parent's high-water mark across ``exec``
(``exec_mmap`` keeps the old address space's ``hiwater_rss`` in ``signal->maxrss``), so every
child that a 2 GB pytest worker starts reports ``ru_maxrss`` >= 2 GB, however small it stays.
``VmHWM`` is the high-water mark of the address space ``exec`` made: the child's alone.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["main", "vm_hwm_mb"]


def vm_hwm_mb() -> float | None:
    """This process's peak resident memory in MB (None: no ``/proc``, not Linux)."""
    try:
        status = Path("/proc/self/status").read_text()
    except OSError:
        return None
    for line in status.splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024  # kB
    return None


def main(argv: list[str]) -> int:
    report, *args = argv
    from seamtrack.cli.main import main as seamtrack

    try:
        return seamtrack(args)
    finally:
        peak = vm_hwm_mb()
        if peak is not None:
            Path(report).write_text(f"{peak:.3f}\n")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
