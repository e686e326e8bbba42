"""The ZeroMQ transport: a REP socket (the server) and one REQ client; JSON messages, the
steps' profiles as raw arrays in further parts of a multipart message
(:mod:`seamtrack.bridge.wire` gives the format). The client speaks first: ``hello`` ->
``reset``, ``ready`` -> step 0, ``command`` -> step 1, ... -> ``end``.

By default the socket listens on the loopback interface, :data:`DEFAULT_ENDPOINT`;
``ipc:///PATH`` is a Unix domain socket (this machine only, and a shorter round trip than TCP
over loopback: ``seamtrack bench bridge`` has both rows), and ``tcp://HOST:PORT`` with another
interface serves a tracker on another machine.

Safety: the socket listens on this machine only unless told otherwise; ZeroMQ drops a peer
whose message is over :data:`HARD_LIMIT_BYTES` (no allocation for it), and a message over
:data:`~seamtrack.bridge.wire.MAX_MESSAGE_BYTES`, or of more than one part, is refused before
it is decoded; messages are parsed as JSON and checked field by field, never evaluated or
unpickled.
"""

from __future__ import annotations

import json
import math
import os
import socket
import stat
import time
from typing import Any

from seamtrack.bridge import wire
from seamtrack.bridge.lockstep import Answer, BridgeFailure, Step, TfChain
from seamtrack.control.tracking import TrackerContext

#: TCP on the loopback interface: a tracker on this machine connects to the same endpoint.
DEFAULT_ENDPOINT = "tcp://127.0.0.1:5555"

#: ZeroMQ disconnects a peer that sends more than this in one message.
HARD_LIMIT_BYTES = 65536


class ZmqTransport:
    """Serve one tracker process on ``endpoint`` (see the module docstring).

    Parameters
    ----------
    endpoint : str
        A ZeroMQ endpoint to bind (``tcp://127.0.0.1:5555``, ``ipc:///tmp/seamtrack-bridge``).
    timeout_s : float
        How long the client may take to answer one step.
    wait_s : float
        How long to wait for the client's ``hello``.
    """

    def __init__(
        self, endpoint: str = DEFAULT_ENDPOINT, timeout_s: float = 5.0, wait_s: float = 60.0
    ):
        import zmq

        self._zmq = zmq
        self.endpoint = endpoint
        self.timeout_s = timeout_s
        self.wait_s = wait_s
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.REP)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.MAXMSGSIZE, HARD_LIMIT_BYTES)
        self.monitor = self.sock.get_monitor_socket(zmq.EVENT_DISCONNECTED)
        try:
            taken = _taken(endpoint)  # ZeroMQ would remove what is on the path
            if taken:
                raise zmq.ZMQError(msg=taken)
            self.sock.bind(endpoint)
        except zmq.ZMQError as exc:
            self.close()
            raise BridgeFailure(
                f"cannot listen on {endpoint!r}: {exc}",
                field="--endpoint",
                fix="give a free ipc://PATH or tcp://HOST:PORT",
            ) from None
        self.poller = zmq.Poller()
        self.poller.register(self.sock, zmq.POLLIN)
        self.poller.register(self.monitor, zmq.POLLIN)
        self.with_profile = True
        self._connected = False
        #: The client's last seam hint (point_mm, direction, tolerance_mm), world frame.
        self.seam_hint: tuple[Any, ...] | None = None

    # ------------------------------------------------------------------ protocol
    def start(self, context: TrackerContext, chain: TfChain, lockstep: str) -> None:
        hello = wire.parse(self._recv(self.wait_s, "--wait-s", "say hello"))
        wire.expect(hello, "hello")
        if hello.get("protocol") != wire.PROTOCOL:
            raise BridgeFailure(
                f"speaks protocol {str(hello.get('protocol'))[:20]}, not {wire.PROTOCOL}",
                fix=f"send 'protocol': {wire.PROTOCOL} (docs/ros.md gives its messages)",
            )
        self.with_profile = hello.get("profile", True) is not False
        self._connected = True
        reset = {
            "op": "reset",
            "protocol": wire.PROTOCOL,
            "lockstep": lockstep,
            "context": wire.context_json(context),
            "max_message_bytes": wire.MAX_MESSAGE_BYTES,
        }
        self.sock.send(json.dumps(reset).encode())
        wire.expect(wire.parse(self._recv(self.timeout_s, "--timeout-s", "answer")), "ready")

    def exchange(self, step: Step) -> Answer:
        self.sock.send_multipart(wire.step_parts(step, self.with_profile))
        raw = self._recv(self.timeout_s, "--timeout-s", f"answer step {step.seq}")
        message = wire.parse(raw)
        (command, within), then = wire.commands_from_json(message, step.seq)
        if "seam_hint" in message:  # it holds until the client says another (or null)
            self.seam_hint = wire.seam_hint_from_json(message)
        return Answer(command, within, tuple(then), self.seam_hint)

    def finish(self, summary: dict[str, Any]) -> None:
        from seamtrack.io.output import json_safe

        try:
            end = {"op": "end", "summary": json_safe(summary)}
            self.sock.send(json.dumps(end).encode(), self._zmq.NOBLOCK)
        except self._zmq.ZMQError:
            pass

    def close(self) -> None:
        try:
            self.sock.disable_monitor()
        except Exception:  # already closed, or never bound
            pass
        self.monitor.close(0)
        self.sock.close(0)
        self.ctx.term()

    # ------------------------------------------------------------------ receiving
    def _recv(self, timeout_s: float, field: str, what: str) -> bytes:
        from zmq.utils.monitor import recv_monitor_message

        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BridgeFailure(
                    f"the client did not {what} within {timeout_s:g} s",
                    field=field,
                    fix="start the tracker process, or raise " + field,
                )
            ready = dict(self.poller.poll(max(1, math.ceil(left * 1000.0))))
            if self.sock in ready:
                parts = self.sock.recv_multipart(copy=True)
                if len(parts) != 1:
                    raise BridgeFailure(
                        f"sent a message of {len(parts)} parts",
                        fix="send each message as one part of UTF-8 JSON",
                    )
                return bytes(parts[0])
            if self.monitor in ready:
                recv_monitor_message(self.monitor)
                if self._connected:
                    raise BridgeFailure(
                        "the client disconnected (or sent a message over "
                        f"{HARD_LIMIT_BYTES} bytes)",
                        fix="keep the tracker process running until the 'end' message",
                    )


def _taken(endpoint: str) -> str:
    """Why an ``ipc://`` path is not free ("" when it is): ZeroMQ removes whatever is on the
    path it binds, so a file that is not a socket, or a socket a server listens on, is refused
    (a socket left by a server that is gone is taken)."""
    if not endpoint.startswith("ipc://"):
        return ""
    path = endpoint[len("ipc://") :]
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    if not stat.S_ISSOCK(mode):
        return "a file that is not a socket is there"
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        try:
            probe.connect(path)
        except OSError:
            return ""
    return "another server listens there"
