"""One ``seamtrack serve`` session, one client, against real processes: strangers on the port
(a port scan's connect and close, a second client's ``hello``) change nothing in the run, a
signal ends it as ``interrupted`` with everything up to the stop written, and the client is
told every end. The oracle of "nothing changed" is the same scene run in-process with
seamtrack's own algorithm II (the same trace.csv and frames.csv bytes)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

zmq = pytest.importorskip("zmq")

from seamtrack.bridge.example_client import ConvergenceRadius  # noqa: E402
from seamtrack.cli.main import main  # noqa: E402
from seamtrack.control.tracking import TrackerContext  # noqa: E402

SEAM = ["--set", "seam.points_mm=[[0, 0, 0], [12, 0, 0], [18, 6, 0]]"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _server(endpoint: str, out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "seamtrack.cli", "serve", "paper-corner", *SEAM]
        + ["--endpoint", endpoint, "--out", str(out), "--wait-s", "60", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _port_scan(port: int) -> None:
    """What ``nc -z`` does: open a TCP connection to the port and close it, saying nothing."""
    with socket.create_connection(("127.0.0.1", port), timeout=5):
        pass


def test_a_port_scan_and_a_second_client_change_nothing(tmp_path: Path) -> None:
    """While the test's own client (algorithm II) tracks, a port scan at step 3, a second
    client's hello at step 5 (sent before the real client answers it) and that second client
    leaving at step 8: the second client is refused with an ``error`` message, the real
    client's run goes on and ends as the in-process run does, to the byte."""
    reference = tmp_path / "in-process"
    assert main(["run", "paper-corner", *SEAM, "--out", str(reference), "--no-plot", "-q"]) == 0
    port = _free_port()
    endpoint = f"tcp://127.0.0.1:{port}"
    out = tmp_path / "served"
    server = _server(endpoint, out, "-q", "--lockstep", "tick", "--no-plot")
    ctx = zmq.Context()
    real, stranger = ctx.socket(zmq.REQ), ctx.socket(zmq.REQ)
    for sock in (real, stranger):
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVTIMEO, 60000)
    refusal = None
    try:
        real.connect(endpoint)
        real.send_json({"op": "hello", "protocol": 2, "profile": False})
        reset = real.recv_json()
        tracker = ConvergenceRadius(reset["context"]["welding_speed_mm_s"], then=0)
        real.send_json({"op": "ready"})
        while True:
            msg = json.loads(real.recv_multipart()[0])
            if msg["op"] != "step":
                break
            for frame in msg["frames"]:
                if frame["found"]:
                    tracker.update(frame["point_mm"])
            if msg["seq"] == 3:
                for _ in range(3):
                    _port_scan(port)
                time.sleep(0.3)  # the scans' disconnections reach the server's monitor
            if msg["seq"] == 5:
                stranger.connect(endpoint)
                stranger.send_json({"op": "hello", "protocol": 2, "profile": True})
                refusal = stranger.recv_json()  # answered while the real client thinks
            if msg["seq"] == 8:
                stranger.close(0)
                time.sleep(0.3)
            cmd = tracker.step(msg["tcp_mm"], msg["then_taken"])
            real.send_json({"op": "command", "seq": msg["seq"], "command": cmd})
        _, err = server.communicate(timeout=120)
    finally:
        if server.poll() is None:
            server.kill()
        real.close(0)
        stranger.close(0)
        ctx.term()
    assert refusal is not None and refusal["op"] == "error" and refusal["status"] == "refused"
    assert "another client" in refusal["reason"]
    assert server.returncode == 0, err
    assert msg["op"] == "end" and msg["status"] == "completed" and msg["reason"] == ""
    for name in ("trace.csv", "frames.csv"):
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name


def test_a_token_binds_the_session_to_the_client_that_has_it(tmp_path: Path) -> None:
    """With a shared token, a hello without it, or with another, is refused and the server
    waits on; the hello with it starts the session (reset), here from a DEALER socket."""
    from seamtrack.bridge.zmq_transport import ZmqTransport

    endpoint = f"ipc://{tmp_path}/bridge"
    token = "k3y-" + "x" * 20
    server = ZmqTransport(endpoint, timeout_s=5.0, wait_s=20.0, token=token)
    context = TrackerContext(5.0, 0.001, 0.01, 0.0, 10.0, 0.01, np.zeros(3), np.ones(3), np.ones(3))
    thread = threading.Thread(target=server.start, args=(context, None, "frame"))
    ctx = zmq.Context()
    socks = []
    try:
        thread.start()
        answers = []
        for given in (None, "k3y-" + "y" * 20, token):  # the last one a DEALER, as docs say
            sock = ctx.socket(zmq.REQ if given != token else zmq.DEALER)
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.RCVTIMEO, 10000)
            sock.connect(endpoint)
            socks.append(sock)
            hello = {"op": "hello", "protocol": 2}
            text = json.dumps(hello if given is None else {**hello, "token": given}).encode()
            if given != token:
                sock.send(text)
                answers.append(json.loads(sock.recv()))
            else:  # an empty frame first, as a REQ socket puts it
                sock.send_multipart([b"", text])
                empty, reset = sock.recv_multipart()
                assert empty == b""
                answers.append(json.loads(reset))
        socks[-1].send_multipart([b"", b'{"op": "ready"}'])
        thread.join(timeout=30)
        assert not thread.is_alive()
    finally:
        thread.join(timeout=30)
        for sock in socks:
            sock.close(0)
        ctx.term()
        server.close()
    assert [a.get("status") for a in answers[:2]] == ["refused", "refused"]
    assert all("token" in a["reason"] for a in answers[:2])
    assert answers[2]["op"] == "reset" and answers[2]["context"]["welding_speed_mm_s"] == 5.0
    assert server.peer is not None and server.refused == 2  # the third one was taken


SIGNALS = [signal.SIGINT, signal.SIGTERM]

#: (transport, k): four seeded moments over ZeroMQ, two over Zenoh.
MOMENTS = [("zmq", k) for k in range(4)] + [("zenoh", k) for k in range(2)]


@pytest.mark.parametrize(("transport", "k"), MOMENTS)
def test_a_signal_ends_serve_as_interrupted_with_everything_written(
    transport: str, k: int, tmp_path: Path
) -> None:
    """SIGINT or SIGTERM at a random moment (seeded) of a run with a client attached: exit
    128 + the signal, one line naming it, the run folder written with status ``interrupted``
    up to the stop (its trace ends where the summary says), no temporary file and no socket
    file left, and the client told (``end``, or ``/seamtrack/status``: ``interrupted``)."""
    if transport == "zenoh":
        pytest.importorskip("zenoh")
        pytest.importorskip("rosbags")
    rng = np.random.default_rng(43 + k)
    signum = SIGNALS[k % 2]
    if transport == "zmq":
        endpoint = f"ipc://{tmp_path}/bridge"
        client_args = ["-m", "seamtrack.bridge.example_client", endpoint, "--then", "0"]
    else:
        endpoint = f"tcp/127.0.0.1:{_free_port()}"
        script = Path(__file__).parent / "bridge_clients" / "zenoh_algorithm2.py"
        client_args = [str(script), endpoint]
    out = tmp_path / "runs" / "served"
    # a long seam, a step a tick: the run is still going when the signal comes
    server = subprocess.Popen(
        [sys.executable, "-m", "seamtrack.cli", "serve", "paper-verification", "--lockstep"]
        + ["tick", "--endpoint", endpoint, "--out", str(out), "--no-plot"]
        + ["--transport", transport],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    client = None
    try:
        assert server.stderr is not None
        waiting = server.stderr.readline()  # once it listens
        assert f"waiting up to 60 s for a tracker on {endpoint}; start one, e.g. " in waiting
        if transport == "zmq":
            assert f"python -m seamtrack.bridge.example_client {endpoint}" in waiting
        client = subprocess.Popen(
            [sys.executable, *client_args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(float(rng.uniform(0.3, 3.0)))
        os.kill(server.pid, signum)
        _, s_err = server.communicate(timeout=60)
        c_out, c_err = client.communicate(timeout=30)
    finally:
        for proc in (server, client):
            if proc is not None and proc.poll() is None:
                proc.kill()
    assert server.returncode == 128 + signum, s_err
    lines = s_err.strip().splitlines()
    assert len(lines) == 1, s_err
    name = signal.Signals(signum).name
    assert lines[0].startswith(f"seamtrack serve: {name}: stopped at t = ")
    assert f"wrote {out}/summary.json, trace.csv, frames.csv, scene.toml" in lines[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["stop_cause"] == name.lower()
    assert name in summary["stop_reason"]
    trace = np.loadtxt(out / "trace.csv", delimiter=",", skiprows=1, ndmin=2)
    assert trace[-1, 0] <= summary["sim_time_s"] + 1e-9 and len(trace) >= 1
    assert sorted(p.name for p in out.parent.iterdir()) == ["served"]  # nothing else
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["summary.json", "trace.csv", "frames.csv", "scene.toml"]
    )
    if transport == "zmq":
        assert not (tmp_path / "bridge").exists()  # the socket file is gone
        assert client.returncode == 1, c_err  # told: the run was interrupted
        assert f"interrupted: bridge: interrupted by {name}" in c_err
    else:
        status = json.loads(c_out.strip().splitlines()[-1])
        assert status["status"] == "interrupted" and name in status["reason"]


def test_a_signal_while_serve_waits_writes_the_run_as_interrupted_at_zero(tmp_path: Path) -> None:
    """No client yet: SIGTERM ends the wait at once (not after --wait-s), and the run folder
    says so (interrupted at t = 0); the line names every file written, error.png too."""
    endpoint = f"ipc://{tmp_path}/bridge"
    out = tmp_path / "served"
    server = _server(endpoint, out)
    try:
        assert server.stderr is not None
        assert "waiting up to 60 s" in server.stderr.readline()
        server.send_signal(signal.SIGTERM)
        _, err = server.communicate(timeout=30)
    finally:
        if server.poll() is None:
            server.kill()
    assert server.returncode == 128 + signal.SIGTERM, err
    assert "SIGTERM: stopped at t = 0.000 s (status interrupted)" in err
    files = "summary.json, trace.csv, frames.csv, scene.toml, error.png"
    assert err.strip().splitlines()[-1].endswith(f"wrote {out}/{files}")
    assert sorted(p.name for p in out.iterdir()) == sorted(files.split(", "))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["sim_time_s"] < 0.1
    assert summary["bridge_steps"] == 0
    assert not (tmp_path / "bridge").exists()


def test_a_port_scan_changes_nothing_over_zenoh(tmp_path: Path) -> None:
    """Over Zenoh the run ends only when the tracker node's own liveliness tokens go: TCP
    connections opened and closed on the router's port all through the run (a port scan)
    leave it the in-process run, to the byte."""
    pytest.importorskip("zenoh")
    pytest.importorskip("rosbags")
    reference = tmp_path / "in-process"
    assert main(["run", "paper-corner", *SEAM, "--out", str(reference), "--no-plot", "-q"]) == 0
    port = _free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    out = tmp_path / "served"
    server = _server(endpoint, out, "-q", "--transport", "zenoh", "--no-plot")
    script = Path(__file__).parent / "bridge_clients" / "zenoh_algorithm2.py"
    client = subprocess.Popen(
        [sys.executable, str(script), endpoint], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    scans = 0
    try:
        while server.poll() is None:
            try:
                _port_scan(port)
                scans += 1
            except OSError:  # not listening yet, or no more
                pass
            time.sleep(0.05)
        _, err = server.communicate(timeout=60)
        client.communicate(timeout=30)
    finally:
        for proc in (server, client):
            if proc.poll() is None:
                proc.kill()
    assert server.returncode == 0, err
    assert scans >= 5
    for name in ("trace.csv", "frames.csv"):
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name


def test_every_page_the_bridge_points_to_exists() -> None:
    """The bridge's error lines and docstrings name docs pages (the fix of an error line): each
    one is there (docs/bridge.md never was; the bridge is docs/ros.md). rmw_zenoh's own
    docs/design.md, which rmw.py cites, is not one of ours."""
    import re

    root = Path(__file__).parents[1]
    sources = [
        *sorted((root / "seamtrack" / "bridge").glob("*.py")),
        root / "seamtrack/cli/serve.py",
    ]
    named = {
        page
        for path in sources
        for page in re.findall(r"(?<!rmw_zenoh )docs/[\w-]+\.md", path.read_text(encoding="utf-8"))
    }
    assert "docs/ros.md" in named
    assert [page for page in sorted(named) if not (root / page).is_file()] == []
