"""``seamtrack bench gym``: the Gymnasium environment's steps per second, on 1 and 2 processes,
and where a step's time goes.

Scene: ``paper-v-groove`` (1024 rays, 100 frames/s, 1 kHz control) over the first
:data:`SEAM_LENGTH_MM` of the paper's curve; the action is zero (the policy costs nothing), and
an episode that ends is reset at once (the reset counts in the time).

Rows:

1. ``in-process loop``: :func:`seamtrack.simulation.loop.run` of the same scene with its own
   tracker, frames per wall second (the reference the environment adds to);
2. ``1 env, this process``: ``env.step`` in a loop (its control ticks compiled,
   ``engine="compiled"``); its step split, in CPU time, into the sensing (ray cast and
   extraction), the loop's other work between two frames (ten control ticks and the frame's
   bookkeeping), the environment's own work (observation, reward, command), and the wall time
   beyond the CPU time (waiting: other work on the machine);
3. ``1 env, lockstep loop``: the same with ``engine="lockstep"`` (the loop itself in a
   coroutine, its ticks in Python: how the environment ran before its ticks were compiled);
4. ``AsyncVectorEnv, 1 process`` and ``2 processes``: environment steps per second of all
   workers together (what the pipes and pickling cost shows in the first; the second scales it
   on two cores);
5. ``BatchedVectorEnv``: :class:`seamtrack.gym.vector.BatchedVectorEnv`, 16 environments in
   one process, then in 2 processes of 8 (this one and a worker: one round trip a step,
   observations in shared memory; each batch's ticks in one compiled call): the goal (issue
   41) is twice the single env's steps/s on 2 cores (``ratio_to_one_env``).

The target (issue 26): >= 1,000 steps/s on one core, on a quiet machine; the 1-minute load
average before each row is written beside it.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

#: The shortened seam (mm of X along the paper's curve) and its overrides.
SEAM_LENGTH_MM = 100.0
OVERRIDES: dict[str, Any] = {"workpiece.params.seam_length_mm": SEAM_LENGTH_MM}
TARGET_STEPS_PER_S = 1000.0


def _single(steps: int, engine: str = "compiled") -> dict[str, Any]:
    import gymnasium

    from seamtrack.gym import SeamTrackEnv
    from seamtrack.gym.lockstep import LockstepRun
    from seamtrack.gym.stepper import HeldRun
    from seamtrack.simulation.loop import run

    env = gymnasium.make(
        "seamtrack/Scene-v0", scene="paper-v-groove", overrides=OVERRIDES, engine=engine
    )
    base = env.unwrapped
    assert isinstance(base, SeamTrackEnv)
    parts = base.parts
    sensed = [0.0]
    scan = parts.scan
    assert scan is not None

    def timed_scan(*args: Any) -> Any:
        start = time.process_time()
        out = scan(*args)
        sensed[0] += time.process_time() - start
        return out

    # the reference: the in-process loop of the same parts, its own tracker, to the end (run
    # twice: the first run loads the compiled kernels)
    reference_parts = dataclasses.replace(parts, sense=lambda T, t, h=None: scan(T, t, h)[1])
    run(reference_parts)
    load = os.getloadavg()[0]
    start = time.perf_counter()
    result = run(reference_parts)
    loop_wall = time.perf_counter() - start
    frames = int(result.summary["frames"])
    reference = {
        "row": "in-process loop",
        "load_average_before": load,
        "frames": frames,
        "frames_per_s": frames / loop_wall,
        "ms_per_frame": 1e3 * loop_wall / frames,
    }

    base.parts = dataclasses.replace(parts, scan=timed_scan)
    in_loop = [0.0]  # CPU time inside the loop (sensing and control ticks)
    # what env.step calls to run the loop to the next frame
    run_type: Any = HeldRun if base.engine == "compiled" else LockstepRun
    method = "advance" if base.engine == "compiled" else "next_frame"
    next_frame = getattr(run_type, method)

    def timed_next_frame(self: Any, *args: Any, **kwargs: Any) -> Any:
        start = time.process_time()
        out = next_frame(self, *args, **kwargs)
        in_loop[0] += time.process_time() - start
        return out

    zero = np.zeros(2, dtype=np.float32)
    env.reset(seed=0)
    load = os.getloadavg()[0]
    sensed[0] = 0.0
    setattr(run_type, method, timed_next_frame)
    try:
        wall = time.perf_counter()
        cpu = time.process_time()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(zero)
            if terminated or truncated:
                env.reset()
        wall = time.perf_counter() - wall
        cpu = time.process_time() - cpu
    finally:
        setattr(run_type, method, next_frame)
    env.close()
    per = 1e3 / steps
    single = {
        "row": "1 env, this process" if engine == "compiled" else "1 env, lockstep loop",
        "engine": base.engine,
        "load_average_before": load,
        "steps": steps,
        "steps_per_s": steps / wall,
        "ms_per_step": wall * per,
        "sensing_ms": sensed[0] * per,
        "loop_ticks_ms": max(in_loop[0] - sensed[0], 0.0) * per,
        "env_ms": max(cpu - in_loop[0], 0.0) * per,
        "waiting_ms": max(wall - cpu, 0.0) * per,
    }
    return {"reference": reference, "single": single}


def _steps_per_s(vec: Any, num_envs: int, steps: int, row: str) -> dict[str, Any]:
    """Zero actions on a vector env, seeds 0, 1, ...: its steps per second (of all its
    environments together), after one warming step; an ended episode resets on the next step
    (autoreset). Closes the env."""
    try:
        vec.reset(seed=0)
        zeros = np.zeros((num_envs, 2), dtype=np.float32)
        vec.step(zeros)  # the workers warm
        load = os.getloadavg()[0]
        rounds = max(1, steps // num_envs)
        start = time.perf_counter()
        for _ in range(rounds):
            vec.step(zeros)
        wall = time.perf_counter() - start
    finally:
        vec.close()
    return {
        "row": row,
        "load_average_before": load,
        "steps": rounds * num_envs,
        "steps_per_s": rounds * num_envs / wall,
        "ms_per_step": 1e3 * wall / (rounds * num_envs),
    }


def _vector(processes: int, steps: int) -> dict[str, Any]:
    import gymnasium

    import seamtrack.gym  # noqa: F401

    vec = gymnasium.make_vec(
        "seamtrack/Scene-v0",
        num_envs=processes,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},  # a fork inherits other threads' held locks
        scene="paper-v-groove",
        overrides=OVERRIDES,
    )
    row = f"AsyncVectorEnv, {processes} process{'es' if processes > 1 else ''}"
    return _steps_per_s(vec, processes, steps, row)


def _batched(workers: int, num_envs: int, steps: int) -> dict[str, Any]:
    from seamtrack.gym.vector import BatchedVectorEnv

    vec = BatchedVectorEnv(num_envs, workers=workers, scene="paper-v-groove", overrides=OVERRIDES)
    row = f"BatchedVectorEnv, {num_envs} envs, {workers} process{'es' if workers > 1 else ''}"
    return _steps_per_s(vec, num_envs, steps, row)


def bench_gym(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """Steps per second of ``seamtrack/Scene-v0`` on 1 and 2 processes, and a step's split.

    Writes ``gym.json`` and ``gym.md`` into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
    quick : bool
        300 steps a row instead of 3,000 (a smoke test, not a measurement).
    """
    import seamtrack.gym  # noqa: F401  (a missing extra fails here, before anything is written)
    from seamtrack.bench.common import machine_info

    steps = 300 if quick else 3000
    first = _single(steps)
    lockstep = _single(steps, engine="lockstep")["single"]
    rows = [first["reference"], first["single"], lockstep, _vector(1, steps), _vector(2, steps),
            _batched(1, 16, steps), _batched(2, 16, steps)]  # fmt: skip
    one = first["single"]["steps_per_s"]
    for row in rows[3:]:
        row["ratio_to_one_env"] = row["steps_per_s"] / one
    report = {
        "machine": machine_info(),
        "scene": "paper-v-groove",
        "overrides": OVERRIDES,
        "target_steps_per_s": TARGET_STEPS_PER_S,
        "quick": quick,
        "rows": rows,
    }
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "gym.json").write_text(json.dumps(report, indent=2))
    (out / "gym.md").write_text(_markdown(rows))
    print(_markdown(rows), end="")
    return report


def _markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| row | steps (frames)/s | ms a step | x one env | load before |",
        "|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        rate = r.get("steps_per_s", r.get("frames_per_s", float("nan")))
        ms = r.get("ms_per_step", r.get("ms_per_frame", float("nan")))
        ratio = f"{r['ratio_to_one_env']:.2f}" if "ratio_to_one_env" in r else ""
        lines.append(
            f"| {r['row']} | {rate:,.0f} | {ms:.3f} | {ratio} | {r['load_average_before']:.2f} |"
        )
    for single in (r for r in rows if r["row"].startswith("1 env")):
        lines += [
            "",
            f"One step of {single['row']} (ms): "
            + ", ".join(
                f"{key[:-3].replace('_', ' ')} {single[key]:.3f}"
                for key in ("sensing_ms", "loop_ticks_ms", "env_ms", "waiting_ms")
            ),
        ]
    lines.append("")
    return "\n".join(lines)
