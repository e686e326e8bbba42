"""``BatchedVectorEnv``: N seamtrack scenes behind Gymnasium's ``VectorEnv`` API, stepped in
batches, a batch per core.

Gymnasium's ``AsyncVectorEnv`` runs one environment per process and pays a pipe round trip and
a pickled observation for every environment at every step; a seamtrack step (one sensor frame,
0.4 ms) is too short for that to pay off: two processes stepped fewer steps per second than one
environment in the caller's process (``seamtrack bench gym``). Here, as in envpool's design,
each worker process holds a *batch* of environments and steps all of them on one message; the
observations, rewards and flags go through shared memory, so a step costs one round trip per
worker whatever the batch size. With one worker (``workers=1``) the batch is stepped in the
caller's process, with no IPC at all.

The semantics are Gymnasium's own:

- ``reset(seed=s)`` seeds environment ``i`` with ``s + i`` (a list gives each its seed), so the
  same seeds give the same bytes as ``SyncVectorEnv`` over the same environments, on any number
  of workers;
- autoreset in Gymnasium's default ``NEXT_STEP`` mode: the step after an environment's episode
  ends resets it (its action is ignored; reward 0, neither terminated nor truncated);
- ``infos`` are batched with Gymnasium's ``_key`` masks.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import traceback
import warnings
from multiprocessing.connection import Connection
from multiprocessing.shared_memory import SharedMemory
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from seamtrack.control.tracking import Command
from seamtrack.gym.env import BadActionWarning, SeamTrackEnv
from seamtrack.gym.stepper import HeldRun, TickBatch

#: The shared arrays: name -> (dtype, per-environment shape given the observation size).
SLOTS: dict[str, tuple[type, Any]] = {
    "obs": (np.float32, lambda size: (size,)),
    "reward": (np.float64, lambda size: ()),
    "terminated": (np.bool_, lambda size: ()),
    "truncated": (np.bool_, lambda size: ()),
    "action": (np.float32, lambda size: (2,)),
}


def observation_size(env: SeamTrackEnv) -> int:
    """The length of an environment's flat observation."""
    shape = env.observation_space.shape
    assert shape is not None
    return int(shape[0])


class Batch:
    """Environments stepped together with Gymnasium's NEXT_STEP autoreset, writing into
    arrays they are given (rows ``indices`` of the batch's arrays).

    Where the environments' ticks run compiled (``engine="compiled"``, the usual gantry), they
    share one :class:`~seamtrack.gym.stepper.TickBatch`: a step takes every environment's
    command, runs the control ticks of all of them to their next frame in one compiled call,
    then senses each one's frame and observes it."""

    def __init__(
        self, indices: list[int], env_kwargs: dict[str, Any],
        mode: AutoresetMode = AutoresetMode.NEXT_STEP,
    ) -> None:  # fmt: skip
        self.indices = indices
        self.mode = mode
        first = SeamTrackEnv(**env_kwargs)  # the others cast on its scene: one in memory
        self.envs = [first] + [SeamTrackEnv(**env_kwargs, share_with=first) for _ in indices[1:]]
        self.ended = np.zeros(len(indices), dtype=bool)
        self.ticks: TickBatch | None = None
        if all(env.engine == "compiled" for env in self.envs):
            self.ticks = TickBatch(self.envs[0].parts, len(indices))
            for k, env in enumerate(self.envs):
                env.tick_batch, env.tick_row = self.ticks, k

    def reset(
        self, arrays: dict[str, NDArray[Any]], seeds: list[int | None], options: Any,
        mask: list[bool] | None = None,
    ) -> list[dict[str, Any]]:  # fmt: skip
        """Reset every environment, or those of ``mask``; their infos (``{}`` for the
        others)."""
        infos: list[dict[str, Any]] = []
        for k, (i, env) in enumerate(zip(self.indices, self.envs, strict=True)):
            if mask is not None and not mask[k]:
                infos.append({})
                continue
            arrays["obs"][i], info = env.reset(seed=seeds[k], options=options)
            infos.append(info)
            self.ended[k] = False
        return infos

    def step(self, arrays: dict[str, NDArray[Any]]) -> list[dict[str, Any]]:
        infos: list[dict[str, Any]] = [{}] * len(self.envs)
        waiting: dict[int, tuple[HeldRun, bool, str]] = {}  # their ticks run batched
        for k, (i, env) in enumerate(zip(self.indices, self.envs, strict=True)):
            if self.ended[k]:
                if self.mode == AutoresetMode.DISABLED:
                    raise ValueError(
                        f"environment {i}'s episode has ended; with autoreset_mode=DISABLED "
                        "reset it first: reset(options={'reset_mask': mask})"
                    )
                # NEXT_STEP: the episode ended last step; this one resets it
                arrays["obs"][i], infos[k] = env.reset()
                self._record(arrays, k, 0.0, False, False)
                continue
            run, (target, at_end), clipped, refused = env.begin_step(arrays["action"][i])
            if refused:
                warnings.warn(
                    f"seamtrack.gym: action refused (environment {i}): {refused}; the step "
                    "applies no correction",
                    BadActionWarning,
                    stacklevel=3,
                )
            if self.ticks is not None and isinstance(run, HeldRun):
                ended = run.hold(target, env.speed_mm_s, at_end)
                if ended is None:
                    waiting[k] = (run, clipped, refused)
                    continue
                out = env.finish_step(ended, clipped, refused)
            else:
                command = Command(np.array(target), env.speed_mm_s, None, at_end)
                out = env.finish_step(run.next_frame(command), clipped, refused)
            infos[k] = self._finish(arrays, k, out)
        rows = np.fromiter(waiting, dtype=np.int64, count=len(waiting))
        while len(rows):
            assert self.ticks is not None
            self.ticks.run(rows)  # every waiting environment's ticks, to its next event
            still = []
            for k in rows.tolist():
                run, clipped, refused = waiting[k]
                frame = run.after_ticks()  # a frame sensed, or the end of the run
                if frame is None:
                    still.append(k)
                    continue
                infos[k] = self._finish(
                    arrays, k, self.envs[k].finish_step(frame, clipped, refused)
                )
            rows = np.array(still, dtype=np.int64)
        return infos

    def _finish(
        self, arrays: dict[str, NDArray[Any]], k: int,
        out: tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]],
    ) -> dict[str, Any]:  # fmt: skip
        obs, reward, terminated, truncated, info = out
        i = self.indices[k]
        arrays["obs"][i] = obs
        self._record(arrays, k, reward, terminated, truncated)
        if self.mode == AutoresetMode.SAME_STEP and self.ended[k]:
            # reset at once: the last observation and info go in final_obs and final_info
            arrays["obs"][i], reset_info = self.envs[k].reset()
            self.ended[k] = False
            return {"final_obs": obs, "final_info": info, **reset_info}
        return info

    def _record(
        self, arrays: dict[str, NDArray[Any]], k: int, reward: float, terminated: bool,
        truncated: bool,
    ) -> None:  # fmt: skip
        i = self.indices[k]
        arrays["reward"][i] = reward
        arrays["terminated"][i] = terminated
        arrays["truncated"][i] = truncated
        self.ended[k] = terminated or truncated

    def close(self) -> None:
        for env in self.envs:
            env.close()


def _per_env(columns: dict[str, list[tuple[int, Any]]], indices: list[int]) -> list[dict]:
    """A batch's infos by key back to one dict per environment (``indices``, in order)."""
    where = {i: k for k, i in enumerate(indices)}
    per_env: list[dict[str, Any]] = [{} for _ in indices]
    for key, pairs in columns.items():
        for i, value in pairs:
            per_env[where[i]][key] = value
    return per_env


def _reset_mask(mask: Any, n: int) -> list[bool]:
    """``options["reset_mask"]`` checked as ``SyncVectorEnv`` checks it (a ``(n,)`` bool
    array with a True), as a list."""
    if not isinstance(mask, np.ndarray):
        raise TypeError(f"options['reset_mask'] must be a numpy array, got {type(mask)}")
    if mask.shape != (n,):
        raise ValueError(f"options['reset_mask'] must have shape ({n},), got {mask.shape}")
    if mask.dtype != np.bool_:
        raise TypeError(f"options['reset_mask'] must have dtype=np.bool_, got {mask.dtype}")
    if not mask.any():
        raise ValueError("options['reset_mask'] must contain at least one True")
    return [bool(x) for x in mask]


#: A batch's infos as it hands them on: ``("columns", {key: [(env index, value), ...]})``
#: (built where the batch runs, merged by key), or ``("per_env", [info, ...])`` when one holds
#: what only Gymnasium's ``_add_info`` batches (``final_obs``, a nested dict).
Infos = tuple[str, Any]


def info_columns(per_env: list[dict[str, Any]], indices: list[int]) -> Infos:
    """A batch's infos (``per_env[k]`` of environment ``indices[k]``) by key, in the order
    ``_add_info`` meets the keys (see :data:`Infos`)."""
    columns: dict[str, list[tuple[int, Any]]] = {}
    for i, info in zip(indices, per_env, strict=True):
        for key, value in info.items():
            if key == "final_obs" or isinstance(value, dict):
                return "per_env", per_env
            pairs = columns.get(key)
            if pairs is None:
                columns[key] = [(i, value)]
            else:
                pairs.append((i, value))
    return "columns", columns


def batch_infos(columns: dict[str, list[tuple[int, Any]]], n: int) -> dict[str, Any]:
    """Gymnasium's batched infos of scalar and array values: for each key (``columns``: the
    environments that gave it and their values, in order), an array of ``n`` (of the first
    value's type; an object array for other values) and the mask ``_key``, as
    ``VectorEnv._add_info`` builds them."""
    infos: dict[str, Any] = {}
    for key, pairs in columns.items():
        first = pairs[0][1]
        if type(first) in (int, float, bool) or issubclass(type(first), np.number):
            array = np.zeros(n, dtype=type(first))
        elif isinstance(first, np.ndarray):
            array = np.zeros((n, *first.shape), dtype=first.dtype)
        else:
            array = np.full(n, fill_value=None, dtype=object)
        mask = np.zeros(n, dtype=np.bool_)
        for i, value in pairs:
            array[i] = value
            mask[i] = True
        infos[key], infos[f"_{key}"] = array, mask
    return infos


def _attach(names: dict[str, str], n: int, size: int) -> tuple[list[SharedMemory], dict]:
    memories, arrays = [], {}
    for key, (dtype, shape) in SLOTS.items():
        memory = SharedMemory(name=names[key])
        memories.append(memory)
        arrays[key] = np.ndarray((n, *shape(size)), dtype=dtype, buffer=memory.buf)
    return memories, arrays


def _worker(
    conn: Connection, indices: list[int], env_kwargs: dict[str, Any], names: dict[str, str],
    n: int, mode: str,
) -> None:  # fmt: skip
    """A worker process: builds its batch, then answers ``reset``, ``step`` and ``close``."""
    memories: list[SharedMemory] = []
    batch = None
    try:
        batch = Batch(indices, env_kwargs, AutoresetMode(mode))
        size = observation_size(batch.envs[0])
        memories, arrays = _attach(names, n, size)
        conn.send(("ready", None))
        while True:
            command, payload = conn.recv()
            if command == "step":
                conn.send(("ok", info_columns(batch.step(arrays), indices)))
            elif command == "reset":
                conn.send(("ok", info_columns(batch.reset(arrays, *payload), indices)))
            else:
                conn.send(("ok", None))
                return
    except KeyboardInterrupt:  # the caller's Ctrl-C reaches its workers too: it decides
        return
    except BaseException as exc:
        try:
            conn.send(("error", (exc, traceback.format_exc())))
        except Exception:
            conn.send(("error", (RuntimeError(str(exc)), traceback.format_exc())))
    finally:
        if batch is not None:
            batch.close()
        for memory in memories:
            memory.close()


class BatchedVectorEnv(gymnasium.vector.VectorEnv):
    """``num_envs`` :class:`~seamtrack.gym.env.SeamTrackEnv` of one scene, stepped in
    ``workers`` batches (default: one per core the process may use, at most ``num_envs``).

    Parameters
    ----------
    num_envs : int
        How many environments.
    workers : int, optional
        The processes that step batches: this one and ``workers - 1`` worker processes (this
        process steps the first batch while the workers step theirs); 1 steps every
        environment in this process.
    context : str
        The multiprocessing start method (``spawn``: a fork would inherit other threads' held
        locks).
    autoreset_mode : AutoresetMode or str
        Gymnasium's autoreset modes, as ``SyncVectorEnv`` runs them: ``NEXT_STEP`` (the
        default: the step after an episode's end resets it), ``SAME_STEP`` (the step that ends
        it resets it; the last observation and info in ``infos["final_obs"]`` and
        ``infos["final_info"]``) or ``DISABLED`` (``reset(options={"reset_mask": mask})``
        resets the ended ones; stepping an ended one is an error).
    **env_kwargs
        :class:`~seamtrack.gym.env.SeamTrackEnv`'s arguments (``scene``, ``overrides``, ...).
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(
        self, num_envs: int, *, workers: int | None = None, context: str = "spawn",
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP, **env_kwargs: Any,
    ) -> None:  # fmt: skip
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs: {num_envs!r}; give a whole number of at least 1")
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            names = ", ".join(m.value for m in AutoresetMode)
            raise ValueError(f"autoreset_mode: {autoreset_mode!r}; use one of {names}") from None
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        workers = min(num_envs, cores if workers is None else int(workers))
        if workers < 1:
            raise ValueError(f"workers: {workers}; give at least 1")
        self.num_envs = num_envs
        self.workers = workers
        slices = [list(part) for part in np.array_split(np.arange(num_envs), workers)]
        self._slices = [[int(i) for i in part] for part in slices]
        self._memories: list[SharedMemory] = []
        self._conns: list[Connection] = []
        self._processes: list[Any] = []
        # The caller's process steps the first batch itself (it would only wait for the
        # workers otherwise); worker processes step the others.
        self._batch = Batch(self._slices[0], env_kwargs, mode)
        single = self._batch.envs[0]
        self.single_observation_space = single.observation_space
        self.single_action_space = single.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        size = observation_size(single)
        if workers > 1:
            self._arrays = self._share(size)
            self._start(context, env_kwargs)
        else:
            self._arrays = {
                key: np.zeros((num_envs, *shape(size)), dtype=dtype)
                for key, (dtype, shape) in SLOTS.items()
            }
        self._closed = False

    # ------------------------------------------------------------------ set-up
    def _share(self, size: int) -> dict[str, NDArray[Any]]:
        arrays = {}
        for key, (dtype, shape) in SLOTS.items():
            nbytes = max(1, self.num_envs * int(np.prod(shape(size))) * np.dtype(dtype).itemsize)
            memory = SharedMemory(create=True, size=nbytes)
            self._memories.append(memory)
            arrays[key] = np.ndarray((self.num_envs, *shape(size)), dtype=dtype, buffer=memory.buf)
        return arrays

    def _start(self, context: str, env_kwargs: dict[str, Any]) -> None:
        ctx: Any = mp.get_context(context)
        names = dict(zip(SLOTS, (m.name for m in self._memories), strict=True))
        for indices in self._slices[1:]:
            mine, theirs = ctx.Pipe()
            process = ctx.Process(
                target=_worker,
                args=(theirs, indices, env_kwargs, names, self.num_envs, self.autoreset_mode.value),
                daemon=True,
            )  # fmt: skip
            process.start()
            theirs.close()
            self._conns.append(mine)
            self._processes.append(process)
        try:
            self._gather()  # every worker built its batch
        except BaseException:
            self.close()
            raise

    @property
    def _batch_here(self) -> Batch:
        """The batch the caller's process steps."""
        assert self._batch is not None, "the vector env is closed"
        return self._batch

    def _here_then_gather(self, here: Any) -> list[Infos]:
        """Run ``here`` (this process's batch: a reset or a step, its infos) while the workers
        run theirs, then every batch's infos, in order; an error raised here is raised after
        the workers answered (their pipes stay in step)."""
        try:
            local = info_columns(here(), self._slices[0])
        except BaseException:
            if self._conns:
                try:
                    self._gather()
                except BaseException:
                    pass
            raise
        return [local, *self._gather()] if self._conns else [local]

    def _gather(self) -> list[Any]:
        """Every worker's answer, in order; the first error is raised here."""
        answers, error = [], None
        for conn in self._conns:
            try:
                status, payload = conn.recv()
            except EOFError:
                status, payload = "error", (RuntimeError("a worker process died"), "")
            if status == "error" and error is None:
                error = payload[0]
            answers.append(payload)
        if error is not None:
            raise error
        return answers

    def _infos(self, parts: list[Infos]) -> dict[str, Any]:
        """Gymnasium's batched infos (``_add_info``'s arrays and ``_key`` masks) from each
        batch's (in the order of their environments), merged a key at a time."""
        if all(kind == "columns" for kind, _ in parts):
            columns: dict[str, list[tuple[int, Any]]] = {}
            for _, part in parts:
                for key, pairs in part.items():
                    columns.setdefault(key, []).extend(pairs)
            return batch_infos(columns, self.num_envs)
        per_env: list[dict[str, Any]] = []
        for (kind, part), indices in zip(parts, self._slices, strict=True):
            per_env += part if kind == "per_env" else _per_env(part, indices)
        infos: dict[str, Any] = {}
        for j, each in enumerate(per_env):
            infos = self._add_info(infos, each, j)
        return infos

    def _outputs(self) -> tuple[NDArray[Any], ...]:
        a = self._arrays
        return (a["obs"].copy(), a["reward"].copy(), a["terminated"].copy(),
                a["truncated"].copy())  # fmt: skip

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Reset every environment (seeds ``seed + i``, or one each from a list), or only
        those of ``options["reset_mask"]`` (a ``(num_envs,)`` bool array), as Gymnasium's
        ``SyncVectorEnv`` does."""
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: {len(seeds)} seeds for {self.num_envs} environments")
        mask = None
        if options is not None and "reset_mask" in options:
            options = dict(options)  # the caller's dict is left as it was
            mask = _reset_mask(options.pop("reset_mask"), self.num_envs)
        for conn, indices in zip(self._conns, self._slices[1:], strict=True):
            part = None if mask is None else [mask[i] for i in indices]
            conn.send(("reset", ([seeds[i] for i in indices], options, part)))
        first = self._slices[0]
        local = None if mask is None else [mask[i] for i in first]
        parts = self._here_then_gather(
            lambda: self._batch_here.reset(self._arrays, [seeds[i] for i in first], options, local)
        )
        return self._arrays["obs"].copy(), self._infos(parts)

    def step(
        self, actions: NDArray[Any]
    ) -> tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_],
               dict[str, Any]]:  # fmt: skip
        actions = np.asarray(actions, dtype=np.float32)
        if actions.shape != (self.num_envs, 2):
            raise ValueError(
                f"actions: shape {actions.shape}; give ({self.num_envs}, 2): a (lateral, "
                f"vertical) correction in mm for each environment"
            )
        self._arrays["action"][:] = actions
        for conn in self._conns:
            conn.send(("step", None))
        parts = self._here_then_gather(lambda: self._batch_here.step(self._arrays))
        obs, reward, terminated, truncated = self._outputs()
        return obs, reward, terminated, truncated, self._infos(parts)

    def close_extras(self, **kwargs: Any) -> None:
        if getattr(self, "_closed", True) and not self._memories:
            return
        self._closed = True
        if self._batch is not None:
            self._batch.close()
        for conn in self._conns:
            try:
                conn.send(("close", None))
                conn.recv()
            except (BrokenPipeError, EOFError, OSError):
                pass
            conn.close()
        for process in self._processes:
            process.join(timeout=10)
            if process.is_alive():
                process.kill()
        for memory in self._memories:
            memory.close()
            memory.unlink()
        self._memories, self._conns, self._processes = [], [], []
