"""The environment's compiled ticks (``engine="compiled"``, seamtrack.gym.stepper): the oracle
is the loop itself run in lockstep (``engine="lockstep"``), whole episodes compared to the byte:
observations, rewards, end flags and infos."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from seamtrack.errors import SceneError
from seamtrack.gym import SeamTrackEnv

pytestmark = [pytest.mark.embree, pytest.mark.cad]

SCENE = "paper-v-groove"
#: 20 mm of the paper's curve, 256 rays: episodes of a few hundred frames.
SHORT = {"workpiece.params.seam_length_mm": 20.0, "sensor.rays": 256}


def _run(env: SeamTrackEnv, actions: np.ndarray, seed: int) -> list[tuple]:
    """One episode (at most ``len(actions)`` steps): each step's bytes and values."""
    obs, info = env.reset(seed=seed)
    out: list[tuple] = [(obs.tobytes(), sorted(info.items()))]
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        out.append((obs.tobytes(), reward, terminated, truncated, sorted(info.items())))
        if terminated or truncated:
            break
    return out


def _both(overrides: dict, actions: np.ndarray, seed: int, **kwargs: object) -> list[list]:
    runs = []
    for engine in ("compiled", "lockstep"):
        env = SeamTrackEnv(scene=SCENE, overrides={**SHORT, **overrides}, engine=engine, **kwargs)
        try:
            assert env.engine == engine
            runs.append(_run(env, actions, seed))
        finally:
            env.close()
    return runs


@pytest.mark.parametrize(
    ("overrides", "amplitude", "status"),
    [
        ({}, 0.0, "completed"),  # zero actions: to the seam's end
        ({}, 1.0, "lost_seam"),  # a random walk off the seam
        # a servo (interpolator and position loops) and frames that arrive 1.5 frames late
        ({"robot.servo_gain_1_s": 40.0, "sensor.latency_s": 0.015}, 0.05, "completed"),
    ],
    ids=["zero", "random-walk", "servo-latency"],
)
def test_compiled_ticks_step_the_loops_episode(overrides, amplitude, status) -> None:
    actions = np.random.default_rng(3).uniform(-amplitude, amplitude, size=(3000, 2))
    compiled, lockstep = _both(overrides, actions.astype(np.float32), seed=3)
    assert dict(compiled[-1][-1])["status"] == status
    assert len(compiled) > 50
    assert compiled == lockstep


def test_the_loops_own_time_limit_ends_both_alike() -> None:
    """The loop's time limit reached before the environment's: the run's end (``stalled``,
    at the loop's last tick) is reported alike."""
    actions = np.zeros((3000, 2), dtype=np.float32)
    compiled, lockstep = _both({"simulation.time_limit_s": 0.5}, actions, seed=0, max_time_s=5.0)
    last = dict(compiled[-1][-1])
    assert last["status"] == "stalled" and compiled[-1][3]  # truncated
    assert last["t_s"] == pytest.approx(0.5)
    assert compiled == lockstep


def test_a_scene_the_ticks_cannot_run_falls_back_to_the_loop() -> None:
    """A rotated robot base: ``auto`` runs the loop itself; ``compiled`` is refused in one
    line naming the argument; an unknown engine too."""
    rotated = {**SHORT, "robot.base_rotation_deg": [0.0, 0.0, 0.5]}
    env = SeamTrackEnv(scene=SCENE, overrides=rotated)
    try:
        assert env.engine == "lockstep"
        env.reset(seed=0)
        env.step(np.zeros(2, dtype=np.float32))
    finally:
        env.close()
    with pytest.raises(SceneError, match="engine") as refused:
        SeamTrackEnv(scene=SCENE, overrides=rotated, engine="compiled")
    assert "\n" not in str(refused.value)
    with pytest.raises(SceneError, match="engine"):
        SeamTrackEnv(scene=SCENE, overrides=SHORT, engine="turbo")


def test_environments_that_share_a_caster_step_alike_and_other_scenes_are_refused() -> None:
    """``share_with``: the second environment casts on the first one's scene in memory (and
    keeps its own section seeds); its episode is the one it steps alone. A caster of another
    scene's mesh is refused in one line."""
    actions = np.random.default_rng(5).uniform(-0.3, 0.3, size=(300, 2)).astype(np.float32)
    alone = SeamTrackEnv(scene=SCENE, overrides=SHORT)
    first = SeamTrackEnv(scene=SCENE, overrides=SHORT)
    shared = SeamTrackEnv(scene=SCENE, overrides=SHORT, share_with=first)
    try:
        assert shared.parts.caster is first.parts.caster
        assert alone.parts.caster is not first.parts.caster
        first.reset(seed=1)  # the first one steps between: its seeds must not matter

        def poke(action: np.ndarray) -> None:
            if first.step(action)[2:4] != (False, False):
                first.reset()

        for _ in range(40):
            poke(actions[0])
        want = _run(alone, actions, seed=2)
        got = []
        obs, info = shared.reset(seed=2)
        got.append((obs.tobytes(), sorted(info.items())))
        for action in actions:
            poke(-action)
            obs, reward, terminated, truncated, info = shared.step(action)
            got.append((obs.tobytes(), reward, terminated, truncated, sorted(info.items())))
            if terminated or truncated:
                break
        assert got == want
    finally:
        for env in (alone, first, shared):
            env.close()
    other = {**SHORT, "workpiece.params.seam_length_mm": 25.0}
    with pytest.raises(SceneError, match="share_with") as refused:
        SeamTrackEnv(scene=SCENE, overrides=other, share_with=alone)
    assert "\n" not in str(refused.value)
