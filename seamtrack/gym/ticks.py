"""The environment's control ticks between two sensor frames, compiled, for one environment or
a batch of them in one call.

Between two frames the environment's command is held: every control tick the gantry's axes
take the same :func:`~seamtrack.control.robot.axes_step` (and the servo's position loops,
:func:`~seamtrack.control.servo.loops_step`), and every ``check_every`` ticks the loop's
progress check (:func:`~seamtrack.simulation.progress.progress_check`). The loop runs a Python
tracker's ticks one by one in Python (about 8 us a tick); :func:`held_ticks` runs them as
:func:`seamtrack.simulation.ticks.gantry_ticks` runs the built-in tracker's, with the command
held instead of the tracker's set-point step: the same compiled steps in the same order, so the
torch moves to the last bit as in :func:`seamtrack.simulation.loop.run`
(``tests/test_gym_ticks.py`` compares whole episodes).

The arrays have one row per environment (a batch); a call runs the rows it is given, each from
its own first tick until its next event (a frame due, a measurement arriving), the end of its
time or a progress check that ends its run.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.control.robot import axes_step
from seamtrack.control.servo import loops_step
from seamtrack.jit import KERNEL
from seamtrack.simulation.progress import GO_ON, progress_check

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Columns of a held command (base frame): whether it has a target, the target (mm), the speed
#: (mm/s), the feed-forward (mm/s), whether to arrive at rest.
C_HAS, C_X, C_Y, C_Z, C_SPEED, C_FX, C_FY, C_FZ, C_STOP = range(9)
COMMAND_FIELDS = 9
#: Rows of an environment's axes: position and velocity (the servo's output), the
#: interpolator's set-point position and velocity, the set-point the servo holds.
A_Q, A_V, A_SQ, A_SV, A_HELD = range(5)
#: Columns of an environment's tick counters: ticks per interpolation (-1: ideal axes), the
#: servo's tick count.
I_EVERY, I_COUNT = 0, 1
#: What stopped a row's ticks (``why``): an event tick is next; the run's time is over; else
#: the progress check's finding (:data:`~seamtrack.simulation.progress.AT_REST_END`, ...),
#: ``ENDED + found``.
EVENT, TIME_OVER, ENDED = 0, 1, 2
#: Rows of the limits (:func:`~seamtrack.control.robot.axes_step`'s ``lim``): travel min, max.
_LO, _HI = 2, 3


@numba.njit(**KERNEL)
def held_ticks(
    rows: IntArray, first: IntArray, next_capture: FloatArray, next_arrival: FloatArray,
    max_ticks: int, dt: float, check_every: int, tcp_offset: FloatArray, limits: FloatArray,
    servo: FloatArray, axes: FloatArray, counters: IntArray, command: FloatArray,
    progress: FloatArray, seam_points: FloatArray, seam_knots: FloatArray,
    seam_columns: FloatArray, ran: IntArray, why: IntArray,
) -> None:  # fmt: skip
    """Each row ``i`` of ``rows``: control ticks from ``first[i]`` on under ``command[i]``,
    stopping before a tick at which a frame is due (``next_capture[i]``) or a measurement
    arrives (``next_arrival[i]``), after tick ``max_ticks`` (``TIME_OVER``) or after a progress
    check (every ``check_every`` ticks, on ``progress[i]``) that ends the run
    (``ENDED + found``). ``axes[i]`` (rows :data:`A_Q`...) and ``counters[i]`` are stepped in
    place; ``ran[i]`` is the number of ticks run, ``why[i]`` what stopped them.

    ``tcp_offset`` (3,): the torch tip less the axes (an unrotated gantry's base origin);
    ``limits``: the axes' limits; ``servo``: the position loops' table (unused when
    ``counters[i, I_EVERY] < 0``: ideal axes); ``seam_*``: the progress check's seam arrays.
    """
    for k in range(len(rows)):
        i = rows[k]
        q, v, held = axes[i, A_Q], axes[i, A_V], axes[i, A_HELD]
        sq, sv = axes[i, A_SQ], axes[i, A_SV]
        cmd, count, P = command[i], counters[i], progress[i]
        has_target = cmd[C_HAS] != 0.0
        tx, ty, tz, speed = cmd[C_X], cmd[C_Y], cmd[C_Z], cmd[C_SPEED]
        fx, fy, fz, stop = cmd[C_FX], cmd[C_FY], cmd[C_FZ], cmd[C_STOP] != 0.0
        has_servo = count[I_EVERY] > 0
        tick = start = first[i]
        stopped = TIME_OVER
        while tick <= max_ticks:
            t = tick * dt
            if tick > start and (t + 1e-9 >= next_capture[i] or next_arrival[i] <= t + 1e-9):
                stopped = EVENT
                break
            x, y, z = q[0] + tcp_offset[0], q[1] + tcp_offset[1], q[2] + tcp_offset[2]
            if has_servo:  # CartesianRobot.step_move and Servo.follow
                axes_step(sq, sv, limits, dt, has_target, tx, ty, tz, speed, fx, fy, fz, stop)
                if count[I_COUNT] % count[I_EVERY] == 0:
                    held[:] = sq
                count[I_COUNT] += 1
                loops_step(q, v, held, servo, dt)
                for a in range(3):
                    q[a] = min(max(q[a], limits[_LO, a]), limits[_HI, a])
            else:
                axes_step(q, v, limits, dt, has_target, tx, ty, tz, speed, fx, fy, fz, stop)
            tick += 1
            if (tick - 1) % check_every == 0:
                moving = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                found = progress_check(P, t, x, y, z, moving, seam_points, seam_knots, seam_columns)
                if found != GO_ON:
                    stopped = ENDED + found
                    break
        ran[i] = tick - start
        why[i] = stopped


class TickArrays(NamedTuple):
    """The per-environment arrays of a batch (:func:`held_ticks`' arguments of the same names;
    ``progress`` is the caller's, as its progress check makes it)."""

    first: IntArray
    next_capture: FloatArray
    next_arrival: FloatArray
    axes: FloatArray
    counters: IntArray
    command: FloatArray
    ran: IntArray
    why: IntArray


def batch_arrays(n: int) -> TickArrays:
    """A batch of ``n`` environments' arrays, zeroed (no measurement on its way)."""
    return TickArrays(
        first=np.zeros(n, dtype=np.int64),
        next_capture=np.zeros(n),
        next_arrival=np.full(n, math.inf),
        axes=np.zeros((n, 5, 3)),
        counters=np.zeros((n, 2), dtype=np.int64),
        command=np.zeros((n, COMMAND_FIELDS)),
        ran=np.zeros(n, dtype=np.int64),
        why=np.zeros(n, dtype=np.int64),
    )
