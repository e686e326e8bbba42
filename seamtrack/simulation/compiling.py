"""One line on stderr when numba compiles seamtrack's kernels (the first run after an install
or a change takes about a minute): a terminal shows the progress bars, but a log or a pipe
would otherwise get a minute of silence.

Numba reports each compilation that its on-disk cache could not serve as a ``numba:compile``
event (``numba.core.event``); a listener prints the line at the first one and then stays quiet.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

#: Commands that never run a compiled kernel (numba is not even imported for them).
QUIET_COMMANDS = frozenset({"init", "sensor", "cache", "warm"})  # warm says it itself
MESSAGE = "seamtrack: compiling numba kernels (first run only, ~1 min)..."
#: ``SEAMTRACK_COMPILE_NOTICE=0`` turns the line off (the test suite does: its in-process CLI
#: calls compile kernels for the first time at any test, and check what stderr holds).
SWITCH = "SEAMTRACK_COMPILE_NOTICE"


def announce_wanted(command: str, quiet: bool, stdout: TextIO | None = None) -> bool:
    """The line is wanted for a command that may compile, not ``--quiet``, with stdout not a
    terminal, unless :data:`SWITCH` is ``0``."""
    if os.environ.get(SWITCH) == "0":
        return False
    out = sys.stdout if stdout is None else stdout
    is_tty = getattr(out, "isatty", lambda: False)()
    return command not in QUIET_COMMANDS and not quiet and not is_tty


@contextmanager
def announce_compiling(stream: TextIO | None = None) -> Iterator[None]:
    """Within the block, print :data:`MESSAGE` to ``stream`` (stderr) when numba first
    compiles a function (a cache miss), once."""
    from numba.core import event

    class _Announce(event.Listener):
        said = False

        def on_start(self, ev: Any) -> None:
            if not self.said:
                self.said = True
                print(MESSAGE, file=sys.stderr if stream is None else stream, flush=True)

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", _Announce()):
        yield
