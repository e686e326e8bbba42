"""The lockstep bridge: the closed loop with its tracker in another process.

:class:`BridgeTracker` stands in the loop for the external tracker (the loop itself is
unchanged: :func:`seamtrack.simulation.loop.run`). At each step it hands a :class:`Step` to a
transport (:mod:`seamtrack.bridge.zmq_transport`, :mod:`seamtrack.bridge.zenoh_transport`)
and blocks until the tracker's command comes back; only then does the loop simulate on.

Steps: with ``lockstep = "tick"`` every control tick is a step (the loop asks its tracker for a
command at every tick, so an external tracker reproduces any in-process one exactly); with
``lockstep = "frame"`` the steps are the ticks at which a sensor frame reaches the tracker,
and the ticks at which the torch comes within the tracker's ``ask_within_mm`` of its target
(the moment the paper's algorithm II switches to its next point: with it, algorithm II is
exact in frame lockstep too); in between, the last command holds. A transport may hand on
the commands that follow the answer (its ``then``: a list of replies, as the ZeroMQ client's
``then`` gives them): at the tick the torch comes within ``ask_within_mm`` of the target, the
next of them takes over without a round trip (the next step counts them, ``then_taken``), and
only once they are used up is the tracker asked.
A step carries the frames that arrived at it (profile, seam point, the sensor's pose) and the
torch's position and velocity at that tick.

Every stop goes through the loop's own :class:`~seamtrack.simulation.stop.StopRequest`, which
the loop reads after each tick. A client that disconnects, sends what is not a command, or
misses the deadline makes the request itself (status ``stalled``, ``stop_cause``
``bridge_failure``, ``stop_reason`` ``bridge: ...`` naming the cause): the run ends at the tick
it failed in. ``seamtrack serve``'s SIGINT and SIGTERM handler makes it too (status
``interrupted``, ``stop_cause`` ``sigint`` or ``sigterm``: a flag, nothing more, so the signal
never lands in compiled code), read after each tick and while the bridge waits for the client
(the wait then ends with :class:`Interrupted`). Either way the client is told: the
transport's ``finish`` sends the status and the reason.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from seamtrack.bridge.frames import Frame as ObservedFrame
from seamtrack.bridge.frames import frame_chain, observe
from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.errors import SeamtrackError
from seamtrack.sensing.profiles import Feature, Profile, SeamHint, hint_from_path
from seamtrack.simulation.assemble import Parts
from seamtrack.simulation.loop import Result, run
from seamtrack.simulation.stop import StopRequest

FloatArray = NDArray[np.float64]

LOCKSTEPS = ("tick", "frame")


class BridgeFailure(SeamtrackError):
    """The external tracker failed the protocol (or the transport could not start): ``field``
    says where (``client``, ``--timeout-s``, ``--endpoint``), the message what, ``fix`` what
    to do."""

    def __init__(self, message: str, field: str = "client", fix: str = "") -> None:
        super().__init__(
            message, field=field, fix=fix or "check the tracker process against docs/ros.md"
        )


class Interrupted(BridgeFailure):
    """The run was stopped from outside (a signal's :class:`StopRequest`), not by the client;
    ``reason`` is the request's."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason, field="signal", fix="nothing: it was asked")


@dataclass(frozen=True, eq=False)
class Frame:
    """One sensor frame as the external tracker receives it (world frame, mm)."""

    t_capture_s: float
    t_arrival_s: float
    feature: Feature
    T_world_sensor: FloatArray
    tcp_world: FloatArray
    profile: Profile | None  # the stripe (mesh mode), the seam point alone (seam mode)
    image: Any = None  # image mode: the camera image (a StripeImage)


@dataclass(frozen=True, eq=False)
class Step:
    """What the external tracker is sent before it answers: ``seq`` counts steps from 0."""

    seq: int
    t_s: float
    tcp_world: FloatArray
    tcp_velocity_world: FloatArray
    frames: list[Frame] = field(default_factory=list)
    then_taken: int = 0  # how many of the last answer's ``then`` took over since


#: A command and the distance from its target within which the tracker wants to be asked
#: again before the next frame (frame lockstep; 0: not before the frame).
Reply = tuple["Command | None", float]


class Answer(NamedTuple):
    """A tracker's whole answer to a step, as a transport reads it: the command (None: brake
    to rest and wait) and its ``ask_within_mm``; the commands that follow it (``then``, each a
    :data:`Reply`: frame lockstep takes them over one after the other at the tick the torch
    comes within the last one's ``ask_within_mm`` of its target); and the client's seam line
    for the extractor's hint (point, unit direction, tolerance; world, mm), as the client last
    gave it (None: none)."""

    command: Command | None
    ask_within_mm: float = 0.0
    then: tuple[Reply, ...] = ()
    seam_hint: tuple[Any, ...] | None = None


#: Asked within ``ask_within_mm`` a little early rather than a tick late (a spare round trip
#: changes nothing: the tracker answers the same).
_ASK_MARGIN = 1e-9


class Transport(Protocol):
    """How steps go out and commands come in (one tracker process at a time). ``stop`` is
    read while the transport waits (:func:`serve` sets it): once requested, the wait ends with
    :class:`Interrupted`."""

    stop: StopRequest

    def start(self, context: TrackerContext, chain: TfChain, lockstep: str) -> None:
        """Wait for the tracker process and give it the run's context."""

    def exchange(self, step: Step) -> Answer:
        """Send ``step``; return the tracker's :class:`Answer`. Raises
        :class:`BridgeFailure`."""

    def finish(self, summary: dict[str, Any]) -> None:
        """Tell the tracker the run is over, its ``status`` and ``stop_reason`` (best
        effort: also after a failure, so that the client is never left waiting)."""

    def close(self) -> None: ...


#: The robot's frames at a sensor pose: (parent, child, T_parent_child) links, mm.
TfChain = Callable[[FloatArray], "list[tuple[str, str, FloatArray]]"]


def tf_chain(parts: Parts) -> TfChain:
    """The TF chain of ``parts``' robot (:func:`seamtrack.bridge.frames.frame_chain`)."""
    return functools.partial(frame_chain, parts.robot)


class BridgeTracker:
    """A :class:`~seamtrack.control.tracking.Tracker` whose decisions come from another
    process through ``transport`` (see the module docstring)."""

    name = "bridge"

    def __init__(
        self,
        transport: Transport,
        chain: TfChain,
        lockstep: str = "tick",
        profiles: dict[float, tuple[Profile, Any]] | None = None,
        stop: StopRequest | None = None,
    ) -> None:
        self.transport = transport
        self.stop = stop if stop is not None else StopRequest()
        self.chain = chain
        self.lockstep = lockstep
        self.profiles = profiles if profiles is not None else {}
        self.failure: BridgeFailure | None = None
        self.steps = 0
        self.exchange_time_s = 0.0
        self.wait_time_s = 0.0
        self._frames: list[Frame] = []
        self._last: Command | None = None
        self._within = 0.0
        self._target: list[float] = []  # the last command's target, as floats (for _asks)
        self._then: list[Reply] = []  # what follows the last command, next last (pop() it)
        self._taken = 0
        self._seam_hint: tuple[Any, ...] | None = None  # the client's seam line, as last given

    def reset(self, context: TrackerContext) -> None:
        start = time.perf_counter()
        try:
            self.transport.start(context, self.chain, self.lockstep)
        except BridgeFailure as exc:
            self._failed(exc)
        self.wait_time_s = time.perf_counter() - start

    def update(self, measurement: Measurement) -> None:
        profile, image = self.profiles.pop(measurement.t_capture_s, (None, None))
        self._frames.append(
            Frame(
                measurement.t_capture_s,
                measurement.t_arrival_s,
                measurement.feature,
                measurement.T_world_sensor,
                np.asarray(measurement.tcp_world, dtype=float),
                profile,
                image,
            )
        )

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        if self.failure is not None:  # the loop stops after this tick (the stop request)
            return None
        if self.lockstep == "frame" and not self._frames and self._within > 0.0:
            tcp = np.asarray(tcp_world, dtype=float).tolist()  # Python floats: every tick
            if self._then:
                self._take_then(tcp)
            if not self._asks(tcp):
                return self._last
        elif self.lockstep == "frame" and not self._frames:
            return self._last
        step = Step(self.steps, t_s, tcp_world, tcp_velocity_world, self._frames, self._taken)
        self._frames = []
        start = time.perf_counter()
        try:
            answer = self.transport.exchange(step)
        except BridgeFailure as exc:
            self._failed(exc)
            return None
        self.exchange_time_s += time.perf_counter() - start
        self.steps += 1
        self._taken = 0
        self._then = list(answer.then)[::-1]
        self._seam_hint = answer.seam_hint
        self._hold(answer.command, answer.ask_within_mm)
        return self._last

    def _failed(self, exc: BridgeFailure) -> None:
        """Keep the failure and ask the loop to stop after this tick: ``stalled``, its cause
        ``bridge_failure`` (a signal's :class:`Interrupted` was asked for already, and the
        first request wins)."""
        self.failure = exc
        self.stop.request("bridge_failure", f"bridge: {exc.message}", status="stalled")

    def _hold(self, received: Command | None, within: float) -> None:
        self._within = within
        if not _same(received, self._last):  # the loop re-plans only on a new command object
            self._last = received
            self._target = [] if received is None else received.target_world.tolist()

    def _take_then(self, tcp: list[float]) -> None:
        """Frame lockstep between frames: while the torch is within ``ask_within_mm`` of the
        target (exactly: a tracker's own test, ``sqrt(dx² + dy² + dz²) <= r``), the next
        command of the answer's ``then`` takes over."""
        while self._then and self._last is not None and self._within > 0.0:
            dx, dy, dz = (tcp[0] - self._target[0], tcp[1] - self._target[1],
                          tcp[2] - self._target[2])  # fmt: skip
            if not math.sqrt(dx * dx + dy * dy + dz * dz) <= self._within:
                return
            self._hold(*self._then.pop())
            self._taken += 1

    def hint(self, T_world_sensor: FloatArray) -> SeamHint | None:
        """The extractor's hint for the frame about to be taken: where the client's last
        ``seam_hint`` line (the last :class:`Answer`'s: point, direction, tolerance; world)
        crosses the laser plane; None without one."""
        line = self._seam_hint
        if line is None or self.failure is not None:
            return None
        point, direction, tolerance = line
        return hint_from_path(T_world_sensor, point, direction, tolerance)

    def _asks(self, tcp: list[float]) -> bool:
        """Frame lockstep between frames: is the torch within the tracker's ``ask_within_mm``
        of its target?"""
        if self._within <= 0.0 or self._last is None:
            return False
        d = math.dist(tcp, self._target)
        return d <= self._within * (1.0 + _ASK_MARGIN) + _ASK_MARGIN


def _same(a: Command | None, b: Command | None) -> bool:
    if a is None or b is None or a is b:
        return a is b
    return (
        a.speed_mm_s == b.speed_mm_s
        and a.stop_at_target == b.stop_at_target
        and a.target_world.tolist() == b.target_world.tolist()  # finite: as array_equal
        and _equal(a.velocity_ff_world, b.velocity_ff_world)
        and _equal(a.rotation_world, b.rotation_world)
        and _equal(a.angular_velocity_world, b.angular_velocity_world)
    )


def _equal(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is b
    return bool(np.array_equal(a, b))


def bridged_parts(parts: Parts, tracker: BridgeTracker) -> Parts:
    """``parts`` with the bridge as its tracker; every frame's profile (the stripe in mesh
    mode, the seam point alone in seam mode: :func:`seamtrack.bridge.frames.observe`) goes
    out with the frame."""
    profiles = tracker.profiles

    def keep(frame: ObservedFrame) -> None:
        profiles[frame.t_s] = (frame.profile, frame.image)

    observed = observe(parts, keep)
    return dataclasses.replace(observed, tracker=tracker, tracker_name="bridge")


def serve(
    parts: Parts,
    transport: Transport,
    lockstep: str = "tick",
    seed: int | None = None,
    clock: Callable[[], float] | None = None,
    stop: StopRequest | None = None,
) -> tuple[Result, BridgeTracker]:
    """Run ``parts`` with the tracker behind ``transport``. The result's summary is the
    loop's; a failed bridge stops the run as ``stalled`` with ``stop_reason`` naming the cause
    (``tracker.failure`` holds it), a requested ``stop`` as ``interrupted`` (both through the
    loop's stop request, :mod:`seamtrack.simulation.stop`);
    ``bridge_steps`` and ``bridge_exchange_s`` count the round trips and their wall time,
    ``bridge_wait_s`` the wait for the tracker (in ``wall_time_s``). The client is told the
    status and the reason in every case (``transport.finish``)."""
    if lockstep not in LOCKSTEPS:
        raise ValueError(f"lockstep must be one of {LOCKSTEPS}, got {lockstep!r}")
    stop = stop if stop is not None else StopRequest()
    transport.stop = stop
    tracker = BridgeTracker(transport, tf_chain(parts), lockstep, stop=stop)
    bridged = bridged_parts(parts, tracker)
    try:
        result = run(bridged, seed=seed, clock=clock or time.perf_counter, stop=stop)
        summary = result.summary
        summary["bridge_steps"] = tracker.steps
        summary["bridge_exchange_s"] = tracker.exchange_time_s
        summary["bridge_wait_s"] = tracker.wait_time_s
        transport.finish(summary)
    finally:
        transport.close()
    return result, tracker


def finite_vector(value: Any, n: int) -> list[float] | None:
    """``value`` as n finite floats, or None when it is not that."""
    if not isinstance(value, list | tuple) or len(value) != n:
        return None
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            return None
        out.append(float(v))
    return out
