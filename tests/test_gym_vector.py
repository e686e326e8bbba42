"""The batched vector env: Gymnasium's VectorEnv API over batches of environments, one batch per
worker process; the oracle is Gymnasium's own SyncVectorEnv over the same environments."""

from __future__ import annotations

from multiprocessing.shared_memory import SharedMemory

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import seamtrack.gym  # noqa: E402,F401  (registers seamtrack/Scene-v0)
from seamtrack.gym import BatchedVectorEnv  # noqa: E402

pytestmark = [pytest.mark.cad, pytest.mark.embree]

#: A 6 mm seam: episodes of about a hundred steps, so that a run crosses several autoresets.
KW = {"scene": "paper-v-groove", "overrides": {"workpiece.params.seam_length_mm": 6.0}}


MODES = gymnasium.vector.AutoresetMode


def _episodes(vec, actions: np.ndarray, mode=MODES.NEXT_STEP) -> list[tuple]:
    """A run from seed 7: each step's outputs (and, with SAME_STEP, the final observations and
    statuses; with DISABLED, the resets of the environments that ended)."""
    out: list[tuple] = [(vec.reset(seed=7)[0],)]
    for a in actions:
        obs, reward, terminated, truncated, info = vec.step(a)
        row = [obs, reward, terminated, truncated, info["_status"]]
        if "final_obs" in info:
            row += [info["_final_obs"], info["final_info"]["status"],
                    [b"" if x is None else x.tobytes() for x in info["final_obs"]]]  # fmt: skip
        out.append(tuple(row))
        ended = terminated | truncated
        if mode == MODES.DISABLED and ended.any():
            obs, info = vec.reset(options={"reset_mask": ended})
            out.append((obs, info["_t_s"]))
    return out


@pytest.fixture(scope="module")
def reference() -> dict:
    """SyncVectorEnv's runs in each autoreset mode (the oracle), and their actions."""
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, size=(260, 3, 2)).astype(np.float32)
    runs = {}
    for mode in MODES:
        sync = gymnasium.make_vec("seamtrack/Scene-v0", num_envs=3, vectorization_mode="sync",
                                  vector_kwargs={"autoreset_mode": mode}, **KW)  # fmt: skip
        try:
            runs[mode] = _episodes(sync, actions, mode)
        finally:
            sync.close()
    return {"actions": actions, "runs": runs}


@pytest.mark.parametrize(
    ("mode", "workers"),
    [
        (MODES.NEXT_STEP, 1),
        (MODES.NEXT_STEP, 2),
        (MODES.SAME_STEP, 1),
        (MODES.SAME_STEP, 2),
        (MODES.DISABLED, 1),
    ],
)
def test_the_same_bytes_as_sync_vector_env_in_each_autoreset_mode(reference, mode, workers) -> None:
    """Seeds s + i, Gymnasium's autoreset modes (NEXT_STEP: the step after an end resets that
    environment and ignores its action; SAME_STEP: the ending step resets it, the last
    observation in final_obs; DISABLED: a reset_mask resets it) and the batched infos:
    SyncVectorEnv's over the same single environments, to the byte, with every environment's
    ticks run in one compiled call (workers=1) or two (workers=2)."""
    actions, expected = reference["actions"], reference["runs"][mode]
    ends = sum(int(row[2].sum() + row[3].sum()) for row in expected[1:] if len(row) > 2)
    assert ends >= 3  # the run crosses episode ends, so the autoreset is compared too
    vec = BatchedVectorEnv(3, workers=workers, autoreset_mode=mode, **KW)
    try:
        assert vec.workers == workers
        assert vec.metadata["autoreset_mode"] == mode
        got = _episodes(vec, actions, mode)
    finally:
        vec.close()
    assert len(got) == len(expected)
    for k, (row, want) in enumerate(zip(got, expected, strict=True)):
        assert len(row) == len(want), k
        for a, b in zip(row, want, strict=True):
            assert np.array_equal(a, b), k


def test_lockstep_and_compiled_batches_agree(reference) -> None:
    """The batch whose ticks run compiled and one whose environments run the loop itself
    (engine="lockstep") step the same episodes."""
    actions = reference["actions"][:120]
    runs = []
    for engine in ("compiled", "lockstep"):
        vec = BatchedVectorEnv(3, workers=1, engine=engine, **KW)
        try:
            assert (vec._batch.ticks is not None) == (engine == "compiled")
            runs.append(_episodes(vec, actions))
        finally:
            vec.close()
    for row, want in zip(*runs, strict=True):
        for a, b in zip(row, want, strict=True):
            assert np.array_equal(a, b)


def test_record_episode_statistics_counts_the_episodes_of_single_envs(reference) -> None:
    """Gymnasium's RecordEpisodeStatistics reads the autoreset mode from the metadata (a
    missing or wrong tag warns or raises: warnings are errors here) and sums each episode's
    rewards: the sums of the single environments' episodes."""
    from gymnasium.wrappers.vector import RecordEpisodeStatistics

    actions = reference["actions"]
    expected = reference["runs"][MODES.NEXT_STEP]
    returns = np.zeros(3)
    want = []
    for row in expected[1:]:
        reward, ended = row[1], row[2] | row[3]
        returns += reward
        want += [returns[i] for i in np.flatnonzero(ended)]
        returns[ended] = 0.0
    vec = RecordEpisodeStatistics(BatchedVectorEnv(3, workers=1, **KW))
    got = []
    try:
        vec.reset(seed=7)
        for a in actions:
            *_, info = vec.step(a)
            if "episode" in info:
                got += [float(r) for r in info["episode"]["r"][info["_episode"]]]
    finally:
        vec.close()
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_bad_autoreset_calls_are_named() -> None:
    with pytest.raises(ValueError, match="autoreset_mode"):
        BatchedVectorEnv(2, workers=1, autoreset_mode="sometimes", **KW)
    vec = BatchedVectorEnv(2, workers=1, autoreset_mode=MODES.DISABLED, **KW)
    try:
        vec.reset(seed=0)
        with pytest.raises(TypeError, match="reset_mask"):
            vec.reset(options={"reset_mask": [True, False]})
        with pytest.raises(ValueError, match="at least one True"):
            vec.reset(options={"reset_mask": np.zeros(2, dtype=bool)})
        far = np.full((2, 2), -1.0, dtype=np.float32)  # steers off the seam: lost in frames
        for _ in range(400):
            _, _, terminated, truncated, _ = vec.step(far)
            if (terminated | truncated).any():
                break
        assert (terminated | truncated).any()
        with pytest.raises(ValueError, match="reset_mask"):
            vec.step(far)
        options = {"reset_mask": terminated | truncated}
        vec.reset(options=options)
        assert "reset_mask" in options  # the caller's dict is left as it was
        vec.step(np.zeros((2, 2), dtype=np.float32))
    finally:
        vec.close()


def test_make_vec_builds_it_and_bad_calls_are_named() -> None:
    vec = gymnasium.make_vec("seamtrack/Scene-v0", num_envs=2,
                             vectorization_mode="vector_entry_point", workers=2, **KW)  # fmt: skip
    names = [m.name for m in vec.unwrapped._memories]
    try:
        assert isinstance(vec.unwrapped, BatchedVectorEnv)
        assert vec.observation_space.shape[0] == 2
        vec.reset(seed=0)
        with pytest.raises(ValueError, match="actions"):
            vec.step(np.zeros((3, 2), dtype=np.float32))
        obs, *_ = vec.step(np.zeros((2, 2), dtype=np.float32))  # still usable
        assert vec.observation_space.contains(obs)
    finally:
        vec.close()
    for name in names:  # the shared memory is gone with the env
        with pytest.raises(FileNotFoundError):
            SharedMemory(name=name)
    with pytest.raises(ValueError, match="num_envs"):
        BatchedVectorEnv(0, **KW)


def test_image_mode_batches_give_sync_vector_envs_bytes() -> None:
    """A scene whose stripe comes from the camera's image (``sensor.source = "image"``: each
    environment's renderer and auto-exposure state its own) steps the same episodes batched as
    in SyncVectorEnv, across episode ends."""
    kw = {"scene": "v-groove-camera", "overrides": {"workpiece.params.seam_length_mm": 4.0}}
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, size=(60, 2, 2)).astype(np.float32)
    sync = gymnasium.make_vec("seamtrack/Scene-v0", num_envs=2, vectorization_mode="sync", **kw)
    try:
        assert sync.envs[0].unwrapped.scene.config.sensor.source == "image"
        expected = _episodes(sync, actions)
    finally:
        sync.close()
    assert sum(int(row[2].sum() + row[3].sum()) for row in expected[1:]) >= 2
    vec = BatchedVectorEnv(2, workers=1, **kw)
    try:
        got = _episodes(vec, actions)
    finally:
        vec.close()
    assert len(got) == len(expected)
    for k, (row, want) in enumerate(zip(got, expected, strict=True)):
        for a, b in zip(row, want, strict=True):
            assert np.array_equal(a, b), k
