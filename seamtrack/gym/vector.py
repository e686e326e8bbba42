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
from multiprocessing.connection import Connection
from multiprocessing.shared_memory import SharedMemory
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from seamtrack.gym.env import SeamTrackEnv

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
    arrays they are given (rows ``indices`` of the batch's arrays)."""

    def __init__(self, indices: list[int], env_kwargs: dict[str, Any]) -> None:
        self.indices = indices
        self.envs = [SeamTrackEnv(**env_kwargs) for _ in indices]
        self.ended = np.zeros(len(indices), dtype=bool)

    def reset(
        self, arrays: dict[str, NDArray[Any]], seeds: list[int | None], options: Any
    ) -> list[dict[str, Any]]:
        infos = []
        for k, (i, env) in enumerate(zip(self.indices, self.envs, strict=True)):
            arrays["obs"][i], info = env.reset(seed=seeds[k], options=options)
            infos.append(info)
        self.ended[:] = False
        return infos

    def step(self, arrays: dict[str, NDArray[Any]]) -> list[dict[str, Any]]:
        infos = []
        for k, (i, env) in enumerate(zip(self.indices, self.envs, strict=True)):
            if self.ended[k]:  # NEXT_STEP: the episode ended last step; this one resets it
                arrays["obs"][i], info = env.reset()
                reward, terminated, truncated = 0.0, False, False
            else:
                arrays["obs"][i], reward, terminated, truncated, info = env.step(
                    arrays["action"][i]
                )
            arrays["reward"][i] = reward
            arrays["terminated"][i] = terminated
            arrays["truncated"][i] = truncated
            self.ended[k] = terminated or truncated
            infos.append(info)
        return infos

    def close(self) -> None:
        for env in self.envs:
            env.close()


def _attach(names: dict[str, str], n: int, size: int) -> tuple[list[SharedMemory], dict]:
    memories, arrays = [], {}
    for key, (dtype, shape) in SLOTS.items():
        memory = SharedMemory(name=names[key])
        memories.append(memory)
        arrays[key] = np.ndarray((n, *shape(size)), dtype=dtype, buffer=memory.buf)
    return memories, arrays


def _worker(
    conn: Connection, indices: list[int], env_kwargs: dict[str, Any], names: dict[str, str],
    n: int,
) -> None:  # fmt: skip
    """A worker process: builds its batch, then answers ``reset``, ``step`` and ``close``."""
    memories: list[SharedMemory] = []
    batch = None
    try:
        batch = Batch(indices, env_kwargs)
        size = observation_size(batch.envs[0])
        memories, arrays = _attach(names, n, size)
        conn.send(("ready", None))
        while True:
            command, payload = conn.recv()
            if command == "step":
                conn.send(("ok", batch.step(arrays)))
            elif command == "reset":
                conn.send(("ok", batch.reset(arrays, *payload)))
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
        Worker processes; 1 steps every environment in this process.
    context : str
        The multiprocessing start method (``spawn``: a fork would inherit other threads' held
        locks).
    **env_kwargs
        :class:`~seamtrack.gym.env.SeamTrackEnv`'s arguments (``scene``, ``overrides``, ...).
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(
        self, num_envs: int, *, workers: int | None = None, context: str = "spawn",
        **env_kwargs: Any,
    ) -> None:  # fmt: skip
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs: {num_envs!r}; give a whole number of at least 1")
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
        self._batch: Batch | None = None
        probe = SeamTrackEnv(**env_kwargs) if workers > 1 else None
        if probe is None:
            self._batch = Batch(self._slices[0], env_kwargs)
            single = self._batch.envs[0]
        else:
            single = probe
        self.single_observation_space = single.observation_space
        self.single_action_space = single.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        size = observation_size(single)
        if probe is not None:
            probe.close()
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
        for indices in self._slices:
            mine, theirs = ctx.Pipe()
            process = ctx.Process(
                target=_worker, args=(theirs, indices, env_kwargs, names, self.num_envs),
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

    def _infos(self, per_env: list[dict[str, Any]]) -> dict[str, Any]:
        infos: dict[str, Any] = {}
        for i, info in enumerate(per_env):
            infos = self._add_info(infos, info, i)
        return infos

    def _outputs(self) -> tuple[NDArray[Any], ...]:
        a = self._arrays
        return (a["obs"].copy(), a["reward"].copy(), a["terminated"].copy(),
                a["truncated"].copy())  # fmt: skip

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: {len(seeds)} seeds for {self.num_envs} environments")
        if self._batch is not None:
            per_env = self._batch.reset(self._arrays, seeds, options)
        else:
            for conn, indices in zip(self._conns, self._slices, strict=True):
                conn.send(("reset", ([seeds[i] for i in indices], options)))
            per_env = [info for answer in self._gather() for info in answer]
        return self._arrays["obs"].copy(), self._infos(per_env)

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
        if self._batch is not None:
            per_env = self._batch.step(self._arrays)
        else:
            for conn in self._conns:
                conn.send(("step", None))
            per_env = [info for answer in self._gather() for info in answer]
        obs, reward, terminated, truncated = self._outputs()
        return obs, reward, terminated, truncated, self._infos(per_env)

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
