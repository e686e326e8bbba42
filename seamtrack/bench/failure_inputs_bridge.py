"""Bad inputs for the lockstep bridge (``seamtrack serve``): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. A misbehaving tracker process is not bad input (it ends
a run that is written as stopped: tests/test_bridge.py); these are the command's own flags."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import Entry

FILES: dict[str, bytes] = {}
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
)
