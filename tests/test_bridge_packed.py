"""Protocol 3's packed records (seamtrack/bridge/packed.py) against protocol 2's JSON, an
independent encoding of the same messages: a step read back from its records holds what its
JSON holds, the points the same bytes; a command packed by the example client (struct alone)
is the command the JSON path reads; a bad record is refused naming what is wrong."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from seamtrack.bridge import example_client, packed, wire
from seamtrack.bridge.lockstep import BridgeFailure, Frame, Step
from seamtrack.sensing.profiles import Feature, Profile


def _step(found: bool = True) -> Step:
    rng = np.random.default_rng(3)
    points = rng.normal(size=(64, 2))
    points[5] = np.nan
    reason = np.zeros(64, np.uint8)
    reason[5] = 2
    profile = Profile(points_laser=points, valid=reason == 0, reason=reason)
    feature = (
        Feature(point_laser=np.array([0.5, 1.0]), point_world=np.array([1.5, -2.0, 3.25]))
        if found
        else Feature.failed("none")
    )
    T = np.arange(16.0).reshape(4, 4) / 7.0
    frames = [
        Frame(0.1, 0.11, feature, T, np.array([1.0, 2.0, 3.0]), profile),
        Frame(0.2, 0.21, Feature.failed("none"), T, np.array([1.5, 2.0, 3.0]), None),
    ]
    return Step(42, 0.125, np.array([1.0, 2.0, 3.0]), np.array([5.0, 0.0, -1.0]), frames, 2)


@pytest.mark.parametrize("found", [True, False])
def test_a_packed_step_holds_what_its_json_holds(found: bool) -> None:
    step = _step(found)
    json_parts = wire.step_parts(step, with_profile=True)
    header = json.loads(json_parts[0])
    got = packed.read_step([bytes(p) for p in packed.StepEncoder().parts(step, True)])
    for key in ("seq", "then_taken", "t_s", "tcp_mm", "tcp_velocity_mm_s"):
        assert list(np.atleast_1d(got[key])) == list(np.atleast_1d(header[key])), key
    assert len(got["frames"]) == len(header["frames"]) == 2
    for k, (a, b) in enumerate(zip(got["frames"], header["frames"], strict=True)):
        assert a["found"] == b["found"] and a["t_capture_s"] == b["t_capture_s"]
        assert list(a["T_world_sensor"]) == [v for row in b["T_world_sensor"] for v in row]
        if b["point_mm"] is None:
            assert all(math.isnan(v) for v in a["point_mm"])
        else:
            assert list(a["point_mm"]) == b["point_mm"]
        arrays = wire.profile_arrays(header, json_parts, k)
        if arrays is None:
            assert a["profile"] is None
        else:
            assert a["profile"][0].tobytes() == arrays[0].tobytes()
            assert a["profile"][1].tobytes() == arrays[1].tobytes()
    # a tick without a frame is the step's record alone
    tick = Step(1, 0.001, np.zeros(3), np.zeros(3))
    assert [len(p) for p in packed.StepEncoder().parts(tick, True)] == [packed.STEP.size] == [68]


def test_the_example_clients_packed_command_is_the_json_command() -> None:
    move = {"target_mm": [1.0, 2.5, -3.0], "speed_mm_s": 5.0, "stop_at_target": False}
    command = {**move, "ask_within_mm": 1.0, "then": [{**move, "stop_at_target": True}]}
    raw = example_client.command_bytes(9, command)
    (c3, w3), then3, hint = packed.decode_command(raw, 9)
    message = {"op": "command", "seq": 9, "command": command}
    (c2, w2), then2 = wire.commands_from_json(message, 9)
    assert hint is False and w3 == w2 == 1.0 and len(then3) == len(then2) == 1
    for a, b in ((c3, c2), (then3[0][0], then2[0][0])):
        assert a is not None and b is not None
        assert a.target_world.tolist() == b.target_world.tolist()
        assert (a.speed_mm_s, a.stop_at_target) == (b.speed_mm_s, b.stop_at_target)
    assert packed.decode_command(example_client.command_bytes(9, None), 9)[0] == (None, 0.0)
    hinted = packed.encode_command(9, [move], ((0.0, 0.0, 0.0), (0.0, 3.0, 4.0), (1.5, 0.4)))
    assert packed.decode_command(hinted, 9)[2] == ((0.0, 0.0, 0.0), (0.0, 0.6, 0.8), (1.5, 0.4))


@pytest.mark.parametrize(
    ("raw", "what"),
    [
        (b'{"op": "command"}', "not a protocol-3 command"),
        (packed.encode_command(8, None), "answers step 8"),
        (packed.encode_command(9, [{"target_mm": [0, math.nan, 0], "speed_mm_s": 5}]), "finite"),
        (packed.encode_command(9, [{"target_mm": [0, 0, 0], "speed_mm_s": 0}]), "speed_mm_s"),
        (packed.encode_command(9, [{"target_mm": [0, 0, 0], "speed_mm_s": 5}])[:-8], "bytes"),
    ],
)
def test_a_bad_packed_command_is_refused(raw: bytes, what: str) -> None:
    with pytest.raises(BridgeFailure, match=what):
        packed.decode_command(raw, 9)


def test_a_move_the_same_to_the_byte_is_taken_again_and_a_changed_one_read() -> None:
    known: dict = {}
    a = {"target_mm": [1.0, 2.0, 3.0], "speed_mm_s": 5.0, "stop_at_target": False}
    b = {**a, "target_mm": [1.0, 2.0, 3.5]}
    first = packed.decode_command(packed.encode_command(1, [a, b]), 1, known)
    again = packed.decode_command(packed.encode_command(2, [b]), 2, known)
    assert again[0] is first[1][0]  # b, sent again: the same command
    other = packed.decode_command(packed.encode_command(3, [a]), 3, known)
    assert other[0] is not first[0]  # a was not in the last message: read anew
    assert other[0][0] is not None and other[0][0].target_world.tolist() == [1.0, 2.0, 3.0]


def test_a_command_the_same_but_for_its_seq_is_the_same_answer_and_still_checked() -> None:
    """CommandReader: the message of the last step again, with this step's seq, is the same
    answer (not read again); with a wrong seq it is refused as any message is; a changed one
    is read anew."""
    reader = packed.CommandReader()
    a = {"target_mm": [1.0, 2.0, 3.0], "speed_mm_s": 5.0, "stop_at_target": False}
    first = reader.read(packed.encode_command(1, [a]), 1)
    assert reader.read(packed.encode_command(2, [a]), 2) is first
    with pytest.raises(BridgeFailure, match="answers step 2 where step 3 was due"):
        reader.read(packed.encode_command(2, [a]), 3)
    moved = reader.read(packed.encode_command(3, [{**a, "speed_mm_s": 6.0}]), 3)
    assert moved is not first and moved[0][0] is not None and moved[0][0].speed_mm_s == 6.0
    assert reader.read(packed.encode_command(4, None), 4)[0] == (None, 0.0)


def test_the_example_client_packs_a_command_once_while_it_holds() -> None:
    """The example client's algorithm II returns the same command object while its points
    hold (so it is packed once), a new one when the oldest point is reached; head + moves
    is the whole command."""
    tracker = example_client.ConvergenceRadius(5.0, radius_mm=1.0, then=2)
    for x in (0.0, 2.0, 4.0, 6.0):
        tracker.update([x, 0.0, 0.0])
    first = tracker.step([-3.0, 0.0, 0.0])
    assert first is not None and [m["target_mm"][0] for m in first["then"]] == [2.0, 4.0]
    tracker.update([8.0, 0.0, 0.0])  # beyond the moves sent: the same command
    assert tracker.step([-2.0, 0.0, 0.0]) is first
    switched = tracker.step([-0.5, 0.0, 0.0])  # within the radius of the oldest
    assert switched is not first and switched is not None
    assert switched["target_mm"] == [2.0, 0.0, 0.0]
    raw = example_client.command_bytes(7, switched)
    assert raw == example_client.command_head(7, switched) + example_client.moves_bytes(switched)
    assert len(raw) == packed.COMMAND.size + 3 * packed.MOVE.size
