"""Bad inputs for the lockstep bridge (``seamtrack serve``): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. A misbehaving tracker process is not bad input (it ends
a run that is written as stopped: tests/test_bridge.py); these are the command's own flags."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import Entry

FILES: dict[str, bytes] = {"short-token.txt": b"letmein\n"}
GENERATED: dict[str, Callable[[Path], None]] = {}


def _serve(*extra: str) -> tuple[str, ...]:
    return ("serve", "paper-corner", *extra, "--out", "OUT", "--wait-s", "1")


ENTRIES: tuple[Entry, ...] = (
    Entry("serve timeout zero", _serve("--timeout-s", "0"), field="--timeout-s"),
    Entry("serve timeout not a number", _serve("--timeout-s", "nan"), field="--timeout-s"),
    Entry("serve wait negative", ("serve", "paper-corner", "--wait-s", "-1"), field="--wait-s"),
    Entry(
        "serve zmq endpoint not an address",
        _serve("--endpoint", "tcp://no such host:5555"),
        field="--endpoint",
    ),
    Entry(
        "serve zmq endpoint unknown transport",
        _serve("--endpoint", "carrier-pigeon://127.0.0.1"),
        field="--endpoint",
    ),
    Entry(
        "serve zenoh endpoint not a locator",
        _serve("--transport", "zenoh", "--endpoint", "not a locator"),
        field="--endpoint",
    ),
    Entry("serve zenoh domain id negative", _serve("--domain-id", "-3"), field="--domain-id"),
    # issue 43: refused up front, naming the field (not blamed on the client later)
    Entry(
        "serve zmq endpoint port out of range",
        _serve("--endpoint", "tcp://127.0.0.1:99999"),
        field="--endpoint",
    ),
    Entry(
        "serve zmq endpoint beyond loopback without a token",
        _serve("--endpoint", "tcp://0.0.0.0:5555"),
        field="--endpoint",
    ),
    Entry(
        "serve token file missing",
        _serve("--endpoint", "tcp://0.0.0.0:5555", "--token-file", "no-such-token.txt"),
        field="--token-file",
    ),
    Entry(
        "serve token too short",
        _serve("--endpoint", "tcp://0.0.0.0:5555", "--token-file", "short-token.txt"),
        field="--token-file",
    ),
    Entry(
        "serve token file with zenoh",
        _serve("--transport", "zenoh", "--token-file", "short-token.txt"),
        field="--token-file",
    ),
    Entry(
        "serve zenoh endpoint port out of range",
        _serve("--transport", "zenoh", "--endpoint", "tcp/127.0.0.1:70000"),
        field="--endpoint",
    ),
)
