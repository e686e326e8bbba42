"""The closed loop turned inside out: :func:`seamtrack.simulation.loop.run` in a thread of its
own, paused at every sensor frame until the environment's ``step()`` hands it the next command.

The loop stays the one the rest of seamtrack runs (the same robot servo, frame timing, latency
and sensing); only its tracker is a stand-in, :class:`LockstepTracker`, that passes each frame
out and the next command in through two queues. The two threads never run at once: the
environment waits on the frame queue while the loop runs, and the loop waits on the command
queue while the environment (and the agent) run.

A frame is handed out at the first control tick after it *arrives* (capture time plus the
sensor's latency), with the torch's position and velocity at that tick; the command that
comes back holds until the next frame arrives.
"""

from __future__ import annotations

import dataclasses
import math
import queue
import threading
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.errors import PluginRuntimeError
from seamtrack.sensing.profiles import Feature, Profile, SeamHint
from seamtrack.simulation.assemble import Parts
from seamtrack.simulation.loop import Result, run

FloatArray = NDArray[np.float64]

#: How long ``close()`` waits for the loop thread to end (s); it ends within a control tick.
JOIN_TIMEOUT_S = 10.0


class _Stop(Exception):
    """Raised inside the loop's thread to end the run (the episode ended, or the env closed)."""


_STOP = object()  # the command that ends the run


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
    """The loop ended by itself: its result, or the error it raised (never both)."""

    result: Result | None = None
    error: BaseException | None = None


class LockstepTracker:
    """A :class:`~seamtrack.control.tracking.Tracker` that asks another thread for each command.

    ``update`` keeps the arriving measurement; the next ``command`` puts the frame (with the
    torch's state at that tick) on ``frames`` and waits on ``commands`` for the move to hold
    until the next frame. ``profiles`` is filled by the sensing wrapper in capture order (the
    loop delivers measurements in the same order).
    """

    def __init__(self) -> None:
        self.frames: queue.SimpleQueue[Frame | Ended] = queue.SimpleQueue()
        self.commands: queue.SimpleQueue[Any] = queue.SimpleQueue()
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
            self.frames.put(
                Frame(profile, measurement.feature, measurement, t_s, tcp_world,
                      tcp_velocity_world)
            )  # fmt: skip
            reply = self.commands.get()
            if reply is _STOP:
                raise _Stop
            self._command = reply
        return self._command


class LockstepRun:
    """One run of the loop in a daemon thread, stepped frame by frame.

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
        self.tracker = LockstepTracker()
        scan = parts.scan
        profiles = self.tracker.profiles

        def sense(T_world_sensor: FloatArray, t_s: float, hint: SeamHint | None = None) -> Feature:
            profile, feature = scan(T_world_sensor, t_s, hint)
            profiles.append(profile)
            return feature

        self.parts = dataclasses.replace(parts, tracker=self.tracker, sense=sense)
        self.ended: Ended | None = None
        self._thread = threading.Thread(
            target=self._run, args=(seed,), name="seamtrack-gym-loop", daemon=True
        )
        self._thread.start()

    def _run(self, seed: int) -> None:
        frames = self.tracker.frames
        try:
            result = run(self.parts, seed=seed)
        except PluginRuntimeError as exc:
            stopped = isinstance(exc.error, _Stop)
            frames.put(Ended() if stopped else Ended(error=exc))
        except BaseException as exc:  # handed to the environment's thread, raised there
            frames.put(Ended(error=exc))
        else:
            frames.put(Ended(result=result))

    def next_frame(self, command: Command | None = None, first: bool = False) -> Frame | Ended:
        """Send the command that holds until the next frame (none for the first frame), then
        wait for that frame, or for the end of the run."""
        if self.ended is not None:
            return self.ended
        if not first:
            self.tracker.commands.put(command)
        item = self.tracker.frames.get()
        if isinstance(item, Ended):
            self.ended = item
            self._thread.join(JOIN_TIMEOUT_S)
        return item

    def stop(self) -> None:
        """End the run and its thread (the loop is waiting for a command, or has ended)."""
        if self._thread.is_alive() and self.ended is None:
            self.tracker.commands.put(_STOP)
            self.ended = Ended()
        self._thread.join(JOIN_TIMEOUT_S)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()


def unlimited_wall_time(parts: Parts) -> Parts:
    """The parts with the loop's wall-clock guard off: the agent's time between steps (a
    gradient update may take minutes) is not the simulation's."""
    return dataclasses.replace(
        parts, settings=dataclasses.replace(parts.settings, wall_time_limit_s=math.inf)
    )
