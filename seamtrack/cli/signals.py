"""SIGINT and SIGTERM during ``seamtrack run``: a stop request, never an exception.

Python's default SIGINT handler raises ``KeyboardInterrupt`` at whatever bytecode runs next,
and that may be a callback inside compiled code (numba's dispatcher, Embree's bindings), which
then crashes (a ``SystemError``, or a segmentation fault) instead of stopping. Here the first
SIGINT or SIGTERM only sets a :class:`~seamtrack.simulation.stop.StopRequest`: the loop sees it
between ticks (at least once a sensor frame) and ends the run as ``interrupted``; the command
writes what was simulated up to the stop, prints one line and exits with ``128 + the signal's
number`` (130 for SIGINT, 143 for SIGTERM, as a shell and ``ros2 bag record`` report them).
A second signal while the first is being honoured raises ``KeyboardInterrupt`` (the user
insists: a stop before the loop begins, such as the first run's minute of compiling, waits
for the loop otherwise); temporary files are still removed, and nothing half-written stays.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from seamtrack.simulation.stop import StopRequest

#: The signals that stop a run gracefully.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def stop_on_signals() -> Iterator[StopRequest]:
    """While the block runs, SIGINT and SIGTERM request a stop (cause ``sigint`` or
    ``sigterm``) rather than raise; the previous handlers come back afterwards. Off the main
    thread (where Python cannot take signals) the request is only made by others."""
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum: int, frame: Any) -> None:
        if stop.requested:  # a second signal: stop now
            raise KeyboardInterrupt
        name = signal.Signals(signum).name
        stop.request(name.lower(), f"{name} received")

    previous = {sig: signal.signal(sig, handler) for sig in STOP_SIGNALS}
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def exit_code(stop: StopRequest) -> int:
    """``128 + n`` for a stop by signal ``n`` (130 SIGINT, 143 SIGTERM), else 0."""
    if stop.cause.upper() in signal.Signals.__members__:
        return 128 + int(signal.Signals[stop.cause.upper()])
    return 0
