"""The two-plate kernels' small helpers agree with the numpy calls they stand in for."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.features.pkernels import _kept, _median
from seamtrack.features.psheets import _order


@pytest.mark.parametrize("n", [1, 2, 3, 8, 9, 101, 400])
def test_median_is_numpys_median(n: int) -> None:
    rng = np.random.default_rng(n)
    for v in (rng.normal(size=n), rng.integers(0, 4, size=n).astype(float)):
        assert _median(v) == np.median(v)
    v = rng.normal(size=n)
    v[n // 2] = np.nan
    assert np.isnan(_median(v))


def test_order_is_a_stable_argsort() -> None:
    rng = np.random.default_rng(1)
    for n in (0, 1, 5, 64):
        keys = rng.integers(-3, 3, size=n).astype(np.int64)
        assert np.array_equal(_order(keys), np.argsort(keys, kind="stable"))


def test_kept_is_flatnonzero() -> None:
    keep = np.random.default_rng(2).random(50) > 0.5
    assert np.array_equal(_kept(keep), np.flatnonzero(keep))
