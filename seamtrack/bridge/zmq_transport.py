"""The ZeroMQ transport: a ROUTER socket (the server) serving one REQ (or DEALER) client; JSON
messages, or in protocol 3 steps and commands as packed records, the steps' profiles as raw
arrays in further parts of a multipart message (:mod:`seamtrack.bridge.wire` and
:mod:`seamtrack.bridge.packed` give the formats). The client speaks first: ``hello`` ->
``reset``, ``ready`` -> step 0, ``command`` -> step 1, ... -> ``end``.

By default the socket listens on the loopback interface, :data:`DEFAULT_ENDPOINT`;
``ipc:///PATH`` is a Unix domain socket (this machine only, and a shorter round trip than TCP
over loopback: ``seamtrack bench bridge`` has both rows), and ``tcp://HOST:PORT`` with another
interface serves a tracker on another machine: then only with a shared token
(:func:`check_endpoint`), which the client's ``hello`` carries.

One session, one peer: the first peer to say ``hello`` (with the token, when one is set) is
the session's client. The ROUTER socket names every peer (its routing id, and the file
descriptor its messages came in on), so whatever any other peer sends (a second client's
``hello``) is answered with an ``error`` message (``"status": "refused"``) and otherwise
ignored; and the socket's disconnect monitor ends the run only when that peer's own
connection goes (a port scan's connect and close, or a second client leaving, change
nothing). Every end of a session, a fault too, is told to the client: an ``end`` message with
the run's ``status`` and ``reason`` (:meth:`ZmqTransport.finish`).

Safety: the socket listens on this machine only unless told otherwise; ZeroMQ drops a peer
whose message is over :data:`HARD_LIMIT_BYTES` (no allocation for it), and a message over
:data:`~seamtrack.bridge.wire.MAX_MESSAGE_BYTES`, or of more than one part, is refused before
it is decoded; messages are parsed as JSON or unpacked as records and checked field by field,
never evaluated or unpickled.
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import math
import os
import re
import socket
import stat
import time
from pathlib import Path
from typing import Any

from seamtrack.bridge import packed, wire
from seamtrack.bridge.lockstep import Answer, BridgeFailure, Interrupted, Step, TfChain
from seamtrack.control.tracking import TrackerContext
from seamtrack.errors import SeamtrackError
from seamtrack.simulation.stop import StopRequest

#: TCP on the loopback interface: a tracker on this machine connects to the same endpoint.
DEFAULT_ENDPOINT = "tcp://127.0.0.1:5555"

#: ZeroMQ disconnects a peer that sends more than this in one message.
HARD_LIMIT_BYTES = 65536

#: How long a wait runs between two looks at the stop request (a signal's flag).
POLL_SLICE_S = 0.05

#: How long closing waits for the last message (``end``, a refusal) to leave.
LINGER_MS = 500

#: How long the end of a run waits for the answer the client still owes (a step's, after its
#: deadline), to send the ``end`` in reply: a REQ socket takes no message before it has sent.
END_GRACE_S = 1.0

#: The shortest shared token taken (characters).
MIN_TOKEN_CHARS = 16


def check_endpoint(endpoint: str, token: str | None = None) -> None:
    """Refuse an endpoint that cannot be bound, before anything runs: a TCP port outside
    1-65535 (or ``*``: any free one), a transport ZeroMQ has no such name for, and an interface
    other than loopback without a shared token (anyone who reaches the port could drive the
    torch). Raises :class:`SeamtrackError` naming ``--endpoint``."""
    scheme, sep, rest = endpoint.partition("://")
    fix = "give tcp://127.0.0.1:PORT (PORT 1-65535) or ipc:///PATH"
    if not sep or scheme not in ("tcp", "ipc"):
        raise SeamtrackError(f"{endpoint[:80]!r} is not tcp://HOST:PORT nor ipc:///PATH",
                             field="--endpoint", fix=fix)  # fmt: skip
    if scheme == "ipc":
        return
    host, colon, port = rest.rpartition(":")
    if not colon or not host:
        raise SeamtrackError(f"{endpoint[:80]!r} has no HOST:PORT", field="--endpoint", fix=fix)
    if not re.fullmatch(r"[A-Za-z0-9._*:\[\]-]+", host):
        raise SeamtrackError(
            f"host {host[:40]!r} of {endpoint[:80]!r} is not an address",
            field="--endpoint",
            fix=fix,
        )
    if port != "*" and not (port.isdigit() and 1 <= int(port) <= 65535):
        raise SeamtrackError(
            f"port {port[:20]!r} of {endpoint[:80]!r} is not 1-65535", field="--endpoint", fix=fix
        )
    if not is_loopback(host) and token is None:
        raise SeamtrackError(
            f"{endpoint[:80]!r} listens beyond this machine without a token",
            field="--endpoint",
            fix="give --token-file FILE (a shared secret the client's hello carries, "
            "docs/ros.md), or listen on 127.0.0.1",
        )


def is_loopback(host: str) -> bool:
    """Is ``host`` (a ZeroMQ TCP endpoint's host: an address, a name, ``*``) this machine
    only? ``localhost`` is; ``*``, ``0.0.0.0`` and other names are not."""
    host = host.strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def read_token(path: str) -> str:
    """The shared token in the file ``path`` (surrounding blanks dropped), checked."""
    try:
        text = Path(path).read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError) as exc:
        raise SeamtrackError(
            f"cannot read {path!r}: {exc.__class__.__name__}",
            field="--token-file",
            fix="give a UTF-8 text file holding the shared token",
        ) from None
    if len(text) < MIN_TOKEN_CHARS or any(c.isspace() for c in text):
        raise SeamtrackError(
            f"the token in {path!r} is {len(text)} characters (or holds blanks)",
            field="--token-file",
            fix=f"put one word of at least {MIN_TOKEN_CHARS} random characters in it, e.g. "
            "python -c 'import secrets; print(secrets.token_urlsafe(24))' > FILE",
        )
    return text


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
    token : str, optional
        A shared secret the client's ``hello`` must carry (``"token"``); a peer without it is
        refused, and the bridge waits on for its client.
    """

    def __init__(
        self,
        endpoint: str = DEFAULT_ENDPOINT,
        timeout_s: float = 5.0,
        wait_s: float = 60.0,
        token: str | None = None,
    ):
        import zmq

        self._zmq = zmq
        self._bound = ""
        self.told = False  # the client was sent its end (or refusal)
        self.owed = False  # the client owes an answer to what was sent last
        self.refused = 0  # messages of other peers refused
        self.endpoint = endpoint
        self.timeout_s = timeout_s
        self.wait_s = wait_s
        self.token = token
        self.stop = StopRequest()
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.ROUTER)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.MAXMSGSIZE, HARD_LIMIT_BYTES)
        self.monitor = self.sock.get_monitor_socket(zmq.EVENT_DISCONNECTED)
        try:
            taken = _taken(endpoint)  # ZeroMQ would remove what is on the path
            if taken:
                raise zmq.ZMQError(msg=taken)
            self.sock.bind(endpoint)
            self._bound = endpoint
        except zmq.ZMQError as exc:
            self.close()
            raise BridgeFailure(
                f"cannot listen on {endpoint!r}: {exc}",
                field="--endpoint",
                fix="give a free ipc://PATH or tcp://HOST:PORT",
            ) from None
        if endpoint.endswith(":*"):  # the port ZeroMQ chose
            self.endpoint = self.sock.getsockopt_string(zmq.LAST_ENDPOINT)
        self.poller = zmq.Poller()
        self.poller.register(self.sock, zmq.POLLIN)
        self.poller.register(self.monitor, zmq.POLLIN)
        self.with_profile = True
        self.packed = False  # protocol 3: packed steps and commands
        # zmq's flags as plain ints, looked up once (an enum's | costs microseconds a step)
        self._srcfd = int(zmq.SRCFD)
        self._noblock, self._more = int(zmq.NOBLOCK), int(zmq.NOBLOCK | zmq.SNDMORE)
        from zmq.utils.monitor import recv_monitor_message

        self._monitor_message = recv_monitor_message
        self.encoder = packed.StepEncoder()
        self.reader = packed.CommandReader()  # the last command, by its bytes
        #: The session's client: its routing envelope (id, and the empty delimiter a REQ
        #: socket puts) and the file descriptor of its connection; None before its hello.
        self.peer: list[bytes] | None = None
        self.peer_fd = -1
        #: The client's last seam hint (point_mm, direction, tolerance_mm), world frame.
        self.seam_hint: tuple[Any, ...] | None = None

    # ------------------------------------------------------------------ protocol
    def start(self, context: TrackerContext, chain: TfChain, lockstep: str) -> None:
        deadline = time.monotonic() + self.wait_s
        while self.peer is None:
            envelope, fd, parts = self._next(deadline, self.wait_s, "--wait-s", "say hello")
            self.peer, self.peer_fd = envelope, fd  # this peer is answered from now on
            hello = wire.parse(_one_part(parts))
            wire.expect(hello, "hello")
            if self.token is not None and not _same_token(hello.get("token"), self.token):
                self._refuse(envelope, "no token, or not the server's (docs/ros.md)")
                self.peer, self.peer_fd = None, -1  # a stranger: wait on for the client
                continue
            if hello.get("protocol") not in wire.PROTOCOLS:
                failure = BridgeFailure(
                    f"speaks protocol {str(hello.get('protocol'))[:20]}, not 2 or 3",
                    fix="send 'protocol': 3 (packed records) or 'protocol': 2 (JSON) "
                    "(docs/ros.md gives their messages)",
                )
                self._refuse(envelope, f"{failure.message}; fix: {failure.fix}")
                self.told = True
                raise failure
        self.with_profile = hello.get("profile", True) is not False
        self.packed = hello.get("protocol") == 3
        reset = {
            "op": "reset",
            "protocol": hello.get("protocol"),
            "lockstep": lockstep,
            "context": wire.context_json(context),
            "max_message_bytes": wire.MAX_MESSAGE_BYTES,
        }
        self._send([json.dumps(reset).encode()])
        raw = self._recv(self.timeout_s, "--timeout-s", "answer")
        wire.expect(wire.parse(raw), "ready")

    def exchange(self, step: Step) -> Answer:
        if self.packed:
            return self._exchange_packed(step)
        self._send(wire.step_parts(step, self.with_profile))
        raw = self._recv(self.timeout_s, "--timeout-s", f"answer step {step.seq}")
        message = wire.parse(raw)
        (command, within), then = wire.commands_from_json(message, step.seq)
        if "seam_hint" in message:  # it holds until the client says another (or null)
            self.seam_hint = wire.seam_hint_from_json(message)
        return Answer(command, within, tuple(then), self.seam_hint)

    def _exchange_packed(self, step: Step) -> Answer:
        """Protocol 3: the step's packed records out (the profiles' points without a copy),
        the packed command in (:mod:`seamtrack.bridge.packed`)."""
        self._send(self.encoder.parts(step, self.with_profile), copy_after=1)
        raw = self._recv(self.timeout_s, "--timeout-s", f"answer step {step.seq}")
        if len(raw) > wire.MAX_MESSAGE_BYTES:
            wire.parse(raw)  # refused as oversized, as in protocol 2
        (command, within), then, hint = self.reader.read(raw, step.seq)
        if hint is not False:  # it holds until the client says another (or clears it)
            self.seam_hint = hint  # type: ignore[assignment]
        return Answer(command, within, tuple(then), self.seam_hint)

    def finish(self, summary: dict[str, Any]) -> None:
        """Send the client ``{"op": "end", "status", "reason", "summary"}``, whatever ended
        the run (a client that answers late finds it waiting: closing lingers for it)."""
        from seamtrack.io.output import json_safe

        if self.peer is None or self.told:
            return
        if self.owed:  # a late answer may still come: the end goes as its reply
            self._late_answer()
        end = {
            "op": "end",
            "status": summary.get("status"),
            "reason": summary.get("stop_reason"),
            "summary": json_safe(summary),
        }
        self._send([json.dumps(end).encode()])
        self.told = True

    def close(self) -> None:
        try:
            self.sock.disable_monitor()
        except Exception:  # already closed, or never bound
            pass
        self.monitor.close(0)
        self.sock.close(LINGER_MS if self.told or self.refused else 0)
        self.ctx.term()
        if self._bound.startswith("ipc://"):  # the socket file this server made: no leftover
            path = self._bound[len("ipc://") :]
            with contextlib.suppress(OSError):
                if stat.S_ISSOCK(os.stat(path).st_mode):
                    os.unlink(path)
        self._bound = ""

    # ------------------------------------------------------------------ sending, receiving
    def _late_answer(self) -> None:
        """Wait up to :data:`END_GRACE_S` for the client's overdue message (dropped)."""
        deadline = time.monotonic() + END_GRACE_S
        while (left := deadline - time.monotonic()) > 0:
            if not self.sock.poll(max(1, math.ceil(left * 1000.0))):
                return
            frames = self.sock.recv_multipart()
            if frames[0] == self.peer[0]:  # type: ignore[index]
                return
            cut = 2 if len(frames) > 2 and frames[1] == b"" else 1
            self._refuse(frames[:cut], "this server serves another client; one at a time")

    def _send(self, parts: list[Any], copy_after: int = -1) -> None:
        """Send ``parts`` to the client; from part ``copy_after`` on (the profiles' arrays)
        without a copy of ours (ZeroMQ holds the buffer until it is sent); the parts before
        are copied, so their buffer may be reused at once."""
        assert self.peer is not None
        self.owed = True
        zmq = self._zmq
        try:
            if copy_after < 0:
                self.sock.send_multipart([*self.peer, *parts], zmq.NOBLOCK)
                return
            send, more = self.sock.send, self._more
            for part in self.peer:
                send(part, more)
            last = len(parts) - 1
            for i, part in enumerate(parts):
                send(part, more if i < last else self._noblock, copy=i < copy_after)
        except zmq.ZMQError:  # the client's queue is full, or it is gone
            pass

    def _refuse(self, envelope: list[bytes], reason: str) -> None:
        """Tell a peer that is not (or cannot be) the session's client why, and nothing more."""
        refusal = {"op": "error", "status": "refused", "reason": reason}
        try:
            self.sock.send_multipart([*envelope, json.dumps(refusal).encode()], self._zmq.NOBLOCK)
        except self._zmq.ZMQError:
            pass
        self.refused += 1

    def _recv(self, timeout_s: float, field: str, what: str) -> bytes:
        """The client's next message (one part); other peers' are refused on the way."""
        deadline = time.monotonic() + timeout_s
        while True:
            envelope, fd, parts = self._next(deadline, timeout_s, field, what)
            if envelope[0] != self.peer[0] or fd != self.peer_fd:  # type: ignore[index]
                self._refuse(envelope, "this server serves another client; one at a time")
                continue
            self.owed = False
            return _one_part(parts)

    def _next(
        self, deadline: float, timeout_s: float, field: str, what: str
    ) -> tuple[list[bytes], int, list[bytes]]:
        """The next message of any peer: its envelope, its connection's file descriptor and
        its parts. The session client's disconnection, the deadline and the stop request end
        the wait; other peers' connections coming and going do not."""
        while True:
            if self.stop.requested:
                raise Interrupted(self.stop.reason)
            left = deadline - time.monotonic()
            if left <= 0:
                raise BridgeFailure(
                    f"the client did not {what} within {timeout_s:g} s",
                    field=field,
                    fix="start the tracker process, or raise " + field,
                )
            slice_ms = max(1, math.ceil(min(left, POLL_SLICE_S) * 1000.0))
            ready = dict(self.poller.poll(slice_ms))
            if self.sock in ready:
                return self._take()
            if self.monitor in ready:
                event = self._monitor_message(self.monitor)
                if self.peer is not None and int(event["value"]) == self.peer_fd:
                    self.owed = False  # nobody to answer
                    raise BridgeFailure(
                        "the client disconnected (or sent a message over "
                        f"{HARD_LIMIT_BYTES} bytes)",
                        fix="keep the tracker process running until the 'end' message",
                    )

    def _take(self) -> tuple[list[bytes], int, list[bytes]]:
        """The message the poll said is there (ZeroMQ delivers a message's parts together):
        its envelope, the file descriptor of the connection it came on, its parts. The
        routing id is taken as bytes, the rest as frames (one call each, no socket option
        read: RCVMORE comes with the frame), the descriptor from the last."""
        recv, noblock = self.sock.recv, self._noblock
        parts = [recv(noblock)]  # the routing id ROUTER puts first
        while True:
            frame = recv(noblock, copy=False)
            parts.append(frame.bytes)
            if not frame.more:
                break
        fd = int(frame.get(self._srcfd))
        cut = 2 if len(parts) > 2 and parts[1] == b"" else 1  # REQ: id, b"", ...
        return parts[:cut], fd, parts[cut:]


def _one_part(parts: list[bytes]) -> bytes:
    if len(parts) != 1:
        raise BridgeFailure(
            f"sent a message of {len(parts)} parts",
            fix="send each message as one part of UTF-8 JSON",
        )
    return parts[0]


def _same_token(given: Any, token: str) -> bool:
    """Compared in constant time (no timing tells how much of it was right)."""
    return isinstance(given, str) and hmac.compare_digest(given.encode(), token.encode())


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
