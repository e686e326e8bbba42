"""The bridge's protocol 3 over ZeroMQ: steps and commands as packed little-endian records,
no JSON on the per-step path (the hello, reset, ready, end and refusals stay JSON: once a run).

A **step** (server -> client) is a multipart message. Part 0 is the step's record,
:data:`STEP` (68 bytes: a tick without a frame is this alone), followed by one :data:`FRAME`
record (200 bytes) for each frame that arrived at it::

    STEP  "<4sIHHd3d3d": b"STP3", seq (u32), then_taken (u16), frames (u16), t_s,
                          tcp_mm (3), tcp_velocity_mm_s (3)
    FRAME "<ddB3xI3d16d3d": t_capture_s, t_arrival_s, flags (u8: 1 found, 2 profile sent),
                          n (u32, the profile's points), point_mm (3; NaN when not found),
                          T_world_sensor (16, row-major), tcp_mm (3)

Each frame with flag 2, in order, adds two parts: its n points (y_L, z_L), mm, as
little-endian float64, row-major (NaN where a ray hit nothing), ``16 n`` bytes; and its n
reason codes as uint8, ``n`` bytes (0: valid; :data:`seamtrack.bridge.messages.REASON_CODES`).
The points go out from the profile's own array (a memoryview: no copy on the way to ZeroMQ).

A **command** (client -> server) is one part: :data:`COMMAND` (12 bytes), then, when flag 1 is
set, ``1 + then`` :data:`MOVE` records (168 bytes each: the command and its ``then``), then,
when flag 2 is set, one :data:`HINT` record (64 bytes)::

    COMMAND "<4sIBB2x": b"CMD3", seq (u32, the step answered), flags (u8: 1 a command, else
                        brake to rest; 2 a seam hint follows; 4 the seam hint cleared),
                        then (u8, at most 16)
    MOVE    "<B7x3dd d3d9d3d": flags (u8: 1 stop_at_target, 2 velocity_ff, 4 rotation,
                        8 angular_velocity), target_mm (3), speed_mm_s, ask_within_mm,
                        velocity_ff_mm_s (3), rotation (9, row-major R_world_tcp),
                        angular_velocity_rad_s (3); the fields a flag leaves out are ignored
    HINT    "<3d3d2d":  point_mm (3), direction (3), tolerance_mm (across, range)

Every field is checked as the JSON protocol's are (finite, speed > 0, ``ask_within_mm`` >= 0,
a rotation matrix), and the record's length against its counts before it is read.
"""

from __future__ import annotations

import math
import struct
from typing import Any

import numpy as np

from seamtrack.bridge.lockstep import BridgeFailure, Reply, Step
from seamtrack.bridge.wire import MAX_THEN, make_command

STEP = struct.Struct("<4sIHHd3d3d")
FRAME = struct.Struct("<ddB3xI3d16d3d")
COMMAND = struct.Struct("<4sIBB2x")
MOVE = struct.Struct("<B7x3ddd3d9d3d")
HINT = struct.Struct("<3d3d2d")
STEP_MAGIC = b"STP3"
COMMAND_MAGIC = b"CMD3"

_NAN3 = (math.nan, math.nan, math.nan)

#: A command's seam hint: (point, unit direction, tolerance); None: cleared; False: not given.
Hint = tuple[Any, ...] | bool | None


class StepEncoder:
    """Packs steps into one reused buffer (grown when a step has more frames than any
    before)."""

    def __init__(self) -> None:
        self._buf = bytearray(STEP.size + 4 * FRAME.size)

    def parts(self, step: Step, with_profile: bool) -> list[Any]:
        """Part 0 (a memoryview of the reused buffer: send it before the next step is packed,
        as ZeroMQ's copying send does) and the profiles' parts (module docstring)."""
        frames = step.frames
        size = STEP.size + FRAME.size * len(frames)
        if len(self._buf) < size:
            self._buf = bytearray(size)
        buf = self._buf
        tx, ty, tz = np.asarray(step.tcp_world, dtype=float).tolist()
        vx, vy, vz = np.asarray(step.tcp_velocity_world, dtype=float).tolist()
        STEP.pack_into(
            buf, 0, STEP_MAGIC, step.seq, step.then_taken, len(frames), step.t_s,
            tx, ty, tz, vx, vy, vz,
        )  # fmt: skip
        parts: list[Any] = [memoryview(buf)[:size]]
        offset = STEP.size
        for f in frames:
            found = bool(f.feature)
            flags = 1 if found else 0
            n = 0
            if with_profile and f.profile is not None:
                assert f.profile.reason is not None
                points = np.ascontiguousarray(f.profile.points_laser, dtype="<f8")
                n = len(points)
                flags |= 2
                parts.append(points.data.cast("B"))
                parts.append(np.ascontiguousarray(f.profile.reason, dtype=np.uint8).data)
            point = np.asarray(f.feature.point_world, dtype=float).tolist() if found else _NAN3
            FRAME.pack_into(
                buf, offset, f.t_capture_s, f.t_arrival_s, flags, n, *point,
                *np.asarray(f.T_world_sensor, dtype=float).ravel().tolist(),
                *np.asarray(f.tcp_world, dtype=float).tolist(),
            )  # fmt: skip
            offset += FRAME.size
        return parts


def read_step(parts: list[bytes]) -> dict[str, Any]:
    """A step read back as a client reads it (sizes checked first): the format in code (the
    tests read steps with it). Profiles as ((n, 2) float64, (n,) uint8) arrays, or None."""
    head = parts[0]
    if len(head) < STEP.size or bytes(head[:4]) != STEP_MAGIC:
        raise ValueError("not a protocol-3 step")
    _, seq, taken, count, t_s, *rest = STEP.unpack_from(head)
    if len(head) != STEP.size + count * FRAME.size:
        raise ValueError(f"part 0 holds {len(head)} bytes, not a step of {count} frames")
    frames = []
    i = 1
    for k in range(count):
        tc, ta, flags, n, *v = FRAME.unpack_from(head, STEP.size + k * FRAME.size)
        profile = None
        if flags & 2:
            points, reason = parts[i], parts[i + 1]
            if len(points) != 16 * n or len(reason) != n:
                raise ValueError(f"frame {k}'s profile parts are not {n} points")
            profile = (np.frombuffer(points, "<f8").reshape(n, 2), np.frombuffer(reason, "u1"))
            i += 2
        frames.append(
            {"t_capture_s": tc, "t_arrival_s": ta, "found": bool(flags & 1),
             "point_mm": v[:3], "T_world_sensor": v[3:19], "tcp_mm": v[19:22],
             "profile": profile}
        )  # fmt: skip
    return {"seq": seq, "then_taken": taken, "t_s": t_s, "tcp_mm": rest[:3],
            "tcp_velocity_mm_s": rest[3:], "frames": frames}  # fmt: skip


def encode_command(
    seq: int,
    moves: list[dict[str, Any]] | None,
    seam_hint: Hint = False,
) -> bytes:
    """A command message: ``moves`` the command and its ``then`` (each a dict of the JSON
    command's keys; None: brake to rest), ``seam_hint`` (point, direction, tolerance), None to
    clear it, False to leave it as it is."""
    flags = 0 if moves is None else 1
    body = b""
    if moves is not None:
        body = b"".join(_move(m) for m in moves)
    if seam_hint is None:
        flags |= 4
    elif seam_hint is not False:
        flags |= 2
        point, direction, tolerance = seam_hint  # type: ignore[misc]
        body += HINT.pack(*point, *direction, *tolerance)
    then = 0 if moves is None else len(moves) - 1
    return COMMAND.pack(COMMAND_MAGIC, seq, flags, then) + body


def _move(m: dict[str, Any]) -> bytes:
    flags = 1 if m.get("stop_at_target") else 0
    ff, rot, omega = m.get("velocity_ff_mm_s"), m.get("rotation"), m.get("angular_velocity_rad_s")
    flags |= (2 if ff is not None else 0) | (4 if rot is not None else 0)
    flags |= 8 if omega is not None else 0
    rows = np.zeros(9) if rot is None else np.asarray(rot, dtype=float).ravel()
    return MOVE.pack(
        flags, *m["target_mm"], m["speed_mm_s"], m.get("ask_within_mm", 0.0),
        *(ff if ff is not None else (0.0, 0.0, 0.0)), *rows.tolist(),
        *(omega if omega is not None else (0.0, 0.0, 0.0)),
    )  # fmt: skip


def decode_command(
    raw: bytes, seq: int, known: dict[bytes, Reply] | None = None
) -> tuple[Reply, list[Reply], Hint]:
    """The command answering step ``seq``, its ``then``, and its seam hint (point, unit
    direction, tolerance; None: cleared; False: not given); every field checked. ``known``:
    the moves of the last message, by their record's bytes (a move the same to the byte is
    the same command: it is taken again, not read again); replaced by this message's."""
    if len(raw) < COMMAND.size or raw[:4] != COMMAND_MAGIC:
        raise _bad("is not a protocol-3 command (b'CMD3' ...)", "send the COMMAND record")
    _, got, flags, then = COMMAND.unpack_from(raw)
    if got != seq:
        raise _bad(f"answers step {got} where step {seq} was due", "echo the step's seq")
    if then > MAX_THEN or flags & ~7 or (flags & 6) == 6:
        raise _bad(f"has flags {flags} or a 'then' of {then} (at most {MAX_THEN})")
    moves = then + 1 if flags & 1 else 0
    size = COMMAND.size + moves * MOVE.size + (HINT.size if flags & 2 else 0)
    if len(raw) != size:
        raise _bad(f"holds {len(raw)} bytes where its counts give {size}")
    replies = [_move_at(raw, COMMAND.size + k * MOVE.size, known) for k in range(moves)]
    if known is not None:  # this message's moves are the ones known from now on
        known.clear()
        for k, reply in enumerate(replies):
            start = COMMAND.size + k * MOVE.size
            known[raw[start : start + MOVE.size]] = reply
    hint: Hint = None if flags & 4 else False
    if flags & 2:
        hint = _read_hint(raw, COMMAND.size + moves * MOVE.size)
    if not replies:
        return (None, 0.0), [], hint
    return replies[0], replies[1:], hint


class CommandReader:
    """:func:`decode_command` with a memory: a message the same to the byte as the last one
    but for its seq (a tracker that holds its command, tick after tick) is the same answer,
    returned again without being read again; any other is read and checked in full."""

    def __init__(self) -> None:
        self._known: dict[bytes, Reply] = {}
        self._body = b""  # the last message after its magic and seq
        self._answer: tuple[Reply, list[Reply], Hint] | None = None

    def read(self, raw: bytes, seq: int) -> tuple[Reply, list[Reply], Hint]:
        """The command answering step ``seq``, its ``then`` and its seam hint, as
        :func:`decode_command` gives them."""
        answer = self._answer
        if (
            answer is not None
            and raw[8:] == self._body
            and raw[:4] == COMMAND_MAGIC
            and _SEQ.unpack_from(raw, 4)[0] == seq
        ):
            return answer
        answer = decode_command(raw, seq, self._known)
        self._body, self._answer = raw[8:], answer
        return answer


_SEQ = struct.Struct("<I")


def _move_at(raw: bytes, offset: int, known: dict[bytes, Reply] | None) -> Reply:
    if known is None:
        return _read_move(raw, offset)
    record = raw[offset : offset + MOVE.size]
    reply = known.get(record)
    if reply is None:
        reply = _read_move(raw, offset)
    return reply


def _read_move(raw: bytes, offset: int) -> Reply:
    flags, *v = MOVE.unpack_from(raw, offset)
    if flags & ~15:
        raise _bad(f"has a move's flags {flags}")
    if not all(map(math.isfinite, v)):
        raise _bad("has a field that is not finite")
    speed, within = v[3], v[4]
    if not speed > 0:
        raise _bad("'speed_mm_s' is not a finite number > 0", "send no command to stop instead")
    if within < 0:
        raise _bad("'ask_within_mm' is negative")
    command = make_command(
        v[0:3],
        speed,
        bool(flags & 1),
        v[5:8] if flags & 2 else None,
        v[8:17] if flags & 4 else None,
        v[17:20] if flags & 8 else None,
    )
    return command, within


def _read_hint(raw: bytes, offset: int) -> tuple[Any, ...]:
    v = HINT.unpack_from(raw, offset)
    if not all(map(math.isfinite, v)):
        raise _bad("has a seam hint field that is not finite")
    direction = v[3:6]
    norm = math.sqrt(sum(d * d for d in direction))
    if not norm > 1e-9:
        raise _bad("'seam_hint' has a zero direction")
    if min(v[6:8]) <= 0:
        raise _bad("'seam_hint' tolerance_mm is not 2 numbers > 0")
    return tuple(v[0:3]), tuple(d / norm for d in direction), tuple(v[6:8])


def _bad(what: str, fix: str = "see protocol 3's records in docs/ros.md") -> BridgeFailure:
    return BridgeFailure(f"sent a bad command: {what}", fix=fix)
