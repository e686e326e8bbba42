"""``SeamTrackEnv``: a seamtrack scene as a Gymnasium environment, one step per sensor frame.

The torch travels along a *nominal* path at the scene's welding speed (by default the straight
line from the seam's start to its end: a program taught by two points); the agent corrects it
sideways and up/down, frame by frame, from what the laser sensor sees. The simulation is the
scene's own closed loop: the same servo, frame timing, latency, ray-cast stripe and noise as
``seamtrack run``, its control ticks between frames compiled (:mod:`seamtrack.gym.stepper`) or,
where they cannot be, the loop itself in a coroutine (:mod:`seamtrack.gym.lockstep`); the two
step the same episodes.

Spaces (``n`` = the scene's laser rays):

* observation: one flat ``float32`` Box of ``3 n + 9`` numbers, see :data:`TORCH_STATE` and
  :func:`split_observation`: the profile's ``(y_L, z_L)`` points (``2 n``, mm, laser frame,
  0 where invalid), their validity (``n``, 1.0 or 0.0), then the torch's state: its lateral and
  vertical offset from the nominal path (mm), its velocity across, up and along it (mm/s), the
  correction commanded so far (lateral, vertical, mm), the time (s) and the progress along the
  nominal path (0 to 1).
* action: ``(lateral, vertical)`` correction in mm, added to the correction held so far and
  applied for this frame (each in ``[-max_correction_mm, max_correction_mm]``, 1 mm by default:
  100 mm/s of correction at 100 frames/s); the correction held stays within ``+- 2 lost_mm``.

A bad action never raises: an exception in ``step()`` shuts an ``AsyncVectorEnv``'s worker down
for good (Gymnasium's vector contract), so one NaN from a policy would end the whole vector
env. An action outside the bound is clipped to it, as Gymnasium's own continuous environments
and its ``ClipAction`` wrapper do (``info["action_clipped"]``). One that is not two finite
numbers (NaN, inf, another shape, not numbers) is refused: the step runs as with a zero action
(the correction held is kept), ``info["action_refused"]`` says why (``""`` when accepted) and a
:class:`BadActionWarning` is issued.

Reward: minus the torch tip's distance to the true seam (mm) at the frame; when the seam is
lost, minus ``lost_mm`` for every frame left to the seam's end at the welding speed on top (so
losing the seam never pays better than staying just inside the limit).

Episode end: terminated when the torch reaches the seam's end (within the scene's end
tolerance) or loses the seam (farther than ``lost_mm`` from it, or the loop stopped it at an
axis limit); truncated when the time reaches ``max_time_s`` (or the loop stalls).
"""

from __future__ import annotations

import bisect
import math
import warnings
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from seamtrack.control.tracking import Command
from seamtrack.errors import SceneError, SeamError
from seamtrack.geometry.seam import Seam
from seamtrack.gym.lockstep import Ended, Frame, LockstepRun, unlimited_wall_time
from seamtrack.gym.observe import fill_observation
from seamtrack.gym.stepper import HeldRun, TickBatch, supports
from seamtrack.simulation.assemble import Parts, build_parts
from seamtrack.simulation.progress import ProgressTracker
from seamtrack.simulation.scene import Scene, load_scene

FloatArray = NDArray[np.float64]
Vec = tuple[float, float, float]

#: The torch state's entries, after the profile and its validity.
TORCH_STATE = (
    "offset_lateral_mm",
    "offset_vertical_mm",
    "velocity_lateral_mm_s",
    "velocity_vertical_mm_s",
    "velocity_along_mm_s",
    "correction_lateral_mm",
    "correction_vertical_mm",
    "t_s",
    "progress",
)

#: How the loop runs between frames (``SeamTrackEnv(engine=...)``).
ENGINES = ("auto", "compiled", "lockstep")

#: Every observation entry lies within +- this (mm, mm/s, s): a bound Gymnasium's checker
#: accepts, far beyond any scene's reach (values are clipped to it).
OBSERVATION_LIMIT = 1.0e5


def split_observation(observation: NDArray[Any], rays: int) -> dict[str, NDArray[Any]]:
    """Views of a flat observation (or a batch of them, ``(..., 3 rays + 9)``): ``profile``
    ``(..., rays, 2)`` (y_L, z_L) mm, ``valid`` ``(..., rays)`` bool, ``torch`` ``(..., 9)`` (see
    :data:`TORCH_STATE`)."""
    obs = np.asarray(observation)
    lead = obs.shape[:-1]
    return {
        "profile": obs[..., : 2 * rays].reshape(*lead, rays, 2),
        "valid": obs[..., 2 * rays : 3 * rays] > 0.5,
        "torch": obs[..., 3 * rays :],
    }


class BadActionWarning(UserWarning):
    """A step's action was refused (not two finite numbers); the step went on without it."""


class _Polyline:
    """A seam's closest arc length near a hint, and its point and frame at an arc length (on
    plain floats: this runs a few times a step)."""

    def __init__(self, seam: Seam) -> None:
        self.progress = ProgressTracker(seam)
        self.points = [tuple(p) for p in seam.points.tolist()]
        self.normals = [tuple(n) for n in seam.normals.tolist()]
        self.knots = seam.arc_length_mm.tolist()
        self.length_mm = float(seam.length_mm)

    def locate(self, point: FloatArray, hint_mm: float) -> float:
        return self.progress.closest_near(point, hint_mm)

    def frame(self, s_mm: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Point, unit tangent, lateral (tangent x normal) and torch normal at ``s_mm``, (3,)
        arrays each."""
        point, tangent, lateral, normal = self.frame_floats(s_mm)
        return np.array(point), np.array(tangent), np.array(lateral), np.array(normal)

    def frame_floats(self, s_mm: float) -> tuple[Vec, Vec, Vec, Vec]:
        """:meth:`frame` as tuples of floats (a few microseconds, where numpy takes tens)."""
        knots = self.knots
        s = min(max(s_mm, 0.0), self.length_mm)
        i = min(max(bisect.bisect_right(knots, s) - 1, 0), len(knots) - 2)
        step = knots[i + 1] - knots[i]
        w = (s - knots[i]) / step
        (ax, ay, az), (bx, by, bz) = self.points[i], self.points[i + 1]
        tx, ty, tz = (bx - ax) / step, (by - ay) / step, (bz - az) / step
        (mx, my, mz), (px, py, pz) = self.normals[i], self.normals[i + 1]
        nx, ny, nz = (1.0 - w) * mx + w * px, (1.0 - w) * my + w * py, (1.0 - w) * mz + w * pz
        along = nx * tx + ny * ty + nz * tz
        nx, ny, nz = nx - along * tx, ny - along * ty, nz - along * tz
        size = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / size, ny / size, nz / size
        return (
            (ax + w * (bx - ax), ay + w * (by - ay), az + w * (bz - az)),
            (tx, ty, tz),
            (ty * nz - tz * ny, tz * nx - tx * nz, tx * ny - ty * nx),
            (nx, ny, nz),
        )


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def nominal_path(seam: Seam, nominal: str) -> Seam:
    """The path the torch follows before corrections: ``"line"``, the straight line from the
    seam's start to its end (torch normal: the seam's mean), or ``"seam"``, the true seam."""
    if nominal == "seam":
        return seam
    if nominal != "line":
        raise SceneError(
            f"unknown nominal path {nominal!r}", field="nominal", fix='use "line" or "seam"'
        )
    normal = seam.normals.mean(axis=0)
    try:
        return Seam.from_points(seam.points[[0, -1]], [normal, normal], name="nominal line")
    except SeamError:
        raise SceneError(
            "the seam ends where it starts (a closed seam): no straight line joins its ends",
            field="nominal",
            fix='use nominal="seam" (corrections relative to the true seam)',
        ) from None


class SeamTrackEnv(gymnasium.Env[NDArray[np.float32], NDArray[np.float32]]):
    """A seamtrack scene as a Gymnasium environment (see the module docstring).

    Parameters
    ----------
    scene : str, Path or Scene
        A built-in scene name, a TOML file or a loaded scene; its sensor must give a profile
        (``sensor.mode = "mesh"``).
    overrides : dict or list of "KEY=VALUE", optional
        Scene overrides, as ``seamtrack run --set`` takes them.
    nominal : {"line", "seam"}
        The path the torch follows before corrections.
    max_correction_mm : float
        The action's bound (mm per frame, each axis).
    lost_mm : float, optional
        The seam is lost when the torch tip is farther from it; default half the sensor's near
        field of view (farther, the seam can leave the stripe).
    max_time_s : float, optional
        Truncation time; default the scene's time limit less two frames.
    start_jitter_mm : float
        The start position's random lateral and vertical shift (uniform within +- this, drawn
        from the environment's generator at each reset).
    lead_mm : float, optional
        How far ahead along the nominal path the torch is aimed; default the larger of 1 mm and
        five frames of travel.
    share_with : SeamTrackEnv, optional
        Another environment of the same scene whose ray-casting scene (mesh, Embree scene,
        section hierarchy) this one casts on instead of building its own: the environments of
        a :class:`~seamtrack.gym.vector.BatchedVectorEnv` batch share one, which keeps a
        batch's memory and cache footprint that of one environment. The same steps either way.
    engine : {"auto", "compiled", "lockstep"}
        How the loop runs between frames: its control ticks compiled
        (:mod:`seamtrack.gym.stepper`; a gantry with an unrotated base, a part that does not
        move), or :func:`seamtrack.simulation.loop.run` itself in a coroutine
        (:mod:`seamtrack.gym.lockstep`; any scene). Both give the same steps; ``"auto"``: the
        compiled ticks where they run.
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012 (Gymnasium's own form)

    def __init__(
        self,
        scene: str | Path | Scene = "paper-v-groove",
        overrides: dict[str, Any] | list[str] | None = None,
        nominal: str = "line",
        max_correction_mm: float = 1.0,
        lost_mm: float | None = None,
        max_time_s: float | None = None,
        start_jitter_mm: float = 0.5,
        lead_mm: float | None = None,
        engine: str = "auto",
        share_with: SeamTrackEnv | None = None,
    ) -> None:
        loaded = scene if isinstance(scene, Scene) else load_scene(scene, overrides)
        if isinstance(scene, Scene) and overrides:
            raise SceneError(
                "overrides given with a loaded scene", field="overrides",
                fix="pass the scene's name or path with the overrides, or apply them first",
            )  # fmt: skip
        if loaded.config.sensor.mode != "mesh":
            raise SceneError(
                "the environment observes the stripe profile, which a seam-mode scene has none of",
                field="sensor.mode",
                fix='use a mesh-mode scene (sensor.mode = "mesh"), e.g. paper-v-groove',
            )
        _check_number("max_correction_mm", max_correction_mm)
        _check_number("start_jitter_mm", start_jitter_mm, zero=True)
        for name, value in (("lost_mm", lost_mm), ("max_time_s", max_time_s), ("lead_mm", lead_mm)):
            if value is not None:
                _check_number(name, value)
        self.scene = loaded
        self._rng = np.random.default_rng(loaded.config.simulation.seed)  # the scan's noise
        self._rebuild = loaded.config.sensor.source == "image"  # auto-exposure state per run
        self._caster = None
        if share_with is not None:
            if share_with.scene.config != loaded.config:
                raise SceneError(
                    "share_with is an environment of another scene",
                    field="share_with",
                    fix="share only between environments of the same scene and overrides",
                )
            self._caster = share_with.parts.caster
        self.parts: Parts = unlimited_wall_time(
            build_parts(loaded, rng=self._rng, caster=self._caster)
        )
        cfg = self.parts.settings
        sensor = self.parts.sensor
        assert sensor is not None and self.parts.scan is not None
        self.truth = _Polyline(self.parts.seam)
        self.nominal = _Polyline(nominal_path(self.parts.seam, nominal))
        self.frame_period_s = cfg.frame_period_s
        self.speed_mm_s = cfg.welding_speed_mm_s
        self.end_tolerance_mm = cfg.end_tolerance_mm
        self.lost_mm = float(lost_mm) if lost_mm is not None else sensor.fov_near_mm / 2.0
        self.max_time_s = (
            float(max_time_s) if max_time_s is not None
            else cfg.time_limit_s - 2.0 * cfg.frame_period_s
        )  # fmt: skip
        self.start_jitter_mm = float(start_jitter_mm)
        self.lead_mm = (
            float(lead_mm) if lead_mm is not None
            else max(1.0, 5.0 * cfg.welding_speed_mm_s * cfg.frame_period_s)
        )  # fmt: skip
        self.rays = self._profile_length()
        size = 3 * self.rays + len(TORCH_STATE)
        self.observation_space = spaces.Box(
            -OBSERVATION_LIMIT, OBSERVATION_LIMIT, shape=(size,), dtype=np.float32
        )
        self.max_correction_mm = bound = float(max_correction_mm)
        self.action_space = spaces.Box(-bound, bound, shape=(2,), dtype=np.float32)
        if engine not in ENGINES:
            raise SceneError(
                f"unknown engine {engine!r}", field="engine", fix=f"use one of {ENGINES}"
            )
        compiled = supports(self.parts)
        if engine == "compiled" and not compiled:
            raise SceneError(
                "the compiled ticks run a gantry with an unrotated base and a part that does "
                "not move; this scene has neither",
                field="engine",
                fix='use engine="auto" (the loop itself where the ticks cannot run compiled)',
            )
        self.engine = "compiled" if compiled and engine != "lockstep" else "lockstep"
        #: Where the compiled ticks run (a row of a batch: the vector env's, or its own).
        self.tick_batch: TickBatch | None = None
        self.tick_row = 0
        self._run: LockstepRun | HeldRun | None = None
        self._correction = (0.0, 0.0)  # (lateral, vertical) mm, as floats
        self._s_nominal = 0.0
        self._s_true = 0.0
        self._last_obs = np.zeros(size, dtype=np.float32)

    # ----------------------------------------------------------------- Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        self._stop()
        rng = self.np_random
        scan_seed, loop_seed = (int(x) for x in rng.integers(0, 2**63 - 1, size=2))
        jitter = rng.uniform(-self.start_jitter_mm, self.start_jitter_mm, size=2)
        if self._rebuild:
            self._rng = np.random.default_rng(scan_seed)
            self.parts = unlimited_wall_time(
                build_parts(self.scene, rng=self._rng, caster=self._caster)
            )
        else:  # the same Generator object the parts' scan draws from, re-seeded in place
            self._rng.bit_generator.state = np.random.default_rng(scan_seed).bit_generator.state
        _, _, lateral, normal = self.nominal.frame(0.0)
        start = self.parts.tcp_start_world + jitter[0] * lateral + jitter[1] * normal
        parts = _with_start(self.parts, start)
        self._correction = (0.0, 0.0)  # (lateral, vertical) mm, as floats
        self._s_nominal = 0.0
        self._s_true = 0.0
        if self.engine == "compiled":
            if self.tick_batch is None:
                self.tick_batch = TickBatch(parts, 1)
            run: LockstepRun | HeldRun = HeldRun(parts, self.tick_batch, self.tick_row)
        else:
            run = LockstepRun(parts, loop_seed)
        self._run = run
        frame = run.next_frame(first=True)
        if isinstance(frame, Ended):
            self._stop()
            if frame.error is not None:
                raise frame.error
            raise RuntimeError("the run ended before its first sensor frame")
        obs, info = self._observe(frame)
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        run, (target, at_end), clipped, refused = self.begin_step(action)
        if refused:
            warnings.warn(
                f"seamtrack.gym: action refused: {refused}; the step applies no correction",
                BadActionWarning,
                stacklevel=2,
            )
        if isinstance(run, HeldRun):
            frame = run.advance(target, self.speed_mm_s, at_end)
        else:
            frame = run.next_frame(Command(np.array(target), self.speed_mm_s, None, at_end))
        return self.finish_step(frame, clipped, refused)

    def begin_step(self, action: Any) -> tuple[LockstepRun | HeldRun, tuple[Vec, bool], bool, str]:
        """The first half of :meth:`step`: the action read and added to the correction held;
        the run, the command it takes next (the target in the world, mm, and whether to arrive
        there at rest; at the welding speed), and whether the action was clipped, or why it was
        refused (``""``: accepted). The vector env runs the ticks of many between the halves."""
        run = self._run
        if run is None:
            raise RuntimeError("call reset() before step() (and after an episode ends)")
        ax, ay, refused = _action_floats(action)
        bound = self.max_correction_mm
        clipped = abs(ax) > bound or abs(ay) > bound
        reach = 2.0 * self.lost_mm  # farther is lost anyway; keeps the aim inside the travel
        cx, cy = self._correction
        self._correction = (
            min(max(cx + min(max(ax, -bound), bound), -reach), reach),
            min(max(cy + min(max(ay, -bound), bound), -reach), reach),
        )  # np.clip's min(max(x, lo), hi), on floats
        return run, self._aim(), clipped, refused

    def finish_step(
        self, frame: Frame | Ended, clipped: bool, refused: str
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        """The second half of :meth:`step`: the frame that arrived (or the run's end)
        observed and rewarded."""
        if isinstance(frame, Ended):
            obs, reward, terminated, truncated, info = self._ended(frame)
            info["action_clipped"], info["action_refused"] = clipped, refused
            return obs, reward, terminated, truncated, info
        obs, info = self._observe(frame)
        info["action_clipped"], info["action_refused"] = clipped, refused
        error = info["error_mm"]
        reward = -error
        terminated = truncated = False
        if self._s_true >= self.truth.length_mm - self.end_tolerance_mm:
            terminated, info["status"] = True, "completed"
        elif error > self.lost_mm:
            terminated, info["status"] = True, "lost_seam"
            reward -= self._lost_penalty()
        elif frame.t_s >= self.max_time_s:
            truncated, info["status"] = True, "time_limit"
        if terminated or truncated:
            self._stop()
        return obs, reward, terminated, truncated, info

    def close(self) -> None:
        self._stop()
        super().close()

    # ----------------------------------------------------------------- internals
    def _stop(self) -> None:
        if self._run is not None:
            self._run.stop()
            self._run = None

    def _aim(self) -> tuple[Vec, bool]:
        """Aim ``lead_mm`` ahead of the torch along the nominal path, shifted by the
        correction: the target (world, mm) and whether to arrive there at rest (the last
        stretch, at the path's end)."""
        s = min(self._s_nominal + self.lead_mm, self.nominal.length_mm)
        (px, py, pz), _, (ax, ay, az), (bx, by, bz) = self.nominal.frame_floats(s)
        c_lat, c_vert = self._correction
        target = (px + c_lat * ax + c_vert * bx, py + c_lat * ay + c_vert * by,
                  pz + c_lat * az + c_vert * bz)  # fmt: skip
        return target, s >= self.nominal.length_mm

    def _observe(self, frame: Frame) -> tuple[NDArray[np.float32], dict[str, Any]]:
        tcp = np.asarray(frame.tcp_world, dtype=np.float64)
        x, y, z = tcp.tolist()
        vx, vy, vz = np.asarray(frame.velocity_world, dtype=np.float64).tolist()
        velocity = (vx, vy, vz)
        self._s_nominal = s_nom = self.nominal.locate(tcp, self._s_nominal)
        (px, py, pz), tangent, lateral, normal = self.nominal.frame_floats(s_nom)
        off = (x - px, y - py, z - pz)
        self._s_true = s_true = self.truth.locate(tcp, self._s_true)
        profile = frame.profile
        valid = profile.valid
        assert valid is not None
        c_lat, c_vert = self._correction
        torch = np.array((
            _dot(off, lateral), _dot(off, normal),
            _dot(velocity, lateral), _dot(velocity, normal), _dot(velocity, tangent),
            c_lat, c_vert, frame.t_s, s_nom / self.nominal.length_mm,
        ))  # fmt: skip
        obs = np.empty(3 * self.rays + len(TORCH_STATE), dtype=np.float32)
        fill_observation(profile.points_laser, valid, torch, OBSERVATION_LIMIT, obs)
        seam_point = self.truth.frame_floats(s_true)[0]
        error = math.dist((x, y, z), seam_point)
        self._last_obs = obs
        info = {
            "t_s": frame.t_s,
            "t_capture_s": frame.measurement.t_capture_s,
            "error_mm": error,
            "arc_length_mm": s_true,
            "seam_found": bool(frame.feature),
            "status": "",
        }
        return obs, info

    def _lost_penalty(self) -> float:
        frames_left = (self.truth.length_mm - self._s_true) / (
            self.speed_mm_s * self.frame_period_s
        )
        return self.lost_mm * max(frames_left, 0.0)

    def _ended(self, ended: Ended) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        """The loop stopped by itself (an axis limit, a stall, its own time limit)."""
        self._stop()
        if ended.error is not None:
            raise ended.error
        status, t_s = ended.outcome()
        info = {"t_s": t_s, "status": status}
        obs = self._last_obs.copy()
        if status == "completed":
            return obs, 0.0, True, False, info
        if status in ("lost_seam", "limit_violation"):
            return obs, -self._lost_penalty(), True, False, info
        return obs, 0.0, False, True, info  # stalled

    def _profile_length(self) -> int:
        """The number of points in the scene's profiles (its rays), from one scan at the start
        (drawn from a throw-away copy of the noise generator's state)."""
        parts = self.parts
        robot = parts.robot
        if parts.start_joints is not None:
            state = robot.state_at_joints(parts.start_joints)
        else:
            state = robot.state_at(robot.q_from_world(parts.tcp_start_world))
        saved = self._rng.bit_generator.state
        assert parts.scan is not None
        profile, _ = parts.scan(robot.sensor_pose(state), 0.0)
        self._rng.bit_generator.state = saved
        return len(profile.points_laser)


def read_action(action: Any) -> tuple[FloatArray, str]:
    """The action as a ``(2,)`` float64 array, and ``""``; or, for an action that is not two
    finite numbers, zeros and the reason it was refused."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        return np.zeros(2), f"{type(action).__name__} is not an array of two numbers"
    if a.shape != (2,):
        return np.zeros(2), f"its shape is {a.shape}, not (2,)"
    if not np.isfinite(a).all():
        return np.zeros(2), f"{a.tolist()} is not finite (the policy gave NaN or inf)"
    return a, ""


def _action_floats(action: Any) -> tuple[float, float, str]:
    """:func:`read_action` as two floats and the reason (a float array of two finite numbers,
    the usual action, is read without numpy's conversions)."""
    if type(action) is np.ndarray and action.shape == (2,) and action.dtype.kind == "f":
        ax, ay = action.tolist()  # float32 or float64 -> the same doubles as asarray's
        if math.isfinite(ax) and math.isfinite(ay):
            return ax, ay, ""
    a, refused = read_action(action)
    ax, ay = a.tolist()
    return ax, ay, refused


def _check_number(name: str, value: Any, zero: bool = False) -> None:
    """Refuse what is not a finite number > 0 (>= 0 with ``zero``), naming the argument."""
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not zero):
        raise SceneError(
            f"{value!r} is not usable", field=name, fix=f"give a number {'>=' if zero else '>'} 0"
        )


def _with_start(parts: Parts, start: FloatArray) -> Parts:
    import dataclasses

    return dataclasses.replace(parts, tcp_start_world=np.asarray(start, dtype=float))
