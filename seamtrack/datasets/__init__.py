"""Labelled datasets of stripe profiles: ``seamtrack dataset SPEC.toml --n N --out DIR`` writes
them, :func:`open` reads them.

>>> import seamtrack as st
>>> data = st.datasets.open("DIR")          # doctest: +SKIP
>>> len(data), data[0]["seam_point_laser"]  # doctest: +SKIP

Modules load on first use: ``import seamtrack.datasets`` imports neither h5py nor numba.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from seamtrack.datasets.reader import Dataset


def open(path: str | Path) -> Dataset:  # the public name DESIGN.md gives
    """Open a dataset folder written by ``seamtrack dataset`` (see :class:`Dataset`)."""
    from seamtrack.datasets.reader import Dataset

    return Dataset(path)


__all__ = ["open"]
