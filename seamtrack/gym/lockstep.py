"""The closed loop turned inside out: :func:`seamtrack.simulation.loop.run` in a greenlet of
its own, paused at every sensor frame until the environment's ``step()`` hands it the next
command.

The loop stays the one the rest of seamtrack runs (the same robot servo, frame timing, latency
and sensing); only its tracker is a stand-in, :class:`LockstepTracker`, that switches to the
environment with each frame and gets the next command back. A greenlet is a coroutine with its
own C stack in the same OS thread: a round trip of two switches costs about 2 us (between two OS
threads it measured 80 to 100 us on a busy machine, plus a wait for a core), nothing runs
concurrently, and a run that is dropped unfinished is ended by the garbage collector
(``GreenletExit`` inside it). The environment must be stepped in the thread that reset it.

A frame is handed out at the first control tick after it *arrives* (capture time plus the
sensor's latency), with the torch's position and velocity at that tick; the command that
comes back holds until the next frame arrives.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass

import greenlet
import numpy as np
from numpy.typing import NDArray

from seamtrack.bridge.frames import observe
from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.sensing.profiles import Feature, Profile
from seamtrack.simulation.assemble import Parts
from seamtrack.simulation.loop import Result, run
from seamtrack.simulation.stop import StopRequest

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Frame:
    """One sensor frame as the environment receives it.

    Attributes
    ----------
    profile : Profile
        The stripe in the laser frame, as the scene's sensor measured it.
    feature : Feature
        The scene's extractor's seam point in it (falsy when none was found).
    measurement : Measurement
        What a tracker would receive (capture and arrival times, sensor pose at capture).
    t_s : float
        The control tick at which the frame arrived (the step's time).
    tcp_world, velocity_world : (3,) float
        The torch tip's position (mm) and velocity (mm/s) at that tick.
    """

    profile: Profile
    feature: Feature
    measurement: Measurement
    t_s: float
    tcp_world: FloatArray
    velocity_world: FloatArray


@dataclass(frozen=True, eq=False)
class Ended:
    """The loop ended by itself: its result, or the error it raised (never both); or, from
    the compiled ticks (:mod:`seamtrack.gym.stepper`), which score nothing, the status and
    time the loop's result would give (``status``, ``t_s``)."""

    result: Result | None = None
    error: BaseException | None = None
    status: str = ""
    t_s: float = math.nan

    def outcome(self) -> tuple[str, float]:
        """The run's status and its last tick's time (s)."""
        if self.result is not None:
            return self.result.status, float(self.result.summary["sim_time_s"])
        return self.status, self.t_s


class LockstepTracker:
    """A :class:`~seamtrack.control.tracking.Tracker` that asks the environment for each command.

    ``update`` keeps the arriving measurement; the next ``command`` switches to the environment
    (``parent``, the greenlet that started the run) with the frame and the torch's state at
    that tick, and gets back the move to hold until the next frame. ``profiles`` is filled in
    capture order by :func:`seamtrack.bridge.frames.observe` (the loop delivers measurements
    in the same order).
    """

    def __init__(self, parent: greenlet.greenlet) -> None:
        self.parent = parent
        self.profiles: deque[Profile] = deque()
        self._arrived: Measurement | None = None
        self._command: Command | None = None

    def reset(self, context: TrackerContext) -> None:
        self._arrived = None
        self._command = None

    def update(self, measurement: Measurement) -> None:
        self._arrived = measurement

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        measurement = self._arrived
        if measurement is not None:
            self._arrived = None
            profile = self.profiles.popleft()
            self._command = self.parent.switch(
                Frame(profile, measurement.feature, measurement, t_s, tcp_world,
                      tcp_velocity_world)
            )  # fmt: skip
        return self._command


class LockstepRun:
    """One run of the loop in a greenlet, stepped frame by frame from the caller's.

    Parameters
    ----------
    parts : Parts
        The scene's parts; their tracker and sensing are replaced here (the scan must exist:
        mesh or image mode).
    seed : int
        The loop's seed (the tracker context's generator).
    """

    def __init__(self, parts: Parts, seed: int) -> None:
        assert parts.scan is not None
        self.tracker = LockstepTracker(greenlet.getcurrent())
        profiles = self.tracker.profiles
        observed = observe(parts, lambda frame: profiles.append(frame.profile))
        self.parts = dataclasses.replace(observed, tracker=self.tracker)
        self.seed = seed
        self.stop_request = StopRequest()  # the loop reads it after each tick
        self.ended: Ended | None = None
        self._greenlet = greenlet.greenlet(self._run)

    def _run(self) -> Ended:
        try:
            result = run(self.parts, seed=self.seed, stop=self.stop_request)
        except greenlet.GreenletExit:  # dropped unfinished: the collector ends it
            raise
        except BaseException as exc:  # handed to the environment, raised there
            return Ended(error=exc)
        return Ended(result=result)

    def next_frame(self, command: Command | None = None, first: bool = False) -> Frame | Ended:
        """Send the command that holds until the next frame (none for the first frame), then
        run the loop to that frame, or to the end of the run."""
        if self.ended is not None:
            return self.ended
        item = self._greenlet.switch() if first else self._greenlet.switch(command)
        if isinstance(item, Ended):
            self.ended = item
        return item

    def stop(self) -> None:
        """End the run (the loop is waiting for a command, has ended, or never started): a
        ``GreenletExit`` raised where the loop waits ends it there, unscored (scoring a run the
        environment ended, which nothing reads, took longer than a hundred steps)."""
        if self.ended is None and self._greenlet:  # started and not dead: waiting in command()
            self._greenlet.throw()
        self.ended = self.ended or Ended(status="interrupted")

    @property
    def alive(self) -> bool:
        """Whether the loop is running (started and waiting for a command)."""
        return bool(self._greenlet)


def unlimited_wall_time(parts: Parts) -> Parts:
    """The parts with the loop's wall-clock guard off: the agent's time between steps (a
    gradient update may take minutes) is not the simulation's."""
    return dataclasses.replace(
        parts, settings=dataclasses.replace(parts.settings, wall_time_limit_s=math.inf)
    )
