"""Labelled datasets of stripe profiles: ``seamtrack dataset SPEC.toml --n N --out DIR`` writes
them, :func:`open` reads them.

>>> import seamtrack as st
>>> st.datasets.write({"joint": {"families": ["v-groove"]}}, 100, "DIR")  # doctest: +SKIP
>>> data = st.datasets.open("DIR")          # doctest: +SKIP
>>> len(data), data[0]["seam_point_laser"]  # doctest: +SKIP

Modules load on first use: ``import seamtrack.datasets`` imports neither h5py nor numba.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from seamtrack.datasets.reader import Dataset
    from seamtrack.datasets.spec import DatasetSpec


def open(path: str | Path) -> Dataset:  # the public name DESIGN.md gives
    """Open a dataset folder written by ``seamtrack dataset`` (see :class:`Dataset`)."""
    from seamtrack.datasets.reader import Dataset

    return Dataset(path)


def write(
    spec: str | Path | dict[str, Any] | DatasetSpec,
    n: int,
    out: str | Path,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    images: bool = False,
) -> dict[str, Any]:
    """Samples 0..n-1 of ``spec`` (a spec file, a dict as in the TOML, or a
    :class:`~seamtrack.datasets.spec.DatasetSpec`) into the folder ``out``: what
    ``seamtrack dataset SPEC --n N --out DIR [--images]`` does (resuming or appending there, if
    the folder holds this spec's dataset). Returns the counts and times of
    :func:`seamtrack.datasets.store.write_dataset`."""
    from seamtrack.datasets.spec import DatasetSpec, load_spec, parse_spec, with_images
    from seamtrack.datasets.store import write_dataset

    if isinstance(spec, dict):
        spec = parse_spec(spec)
    elif not isinstance(spec, DatasetSpec):
        spec = load_spec(spec)
    if images:
        spec = with_images(spec)
    return write_dataset(spec, n, out, workers=workers, scheduler=scheduler)


__all__ = ["open", "write"]
