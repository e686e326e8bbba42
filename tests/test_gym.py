"""The Gymnasium environment (``seamtrack.gym``): the API checker, seeding, a baseline policy
against doing nothing, the episode's end, vector environments, and the missing extra."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import seamtrack.gym as sgym  # noqa: E402
from seamtrack.errors import SceneError  # noqa: E402
from seamtrack.geometry.seam import paper_curve  # noqa: E402

pytestmark = [pytest.mark.embree, pytest.mark.cad]

#: paper-v-groove over the first 100 mm of the paper's curve (which bends 2.9 mm away from the
#: straight line joining its ends), at 10 mm/s: ~1,000 frames; 256 rays keep the tests short.
SHORT = {
    "workpiece.params.seam_length_mm": 100.0,
    "simulation.welding_speed_mm_s": 10.0,
    "sensor.rays": 256,
}
ID = "seamtrack/Scene-v0"


def make(**kwargs: object) -> gymnasium.Env:
    return gymnasium.make(ID, scene="paper-v-groove", overrides=SHORT, **kwargs)


def running(env: gymnasium.Env) -> bool:
    """Whether the environment holds a run of the loop that has not ended."""
    run = env.unwrapped._run
    return run is not None and run.alive


def episode(env: gymnasium.Env, policy: object, seed: int) -> dict:
    """One whole episode: observations, rewards, infos, and the end flags."""
    obs, info = env.reset(seed=seed)
    if hasattr(policy, "reset"):
        policy.reset()
    observations, rewards, infos = [obs], [], [info]
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        observations.append(obs)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            return {
                "obs": np.array(observations),
                "rewards": np.array(rewards),
                "infos": infos,
                "terminated": terminated,
                "truncated": truncated,
            }


def zero(obs: np.ndarray) -> np.ndarray:
    return np.zeros(2, dtype=np.float32)


def test_check_env_passes() -> None:
    env = make()
    try:
        check_env(env.unwrapped)
    finally:
        env.close()
    assert not running(env)


def test_spaces_follow_the_scene() -> None:
    env = make()
    try:
        base = env.unwrapped
        assert env.observation_space.shape == (3 * 256 + len(sgym.TORCH_STATE),)
        assert env.observation_space.dtype == np.float32
        assert env.action_space.shape == (2,)
        obs, _ = env.reset(seed=0)
        parts = sgym.split_observation(obs, base.rays)
        assert parts["profile"].shape == (256, 2) and parts["valid"].any()
        # invalid points read 0, valid ones lie in front of the sensor (positive range)
        assert (parts["profile"][~parts["valid"]] == 0).all()
        assert (parts["profile"][parts["valid"]][:, 1] > 0).all()
        torch = dict(zip(sgym.TORCH_STATE, parts["torch"].tolist(), strict=True))
        assert torch["t_s"] == 0.0 and torch["progress"] == pytest.approx(0.0, abs=0.01)
    finally:
        env.close()


def test_same_seed_gives_the_same_episode_bytes() -> None:
    env = make(max_time_s=1.0)
    try:
        runs = []
        for seed in (7, 7, 8):
            env.action_space.seed(seed)
            runs.append(episode(env, lambda obs: env.action_space.sample() * 0.05, seed))
    finally:
        env.close()
    a, b, c = runs
    assert a["obs"].tobytes() == b["obs"].tobytes()
    assert a["rewards"].tobytes() == b["rewards"].tobytes()
    # another seed starts elsewhere (the start jitter): the seed is used, not ignored
    assert a["obs"][0].tobytes() != c["obs"][0].tobytes()


def test_pd_policy_beats_zero_action_on_a_curving_seam() -> None:
    """Zero action follows the straight line between the seam's ends, so its error reaches the
    curve's largest distance from that chord (computed here from the paper's Eq. 15-17); the
    PD policy on the profile's root follows the curve."""
    x = np.linspace(0.0, 100.0, 20001)
    curve = paper_curve(x)
    chord = curve[-1] - curve[0]
    chord /= np.linalg.norm(chord)
    rel = curve - curve[0]
    bulge = float(np.max(np.linalg.norm(rel - np.outer(rel @ chord, chord), axis=1)))
    env = make()
    try:
        still = episode(env, zero, seed=1)
        pd = episode(env, sgym.ProfilePD(env), seed=1)
    finally:
        env.close()
    for run in (still, pd):
        assert run["terminated"] and not run["truncated"]
        assert run["infos"][-1]["status"] == "completed"
        length = env.unwrapped.truth.length_mm
        assert run["infos"][-1]["arc_length_mm"] >= length - env.unwrapped.end_tolerance_mm
    still_err = np.array([i["error_mm"] for i in still["infos"]])
    pd_err = np.array([i["error_mm"] for i in pd["infos"]])
    assert still_err.max() == pytest.approx(bulge, abs=0.3)
    assert pd_err.mean() < 0.25 * still_err.mean()
    # the reward is minus the error, frame by frame
    np.testing.assert_array_equal(pd["rewards"], -pd_err[1:])
    assert pd["rewards"].sum() > still["rewards"].sum()


def test_losing_the_seam_terminates_with_the_documented_penalty() -> None:
    env = make()
    try:
        run = episode(env, lambda obs: np.array([1.0, 0.0], dtype=np.float32), seed=0)
        base = env.unwrapped
        assert not running(env)  # ended with the episode, before close()
    finally:
        env.close()
    last = run["infos"][-1]
    assert run["terminated"] and not run["truncated"] and last["status"] == "lost_seam"
    assert last["error_mm"] > base.lost_mm
    frames_left = (base.truth.length_mm - last["arc_length_mm"]) / (
        base.speed_mm_s * base.frame_period_s
    )
    assert run["rewards"][-1] == pytest.approx(-last["error_mm"] - base.lost_mm * frames_left)


def test_time_limit_truncates() -> None:
    env = make(max_time_s=0.25)
    try:
        run = episode(env, zero, seed=0)
        assert not running(env)
        with pytest.raises(RuntimeError, match="reset"):
            env.step(np.zeros(2, dtype=np.float32))
    finally:
        env.close()
    last = run["infos"][-1]
    assert run["truncated"] and not run["terminated"] and last["status"] == "time_limit"
    period = env.unwrapped.frame_period_s
    assert 0.25 <= last["t_s"] < 0.25 + period + 1e-9
    assert len(run["rewards"]) == round(last["t_s"] / period)


def test_a_frame_is_observed_when_it_arrives() -> None:
    """With a sensor latency, each observation is the frame taken that long before the step."""
    latency = 0.03
    env = gymnasium.make(
        ID, scene="paper-v-groove", overrides={**SHORT, "sensor.latency_s": latency},
        max_time_s=0.2,
    )  # fmt: skip
    try:
        run = episode(env, zero, seed=0)
        period = env.unwrapped.frame_period_s
    finally:
        env.close()
    captured = np.array([i["t_capture_s"] for i in run["infos"]])
    arrived = np.array([i["t_s"] for i in run["infos"]])
    np.testing.assert_allclose(arrived - captured, latency, atol=1e-9)
    np.testing.assert_allclose(np.diff(captured), period, atol=1e-9)


def test_reset_and_close_mid_episode_end_the_run() -> None:
    env = make()
    env.reset(seed=0)
    for _ in range(3):
        env.step(np.zeros(2, dtype=np.float32))
    first = env.unwrapped._run
    assert first.alive
    env.reset(seed=1)  # ends the running episode first
    assert not first.alive and running(env)
    env.step(np.zeros(2, dtype=np.float32))
    second = env.unwrapped._run
    env.close()
    env.close()  # twice is fine
    assert not second.alive and not running(env)


def correction(obs: np.ndarray, rays: int) -> np.ndarray:
    """The correction held, (lateral, vertical) mm, as the observation reports it."""
    torch = sgym.split_observation(obs, rays)["torch"]
    return torch[..., 5:7].astype(np.float64)


BAD_ACTIONS = {
    "nan": np.array([np.nan, 0.0], dtype=np.float32),
    "inf": np.array([0.2, -np.inf], dtype=np.float32),
    "three numbers": np.zeros(3, dtype=np.float32),
    "a batch of one": np.zeros((1, 2), dtype=np.float32),
    "text": "left",
    "none": None,
}


@pytest.mark.parametrize("bad", BAD_ACTIONS, ids=list(BAD_ACTIONS))
def test_a_bad_action_is_refused_and_the_step_runs_as_with_zero_action(bad: str) -> None:
    """A bad action raises nothing (a raise ends an AsyncVectorEnv's worker): the step applies
    no new correction, so it gives the very observation and reward of a zero action, and says
    why in ``info``; the episode goes on."""
    steps = [np.array([0.3, -0.2], dtype=np.float32), np.array([-0.1, 0.1], dtype=np.float32)]
    runs = []
    env = make()
    try:
        for action in (np.zeros(2, dtype=np.float32), BAD_ACTIONS[bad]):
            env.reset(seed=5)
            first = env.step(steps[0])
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                middle = env.step(action)
            after = env.step(steps[1])
            runs.append((first, middle, after, [w.category for w in caught]))
    finally:
        env.close()
    (_, zero_mid, zero_after, zero_warned), (_, bad_mid, bad_after, bad_warned) = runs
    assert zero_warned == [] and bad_warned == [sgym.BadActionWarning]
    assert zero_mid[4]["action_refused"] == ""
    assert bad_mid[4]["action_refused"] and "\n" not in bad_mid[4]["action_refused"]
    assert not bad_mid[4]["action_clipped"]
    for zero_step, bad_step in ((zero_mid, bad_mid), (zero_after, bad_after)):
        assert zero_step[0].tobytes() == bad_step[0].tobytes()
        assert zero_step[1:4] == bad_step[1:4]  # reward, terminated, truncated
    # the correction held is the sum of the accepted actions only
    rays = env.unwrapped.rays
    np.testing.assert_array_equal(
        correction(bad_after[0], rays), np.float32(steps[0]) + np.float32(steps[1])
    )


def test_an_action_beyond_the_bound_moves_the_torch_by_the_bound_only() -> None:
    """``max_correction_mm`` bounds each axis of an action: 5 mm asked with a 0.5 mm bound moves
    the correction held by 0.5 mm (and says so), exactly as asking 0.5 mm does; an action
    within the bound is applied as it is."""
    env = make(max_correction_mm=0.5)
    try:
        rays = env.unwrapped.rays
        observed = []
        for action in ([5.0, -3.0], [0.5, -0.5]):
            env.reset(seed=2)
            obs, reward, *_, info = env.step(np.array(action, dtype=np.float32))
            observed.append((obs, reward, info))
        obs, _, _, _, inside = env.step(np.array([-0.25, 0.125], dtype=np.float32))
    finally:
        env.close()
    (beyond, beyond_reward, beyond_info), (at_bound, bound_reward, bound_info) = observed
    np.testing.assert_array_equal(correction(beyond, rays), [0.5, -0.5])
    assert beyond_info["action_clipped"] and not bound_info["action_clipped"]
    assert beyond.tobytes() == at_bound.tobytes() and beyond_reward == bound_reward
    np.testing.assert_array_equal(correction(obs, rays), [0.25, -0.375])
    assert not inside["action_clipped"] and inside["action_refused"] == ""


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_a_bad_action_leaves_a_vector_env_usable(mode: str) -> None:
    """One NaN, one inf and a batch of the wrong width in a vector env: no worker dies, the
    refused steps are those of a zero action (the other env untouched), and the vector env
    steps and resets on as before; its episodes are those of single envs."""
    seeds = [3, 4]
    zero2 = np.zeros((2, 2), dtype=np.float32)
    small = np.array([[0.05, -0.02], [-0.03, 0.04]], dtype=np.float32)
    nan_first = np.array([[np.nan, 0.0], [0.02, 0.01]], dtype=np.float32)
    inf_second = np.array([[0.01, 0.02], [0.0, np.inf]], dtype=np.float32)
    wide = np.zeros((2, 3), dtype=np.float32)  # each env gets three numbers
    actions = [small, nan_first, small, inf_second, wide, small]
    # what a single env is given instead: a refused action is a zero one
    as_applied = [small, np.array([[0.0, 0.0], [0.02, 0.01]], dtype=np.float32), small,
                  np.array([[0.01, 0.02], [0.0, 0.0]], dtype=np.float32), zero2, small]  # fmt: skip
    refused = [[False, False], [True, False], [False, False], [False, True], [True, True],
               [False, False]]  # fmt: skip
    kwargs = {"vector_kwargs": {"context": "spawn"}} if mode == "async" else {}
    vec = gymnasium.make_vec(
        ID, num_envs=2, vectorization_mode=mode, scene="paper-v-groove", overrides=SHORT,
        **kwargs,
    )  # fmt: skip
    try:
        obs, _ = vec.reset(seed=seeds)
        vec_obs, vec_rewards = [obs], []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sgym.BadActionWarning)  # a sync env's, in-process
            for a, flags in zip(actions, refused, strict=True):
                obs, reward, terminated, truncated, info = vec.step(a)
                assert not (terminated.any() or truncated.any())
                assert [bool(r) for r in info["action_refused"]] == flags
                vec_obs.append(obs)
                vec_rewards.append(reward)
        again, _ = vec.reset(seed=seeds)  # the workers are alive and reset as before
        vec.step(small)
    finally:
        vec.close()
    assert again.tobytes() == vec_obs[0].tobytes()
    env = make()
    try:
        for k, seed in enumerate(seeds):
            obs, _ = env.reset(seed=seed)
            assert obs.tobytes() == vec_obs[0][k].tobytes()
            for i, a in enumerate(as_applied):
                obs, reward, *_ = env.step(a[k])
                assert obs.tobytes() == vec_obs[i + 1][k].tobytes()
                assert reward == vec_rewards[i][k]
    finally:
        env.close()


def test_async_vector_env_gives_the_trajectories_of_single_envs() -> None:
    seeds = [3, 4]
    actions = np.random.default_rng(0).uniform(-0.05, 0.05, size=(40, 2, 2)).astype(np.float32)
    # spawned workers: a forked one inherits the locks of this process's threads (numba's,
    # zenoh's from other tests), which may be held at the fork: a hang
    vec = gymnasium.make_vec(
        ID,
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},
        scene="paper-v-groove",
        overrides=SHORT,
    )
    try:
        obs, _ = vec.reset(seed=seeds)
        vec_obs, vec_rewards = [obs], []
        for a in actions:
            obs, reward, terminated, truncated, _ = vec.step(a)
            assert not (terminated.any() or truncated.any())
            vec_obs.append(obs)
            vec_rewards.append(reward)
    finally:
        vec.close()
    env = make()
    try:
        for k, seed in enumerate(seeds):
            obs, _ = env.reset(seed=seed)
            assert obs.tobytes() == vec_obs[0][k].tobytes()
            for i, a in enumerate(actions):
                obs, reward, *_ = env.step(a[k])
                assert obs.tobytes() == vec_obs[i + 1][k].tobytes()
                assert reward == vec_rewards[i][k]
    finally:
        env.close()


def test_the_scene_may_be_a_name_a_path_or_a_scene(tmp_path) -> None:
    """The same scene three ways gives the same first observation."""
    from importlib.resources import files

    from seamtrack.simulation.scene import load_scene

    path = tmp_path / "groove.toml"
    path.write_text(files("seamtrack.scenes").joinpath("paper-v-groove.toml").read_text())
    first = []
    for scene, overrides in (
        ("paper-v-groove", SHORT),
        (path, SHORT),
        (load_scene("paper-v-groove", SHORT), None),
    ):
        env = gymnasium.make(ID, scene=scene, overrides=overrides)
        try:
            first.append(env.reset(seed=2)[0])
        finally:
            env.close()
    assert first[0].tobytes() == first[1].tobytes() == first[2].tobytes()
    with pytest.raises(SceneError, match="loaded scene") as info:
        gymnasium.make(ID, scene=load_scene("paper-v-groove"), overrides=SHORT)
    assert info.value.field == "overrides"


def test_a_seam_mode_scene_is_refused_in_one_line() -> None:
    with pytest.raises(SceneError) as info:
        gymnasium.make(ID, scene="paper-verification")
    assert info.value.field == "sensor.mode"
    assert "\n" not in str(info.value) and "mesh" in str(info.value)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"nominal": "spline"}, "nominal"),
        ({"max_correction_mm": 0.0}, "max_correction_mm"),
        ({"max_correction_mm": float("nan")}, "max_correction_mm"),
        ({"start_jitter_mm": -1.0}, "start_jitter_mm"),
        ({"lost_mm": "5"}, "lost_mm"),
        ({"max_time_s": -2.0}, "max_time_s"),
    ],
)
def test_bad_arguments_are_refused_in_one_line(kwargs: dict, field: str) -> None:
    with pytest.raises(SceneError) as info:
        make(**kwargs)
    assert info.value.field == field and "\n" not in str(info.value)


def blocking(module: str) -> str:
    """Python code that makes ``import module`` fail, as when it is not installed."""
    return f"import sys; sys.modules[{module!r}] = None; "


@pytest.mark.parametrize("module", ["gymnasium", "greenlet"])
def test_a_missing_extra_names_the_pip_install(module: str) -> None:
    done = subprocess.run(
        [sys.executable, "-c", blocking(module) + "import seamtrack.gym"],
        capture_output=True,
        text=True,
    )
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert last.endswith(
        f"GymnasiumMissing: seamtrack.gym: {module} is not installed; "
        "fix: pip install 'seamtrack[gym]'"
    )


def test_bench_gym_without_gymnasium_is_one_line_and_writes_nothing(tmp_path) -> None:
    out = tmp_path / "bench"
    code = (
        blocking("gymnasium")
        + "from seamtrack.cli import main; "
        + f"sys.exit(main(['bench', 'gym', '--quick', '--out', {str(out)!r}]))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "seamtrack: error: seamtrack.gym: gymnasium is not installed; "
        "fix: pip install 'seamtrack[gym]'"
    ]
    assert not out.exists()
