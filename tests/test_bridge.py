"""The lockstep bridge (``seamtrack serve``) against external trackers that import nothing of
seamtrack: tests/bridge_clients/zmq_algorithm2.py (pyzmq only) and zenoh_algorithm2.py (zenoh
and rosbags only, speaking rmw_zenoh's ROS 2 format). Both implement the paper's algorithm II;
the oracle is the same scene run in-process with seamtrack's own algorithm II: the same
trace.csv and frames.csv bytes, the same summary to 1e-9 mm (but its wall times).

Misbehaving clients (garbage, oversized, silent, gone) end the run with one error line and a
run folder written as for any stopped run. The key expressions, liveliness tokens and type
hashes are checked against the examples of rmw_zenoh's design document (docs/design.md).
"""

from __future__ import annotations

import json
import math
import shutil
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

pytest.importorskip("zmq")
pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

from seamtrack.cli.main import main

CLIENTS = Path(__file__).parent / "bridge_clients"

#: Short versions of the two scenes (a few seconds of simulated time), run with algorithm II.
SHORT = {
    "paper-corner": ["seam.points_mm=[[0, 0, 0], [12, 0, 0], [18, 6, 0]]"],
    "paper-v-groove": [
        "tracker.name=convergence-radius",
        "tracker.params={}",
        "sensor.rays=256",
        "simulation.time_limit_s=2.5",
    ],
}

#: Summary keys that are wall-clock timings, or only the bridge has.
BRIDGE_KEYS = {"bridge_steps", "bridge_exchange_s", "bridge_wait_s"}
TIMINGS = {"wall_time_s", "sense_wall_time_s", *BRIDGE_KEYS}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _sets(scene: str) -> list[str]:
    return [arg for value in SHORT[scene] for arg in ("--set", value)]


def _endpoint(transport: str) -> str:
    """ZeroMQ: a Unix socket on a path of its own (no race for a free port); Zenoh: a free port."""
    if transport == "zmq":
        return f"ipc://{tempfile.mkdtemp(prefix='seamtrack-test-')}/bridge"
    return f"tcp/127.0.0.1:{_free_port()}"


def _serve(
    scene: str,
    transport: str,
    out: Path,
    misbehave: str = "",
    timeout_s: float = 10.0,
    lockstep: str = "tick",
    client_args: tuple[str, ...] = (),
) -> tuple[subprocess.CompletedProcess, subprocess.CompletedProcess]:
    endpoint = _endpoint(transport)
    server = subprocess.Popen(
        [sys.executable, "-m", "seamtrack.cli", "serve", scene, *_sets(scene)]
        + ["--transport", transport, "--endpoint", endpoint, "--out", str(out)]
        + ["--lockstep", lockstep]
        + ["--no-plot", "-q", "--timeout-s", str(timeout_s), "--wait-s", "60"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    script = CLIENTS / f"{transport}_algorithm2.py"
    args = [sys.executable, str(script), endpoint, *client_args]
    if transport == "zmq" and not misbehave:  # the client that ships with seamtrack
        args = [sys.executable, "-m", "seamtrack.bridge.example_client", endpoint, *client_args]
    args += ["--misbehave", misbehave] if misbehave else []
    args += ["--deadline-s", str(timeout_s)] if misbehave and transport == "zmq" else []
    client = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        s_out, s_err = server.communicate(timeout=240)
    finally:
        if server.poll() is None:
            server.kill()
    try:
        c_out, c_err = client.communicate(timeout=5 if misbehave else 60)
    except subprocess.TimeoutExpired:
        client.kill()
        c_out, c_err = client.communicate()
    if endpoint.startswith("ipc://"):
        shutil.rmtree(Path(endpoint[len("ipc://") :]).parent, ignore_errors=True)
    return (
        subprocess.CompletedProcess(server.args, server.returncode, s_out, s_err),
        subprocess.CompletedProcess(client.args, client.returncode, c_out, c_err),
    )


@pytest.fixture(scope="module")
def in_process(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Each short scene run in-process with seamtrack's algorithm II."""
    runs = {}
    for scene in SHORT:
        out = tmp_path_factory.mktemp(scene)
        assert main(["run", scene, *_sets(scene), "--out", str(out), "--no-plot", "-q"]) == 0
        runs[scene] = out
    return runs


def _same_run(reference: Path, bridged: Path) -> None:
    for name in ("trace.csv", "frames.csv"):
        assert (bridged / name).read_bytes() == (reference / name).read_bytes(), name
    a = json.loads((reference / "summary.json").read_text())
    b = json.loads((bridged / "summary.json").read_text())
    assert set(b) - set(a) == BRIDGE_KEYS
    for key, value in a.items():
        if key in TIMINGS:
            continue
        if isinstance(value, float):
            assert b[key] == pytest.approx(value, abs=1e-9, nan_ok=True), key
        else:
            assert b[key] == value, key


@pytest.mark.parametrize("transport", ["zmq", "zenoh"])
@pytest.mark.parametrize("scene", list(SHORT))
def test_external_algorithm2_equals_in_process(
    scene: str, transport: str, in_process: dict[str, Path], tmp_path: Path
) -> None:
    out = tmp_path / "run"
    server, client = _serve(scene, transport, out)
    assert server.returncode == 0, server.stderr
    assert client.returncode == 0, client.stderr
    _same_run(in_process[scene], out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] > 2 and summary["bridge_steps"] > summary["frames"]
    if scene == "paper-corner":  # the corner is turned and welded to the end
        assert summary["status"] == "completed"
        assert math.isfinite(summary["max_error_mm"])


@pytest.mark.parametrize(
    ("transport", "then"), [("zmq", "2"), ("zmq", "0"), ("zenoh", "2"), ("zenoh", "0")]
)
def test_frame_lockstep_with_ask_within_is_exact_too(
    transport: str, then: str, in_process: dict[str, Path], tmp_path: Path
) -> None:
    """With one step per frame, plus a step whenever the torch comes within the client's
    ``ask_within`` (its radius) of the target, algorithm II still switches on the very tick:
    the same run, in a fraction of the round trips; and so it does when the bridge switches
    to the points the client sent ahead (ZeroMQ's ``then``, Zenoh's ``cmd_then``; ``--then
    0``: none sent)."""
    out = tmp_path / "run"
    args = ("--then", then) if then else ()
    server, client = _serve("paper-corner", transport, out, lockstep="frame", client_args=args)
    assert server.returncode == 0, server.stderr
    assert client.returncode == 0, client.stderr
    _same_run(in_process["paper-corner"], out)
    summary = json.loads((out / "summary.json").read_text())
    ticks = round(summary["sim_time_s"] / 0.001) + 1
    assert summary["frames"] <= summary["bridge_steps"] < ticks / 10


def test_every_frame_brings_its_profile_tf_and_clock_over_zenoh(
    in_process: dict[str, Path], tmp_path: Path
) -> None:
    """A ROS 2 subscriber gets, per sensor frame, one PointCloud2 stamped with the capture time
    (one point per ray: 256 here), one TFMessage with the chain world -> base -> tcp -> sensor,
    and a Clock at every step; a get on the keys of /seamtrack/context and /tf_static (what a
    late subscriber does) answers with the context sent and the links that do not move."""
    import numpy as np

    out = tmp_path / "run"
    server, client = _serve(
        "paper-v-groove", "zenoh", out, lockstep="frame", client_args=("--check-frames",)
    )
    assert server.returncode == 0, server.stderr
    _same_run(in_process["paper-v-groove"], out)
    seen = json.loads(client.stdout.strip().splitlines()[-1])
    frames = np.loadtxt(out / "frames.csv", delimiter=",", skiprows=1, ndmin=2)
    stamps = [sec + ns * 1e-9 for sec, ns, _ in seen["/seamtrack/profile"]]
    assert np.allclose(stamps, frames[:, 0], rtol=0, atol=1e-9)
    assert {width for *_, width in seen["/seamtrack/profile"]} == {256}
    chain = [["world", "base"], ["base", "tcp"], ["tcp", "sensor"]]
    assert seen["/tf"] == [chain] * len(frames)
    summary = json.loads((out / "summary.json").read_text())
    assert len(seen["/clock"]) == summary["bridge_steps"]
    assert seen["late_context"]  # the context is latched: asked for later, it comes again
    assert seen["late_tf_static"] == [[["world", "base"], ["tcp", "sensor"]]]


CAUSES = {
    ("zmq", "garbage"): "not JSON",
    ("zmq", "oversized"): "over the 4096-byte limit",
    ("zmq", "bad-command"): "'target_mm' is not 3 finite numbers",
    ("zmq", "silent"): "did not answer step 5 within 2 s",
    ("zmq", "vanish"): "disconnected",
    ("zmq", "multipart"): "sent a message of 2 parts",
    ("zenoh", "garbage"): "garbage on /seamtrack/cmd_pose",
    ("zenoh", "oversized"): "over the 4096-byte limit",
    ("zenoh", "silent"): "did not answer step 5 within 2 s",
    ("zenoh", "vanish"): "disconnected",
}


@pytest.mark.parametrize(("transport", "misbehave"), list(CAUSES))
def test_misbehaving_client_ends_the_run(transport: str, misbehave: str, tmp_path: Path) -> None:
    out = tmp_path / "run"
    server, client = _serve("paper-corner", transport, out, misbehave, timeout_s=2.0)
    assert server.returncode == 2
    lines = server.stderr.strip().splitlines()
    assert len(lines) == 1, server.stderr
    assert lines[0].startswith("seamtrack: error: ") and "; fix: " in lines[0]
    assert CAUSES[transport, misbehave] in lines[0]
    summary = json.loads((out / "summary.json").read_text())  # written as a stopped run
    assert summary["status"] == "stalled"
    assert CAUSES[transport, misbehave] in summary["stop_reason"]
    assert (out / "trace.csv").exists() and (out / "frames.csv").exists()
    assert not list(out.glob(".partial-*"))
    if transport == "zmq" and misbehave != "vanish":  # the client is told why, and how it ended
        told = json.loads(client.stdout.strip().splitlines()[-1])
        assert told is not None, client.stderr
        assert told["op"] == "end" and told["status"] == "stalled"
        assert CAUSES[transport, misbehave] in told["reason"]
        assert told["summary"]["stop_reason"] == summary["stop_reason"]


def test_every_frame_brings_its_profile_over_zmq(
    in_process: dict[str, Path], tmp_path: Path
) -> None:
    """The profiles reach a pyzmq-only client as the binary parts the step's JSON header
    describes, and read back (sizes checked, standard library only) they are the run's own
    profiles, bit for bit: the oracle is the same scene run in-process with an observer."""
    import numpy as np

    from seamtrack.bridge import frames as fr
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    out, dump = tmp_path / "run", tmp_path / "profiles.jsonl"
    server, client = _serve(
        "paper-v-groove", "zmq", out, lockstep="frame", client_args=("--dump-profiles", str(dump))
    )
    assert server.returncode == 0, server.stderr
    assert client.returncode == 0, client.stderr
    _same_run(in_process["paper-v-groove"], out)
    log = fr.FrameLog()
    run(fr.observe(build_parts(load_scene("paper-v-groove", SHORT["paper-v-groove"])), log))
    rows = [json.loads(line) for line in dump.read_text().splitlines()]
    assert len(rows) == len(log.frames) > 100
    for row, frame in zip(rows, log.frames, strict=True):
        assert row["t_capture_s"] == frame.t_s
        got = np.array(row["points"], dtype=float)  # None (NaN) -> nan
        np.testing.assert_array_equal(got, frame.profile.points_laser)
        assert row["reason"] == frame.profile.reason.tolist()
