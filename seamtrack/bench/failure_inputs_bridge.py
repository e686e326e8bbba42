"""Bad inputs for the lockstep bridge (``seamtrack serve``): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. A misbehaving tracker process is not bad input (it ends
a run that is written as stopped: tests/test_bridge.py); these are the command's own flags."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import Entry

FILES: dict[str, bytes] = {"short-token.txt": b"letmein\n"}
GENERATED: dict[str, Callable[[Path], None]] = {}


def _serve(name: str, *extra: str) -> Entry:
    """``seamtrack serve paper-corner EXTRA...``, its error naming the last flag of ``extra``."""
    flag = [word for word in extra if word.startswith("--")][-1]
    args = ("serve", "paper-corner", *extra, "--out", "OUT", "--wait-s", "1")
    return Entry(name, args, field=flag)


ENTRIES: tuple[Entry, ...] = (
    _serve("serve timeout zero", "--timeout-s", "0"),
    _serve("serve timeout not a number", "--timeout-s", "nan"),
    Entry("serve wait negative", ("serve", "paper-corner", "--wait-s", "-1"), field="--wait-s"),
    _serve("serve zmq endpoint not an address", "--endpoint", "tcp://no such host:5555"),
    _serve("serve zmq endpoint unknown transport", "--endpoint", "carrier-pigeon://127.0.0.1"),
    _serve("serve zenoh endpoint not a locator",
           "--transport", "zenoh", "--endpoint", "not a locator"),
    _serve("serve zenoh domain id negative", "--domain-id", "-3"),
    # issue 43: refused up front, naming the field (not blamed on the client later)
    _serve("serve zmq endpoint port out of range", "--endpoint", "tcp://127.0.0.1:99999"),
    _serve("serve zmq endpoint beyond loopback without a token",
           "--endpoint", "tcp://0.0.0.0:5555"),
    _serve("serve token file missing",
           "--endpoint", "tcp://0.0.0.0:5555", "--token-file", "no-such-token.txt"),
    _serve("serve token too short",
           "--endpoint", "tcp://0.0.0.0:5555", "--token-file", "short-token.txt"),
    _serve("serve token file with zenoh",
           "--transport", "zenoh", "--token-file", "short-token.txt"),
    _serve("serve zenoh endpoint port out of range",
           "--transport", "zenoh", "--endpoint", "tcp/127.0.0.1:70000"),
)  # fmt: skip
