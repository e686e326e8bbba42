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


def _episodes(vec, actions: np.ndarray) -> list[tuple[np.ndarray, ...]]:
    out = [(vec.reset(seed=7)[0],)]
    for a in actions:
        obs, reward, terminated, truncated, info = vec.step(a)
        out.append((obs, reward, terminated, truncated, info["_status"]))
    return out


@pytest.fixture(scope="module")
def reference() -> tuple[np.ndarray, list[tuple[np.ndarray, ...]]]:
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, size=(260, 3, 2)).astype(np.float32)
    sync = gymnasium.make_vec("seamtrack/Scene-v0", num_envs=3, vectorization_mode="sync", **KW)
    try:
        return actions, _episodes(sync, actions)
    finally:
        sync.close()


@pytest.mark.parametrize("workers", [1, 2])
def test_the_same_bytes_as_sync_vector_env_on_any_number_of_workers(reference, workers) -> None:
    """Seeds s + i, the NEXT_STEP autoreset (the step after an end resets that environment and
    ignores its action) and the batched infos: SyncVectorEnv's, to the byte."""
    actions, expected = reference
    ends = sum(int(row[2].sum() + row[3].sum()) for row in expected[1:])
    assert ends >= 3  # the run crosses episode ends, so the autoreset is compared too
    vec = BatchedVectorEnv(3, workers=workers, **KW)
    try:
        assert vec.workers == workers
        assert vec.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.NEXT_STEP
        got = _episodes(vec, actions)
    finally:
        vec.close()
    for k, (row, want) in enumerate(zip(got, expected, strict=True)):
        for a, b in zip(row, want, strict=True):
            assert np.array_equal(a, b), k


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
