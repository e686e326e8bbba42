"""The bridge's messages over ZeroMQ in protocol 2 (JSON, and the profiles as raw arrays; the
hello, reset, ready, end and refusals of protocol 3 too, whose steps and commands are packed
records: :mod:`seamtrack.bridge.packed`), and the command check both transports share. Units
are the simulator's: mm, s, rad; poses are row-major 4 x 4
lists; in JSON a NaN is ``null``.

Client -> server (each message one ZeroMQ frame of UTF-8 JSON, at most
:data:`MAX_MESSAGE_BYTES`):

* ``{"op": "hello", "protocol": 2, "profile": true}`` (``profile``: send the stripe profiles;
  ``"token"``: the server's shared token, when it has one);
* ``{"op": "ready"}`` after the ``reset``;
* ``{"op": "command", "seq": k, "command": null | {...}}`` answering step ``k``. A command holds
  ``target_mm`` (x, y, z, required), ``speed_mm_s`` (> 0, required), and optionally
  ``stop_at_target`` (bool, arrive at rest), ``velocity_ff_mm_s`` (x, y, z),
  ``rotation`` (3 x 3 rows, the tool orientation goal ``R_world_tcp``) and
  ``angular_velocity_rad_s`` (x, y, z), ``ask_within_mm`` (with frame lockstep: ask again
  as soon as the torch is within this distance of the target, not only at the next frame),
  and ``then`` (with frame lockstep: the commands that follow, at most :data:`MAX_THEN`, each
  of these keys but ``then``: when the torch comes within ``ask_within_mm`` of the target, the
  next of them takes over at that tick without a round trip; the step after says how many
  took over, ``then_taken``; once they are used up, ``ask_within_mm`` asks again). ``null``
  brakes to rest and waits. Optionally, beside ``command``, a ``"seam_hint"``:
  ``{"point_mm": [x, y, z], "direction": [dx, dy, dz]}`` (world; and
  ``"tolerance_mm": [across, range]``), where the tracker expects the seam and where it heads:
  from then on each frame's extractor is told where that line crosses the laser plane (a
  :class:`~seamtrack.sensing.profiles.SeamHint`, as an in-process tracker's ``hint`` gives
  it), until a ``"seam_hint": null``. No other key.

Server -> client:

* ``{"op": "reset", "protocol": 2, "lockstep": "tick" | "frame", "context": {...},
  "max_message_bytes": n}``;
* a step: a multipart message. Part 0 is JSON ``{"op": "step", "seq": k, "t_s": t, "tcp_mm":
  [...], "tcp_velocity_mm_s": [...], "then_taken": n, "frames": [...]}`` (``then_taken``: how
  many of the last command's ``then`` took over since the last step), each frame ``{"t_capture_s",
  "t_arrival_s", "found", "point_mm" (or null), "T_world_sensor", "tcp_mm", "profile"}``.
  A frame's ``profile`` is null (none, or the client said ``"profile": false``) or
  ``{"points": {"part": i, "dtype": "<f8", "shape": [n, 2]}, "reason": {"part": i + 1,
  "dtype": "|u1", "shape": [n]}}``: part ``i`` holds the n points (y_L, z_L) in mm as raw
  little-endian float64, row-major (NaN where a ray hit nothing), part ``i + 1`` the n
  reason codes as uint8 (0: valid; :data:`seamtrack.bridge.messages.REASON_CODES`). A part's
  length is the product of its shape times the dtype's size: check it before reading;
* ``{"op": "end", "status": s, "reason": r, "summary": {...}}`` once the run is over,
  whatever ended it (``reason``: the summary's ``stop_reason``; no answer expected);
* ``{"op": "error", "status": "refused", "reason": r}`` to a peer that is refused: a hello of
  another protocol or without the token, any message of a peer other than the session's.

Protocol 1 sent the profiles as JSON lists (some 50 kB and milliseconds a frame); a client
saying protocol 1 is refused, the refusal (and the error) naming protocols 2 and 3.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from seamtrack.bridge.lockstep import BridgeFailure, Reply, Step, finite_vector
from seamtrack.control.tracking import Command, TrackerContext
from seamtrack.sensing.profiles import HINT_TOLERANCE_MM

PROTOCOL = 3

#: The protocols served: 3 (steps and commands as packed records,
#: :mod:`seamtrack.bridge.packed`) and 2 (JSON steps and commands, as below).
PROTOCOLS = (2, 3)

#: The largest message a client may send: a command is a few hundred bytes.
MAX_MESSAGE_BYTES = 4096

#: The most commands a command's ``then`` holds.
MAX_THEN = 16

_COMMAND_KEYS = {
    "ask_within_mm",
    "target_mm",
    "speed_mm_s",
    "stop_at_target",
    "velocity_ff_mm_s",
    "rotation",
    "angular_velocity_rad_s",
}


def context_json(context: TrackerContext) -> dict[str, Any]:
    return {
        "welding_speed_mm_s": context.welding_speed_mm_s,
        "control_period_s": context.control_period_s,
        "frame_period_s": context.frame_period_s,
        "latency_s": context.latency_s,
        "look_ahead_mm": context.look_ahead_mm,
        "sensor_resolution_mm": context.sensor_resolution_mm,
        "tcp_start_mm": np.asarray(context.tcp_start_world, dtype=float).tolist(),
        "velocity_max_mm_s": np.asarray(context.velocity_max_world, dtype=float).tolist(),
        "acceleration_max_mm_s2": np.asarray(context.acceleration_max_world, dtype=float).tolist(),
        "turns_tool": bool(context.turns_tool),
    }


def step_parts(step: Step, with_profile: bool) -> list[bytes]:
    """A step as the parts of one ZeroMQ multipart message (module docstring): the JSON
    header, then each sent profile's points and reasons as raw little-endian arrays.

    The header is written from a template (the bytes ``json.dumps`` gives, NaN as null): this
    runs once a step, on the bridge's critical path."""
    frames = []
    parts: list[bytes] = [b""]
    for f in step.frames:
        found = bool(f.feature)
        profile = "null"
        if with_profile and f.profile is not None:
            assert f.profile.reason is not None
            points = np.ascontiguousarray(f.profile.points_laser, dtype="<f8")
            n = len(points)
            i = len(parts)
            profile = _PROFILE % (i, n, i + 1, n)
            parts.append(points.tobytes())
            parts.append(np.ascontiguousarray(f.profile.reason, dtype=np.uint8).tobytes())
        T = np.asarray(f.T_world_sensor, dtype=float).tolist()
        frames.append(
            _FRAME
            % (
                _number(f.t_capture_s),
                _number(f.t_arrival_s),
                "true" if found else "false",
                _list(np.asarray(f.feature.point_world).tolist()) if found else "null",
                ", ".join(_list(row) for row in T),
                _list(np.asarray(f.tcp_world, dtype=float).tolist()),
                profile,
            )
        )
    parts[0] = (
        _STEP
        % (
            step.seq,
            _number(step.t_s),
            _list(np.asarray(step.tcp_world, dtype=float).tolist()),
            _list(np.asarray(step.tcp_velocity_world, dtype=float).tolist()),
            step.then_taken,
            ", ".join(frames),
        )
    ).encode()
    return parts


_STEP = (
    '{"op": "step", "seq": %d, "t_s": %s, "tcp_mm": %s, "tcp_velocity_mm_s": %s, '
    '"then_taken": %d, "frames": [%s]}'
)
_FRAME = (
    '{"t_capture_s": %s, "t_arrival_s": %s, "found": %s, "point_mm": %s, '
    '"T_world_sensor": [%s], "tcp_mm": %s, "profile": %s}'
)
_PROFILE = (
    '{"points": {"part": %d, "dtype": "<f8", "shape": [%d, 2]}, '
    '"reason": {"part": %d, "dtype": "|u1", "shape": [%d]}}'
)


def _number(value: float) -> str:
    """A float as JSON writes it (``repr``), NaN as null."""
    text = repr(float(value))
    if "n" in text:  # a NaN or an infinity
        return "null" if value != value else json.dumps(float(value))
    return text


def _list(values: list[float]) -> str:
    """A list of floats as JSON writes it, NaN as null."""
    text = ", ".join(map(repr, values))  # json.dumps's float form, for finite floats
    if "n" in text:  # a NaN or an infinity
        text = ", ".join(map(_number, values))
    return "[" + text + "]"


def profile_arrays(
    header: dict[str, Any], parts: list[bytes], frame: int
) -> tuple[Any, Any] | None:
    """A step's frame's profile as ((n, 2) float64 points in mm, (n,) uint8 reasons), read
    from the parts of its message as a client does (sizes checked first); None when the
    frame has none: the format in code (tests/test_bridge_rmw.py reads steps with it)."""
    profile = header["frames"][frame]["profile"]
    if profile is None:
        return None
    out = []
    for name in ("points", "reason"):
        d = profile[name]
        dtype = np.dtype(d["dtype"])
        count = int(np.prod(d["shape"]))
        raw = parts[d["part"]]
        if len(raw) != count * dtype.itemsize:
            raise ValueError(f"part {d['part']} holds {len(raw)} bytes, not {count} x {dtype}")
        out.append(np.frombuffer(raw, dtype=dtype).reshape(d["shape"]))
    return out[0], out[1]


def parse(raw: bytes, limit: int = MAX_MESSAGE_BYTES) -> dict[str, Any]:
    """A client message as a JSON object, refused when oversized or not JSON."""
    if len(raw) > limit:
        raise BridgeFailure(
            f"a message of {len(raw)} bytes is over the {limit}-byte limit",
            fix="send one command per step (a few hundred bytes)",
        )
    try:
        message = json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError) as exc:
        raise BridgeFailure(
            f"sent what is not JSON ({exc.__class__.__name__})",
            fix="send UTF-8 JSON objects as docs/ros.md gives them",
        ) from None
    if not isinstance(message, dict) or not isinstance(message.get("op"), str):
        raise BridgeFailure(
            "sent JSON that is not an object with an 'op'",
            fix="send {'op': 'command', 'seq': k, 'command': ...}",
        )
    return message


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not allowed")


def expect(message: dict[str, Any], op: str) -> None:
    if message["op"] != op:
        raise BridgeFailure(
            f"sent op {str(message['op'])[:40]!r} where {op!r} was due",
            fix=f"answer with {op!r} (docs/ros.md gives the order)",
        )


def command_from_json(message: dict[str, Any], seq: int) -> Reply:
    """The command answering step ``seq`` and its ``ask_within_mm`` (0 when not given);
    every field checked, nothing evaluated."""
    return commands_from_json(message, seq)[0]


def commands_from_json(message: dict[str, Any], seq: int) -> tuple[Reply, list[Reply]]:
    """:func:`command_from_json`, and the commands of its ``then`` (none when not given)."""
    expect(message, "command")
    if set(message) - {"op", "seq", "command", "seam_hint"}:
        raise _bad("has keys other than op, seq, command, seam_hint")
    got = message.get("seq")
    if isinstance(got, bool) or not isinstance(got, int) or got != seq:
        raise _bad(f"answers step {str(got)[:20]} where step {seq} was due", "echo the step's seq")
    body = message.get("command")
    if body is None:
        return (None, 0.0), []
    if not isinstance(body, dict):
        raise _bad("'command' is neither null nor an object")
    then = body.get("then", [])
    if not isinstance(then, list) or len(then) > MAX_THEN:
        raise _bad(f"'then' is not a list of at most {MAX_THEN} commands")
    if any(not isinstance(c, dict) or "then" in c for c in then):
        raise _bad("'then' holds what is not a command (or a command with its own 'then')")
    return _command_body({k: v for k, v in body.items() if k != "then"}), [
        _command_body(c) for c in then
    ]


def _command_body(body: dict[str, Any]) -> Reply:
    """One command object (no ``then``) checked field by field."""
    unknown = set(body) - _COMMAND_KEYS
    if unknown:
        raise _bad(f"unknown command key {sorted(unknown)[0][:40]!r}")
    target = finite_vector(body.get("target_mm"), 3)
    if target is None:
        raise _bad("'target_mm' is not 3 finite numbers")
    speed = body.get("speed_mm_s")
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not 0 < speed < math.inf:
        raise _bad("'speed_mm_s' is not a finite number > 0", "send null to stop instead")
    stop = body.get("stop_at_target", False)
    if not isinstance(stop, bool):
        raise _bad("'stop_at_target' is not true or false")
    within = _optional(body, "ask_within_mm", 1)
    if within is not None and within[0] < 0:
        raise _bad("'ask_within_mm' is negative")
    command = make_command(
        target,
        float(speed),
        stop,
        _optional(body, "velocity_ff_mm_s", 3),
        _optional(body, "rotation", 9),
        _optional(body, "angular_velocity_rad_s", 3),
    )
    return command, 0.0 if within is None else within[0]


def seam_hint_from_json(message: dict[str, Any]) -> tuple[Any, ...] | None:
    """A command message's ``seam_hint`` as (point_mm, unit direction, tolerance_mm), None
    when it has none (or ``null``); checked field by field."""
    body = message.get("seam_hint")
    if body is None:
        return None
    if not isinstance(body, dict) or set(body) - {"point_mm", "direction", "tolerance_mm"}:
        raise _bad("'seam_hint' is not an object of point_mm, direction (and tolerance_mm)")
    point = finite_vector(body.get("point_mm"), 3)
    direction = finite_vector(body.get("direction"), 3)
    if point is None or direction is None:
        raise _bad("'seam_hint' needs point_mm and direction, 3 finite numbers each")
    norm = math.sqrt(sum(d * d for d in direction))
    if not norm > 1e-9:
        raise _bad("'seam_hint' has a zero direction")
    tolerance = body.get("tolerance_mm", list(HINT_TOLERANCE_MM))
    checked = finite_vector(tolerance, 2)
    if checked is None or min(checked) <= 0:
        raise _bad("'seam_hint' tolerance_mm is not 2 numbers > 0")
    unit = tuple(d / norm for d in direction)
    return tuple(point), unit, tuple(checked)


def make_command(
    target: list[float],
    speed: float,
    stop: bool,
    ff: list[float] | None,
    rotation: list[float] | None,
    omega: list[float] | None,
) -> Command:
    rot = None
    if rotation is not None:
        rot = np.array(rotation, dtype=float).reshape(3, 3)
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-6) or np.linalg.det(rot) < 0:
            raise _bad("'rotation' is not a rotation matrix")
    return Command(
        np.array(target, dtype=float),
        speed,
        None if ff is None else np.array(ff, dtype=float),
        stop,
        rot,
        None if omega is None else np.array(omega, dtype=float),
    )


def _optional(body: dict[str, Any], key: str, n: int) -> list[float] | None:
    value = body.get(key)
    if value is None:
        return None
    if n == 1:
        value = [value]
    if key == "rotation" and isinstance(value, list) and all(isinstance(r, list) for r in value):
        value = [v for row in value for v in row] if len(value) == 3 else None
    checked = finite_vector(value, n)
    if checked is None:
        raise _bad(f"{key!r} is not {n} finite numbers")
    return checked


def _bad(what: str, fix: str = "see the command's fields in docs/ros.md") -> BridgeFailure:
    return BridgeFailure(f"sent a bad command: {what}", fix=fix)
