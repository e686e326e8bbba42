"""Reading a dataset folder: ``seamtrack.datasets.open(DIR)``.

A :class:`Dataset` is a sequence of samples: ``len(data)``, ``data[i]`` (a dict of numpy
arrays), ``data[a:b]`` or ``data[[i, j]]`` (the same dict with a leading sample axis), and
``data.spec``. That is all a PyTorch ``DataLoader`` asks of a map-style dataset, so it can be
handed over as it is (no torch dependency here); file handles are opened per process, so
loader workers that fork or spawn each open their own.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from seamtrack.datasets.layout import MANIFEST, chunk_path, read_manifest
from seamtrack.datasets.layout import arrays as arrays_of
from seamtrack.datasets.spec import FAMILIES, DatasetSpec
from seamtrack.errors import OutputError


class Dataset:
    """The samples of a dataset folder written by ``seamtrack dataset``.

    Parameters
    ----------
    path : str or Path
        The folder (``--out`` of ``seamtrack dataset``).

    Attributes
    ----------
    spec : DatasetSpec
        The spec it was drawn from (every default filled in).
    names : dict
        What the integer codes and columns mean: ``joint_names``, ``feature_names`` (per
        family), ``param_names``, ``path_names``, ``material_names``, ``preset_names``,
        ``reason_names``.
    missing : list of int
        Chunks past the readable samples that are absent (a run that was stopped: rerun it).

    Each sample (``data[i]``) holds, with R rays and K = 6 feature slots:

    ``points_laser`` (R, 2) float (y_L, z_L) mm, the lit point where lost, NaN on a miss;
    ``valid`` (R,) bool; ``reason`` (R,) uint8 (``names["reason_names"]``);
    ``seam_point_laser`` (2,) mm (NaN for ``flat``); ``features_laser`` (K, 2) mm, NaN padded
    (``names["feature_names"][family]``); ``joint``, ``path``, ``material``, ``preset``
    uint8 codes; ``tack`` bool; ``params`` (P,) float (``names["param_names"]``; NaN where the
    family has no such parameter); ``T_seam_sensor`` and ``T_world_seam`` (4, 4); ``index``
    int64, the sample's number (its seed is ``SeedSequence(spec.seed).spawn(index + 1)[index]``).

    With beads (``[joint] passes`` above 0): ``groove_points_laser`` (7, 2) mm, a V-groove's
    7 points (left top corner, left bottom corner, three bottom points, right bottom corner,
    right top corner; :mod:`seamtrack.features.synthetic_groove`; NaN for other families) and
    ``layers`` uint8, the layers of beads laid in it.

    With images (``spec.images``), C camera columns and H rows: ``image`` (H, C) uint16 grey
    levels (full scale ``names["image_levels"]``); its truth ``image_truth_row`` (C,) float, the
    sub-pixel row of the ideal stripe per column (NaN where none) and ``image_truth_laser``
    (C, 2) the same as (y_L, z_L) mm, ``image_reflection`` (C,)
    bool and ``image_reflection_row`` (C,) float, a false stripe (the first specular bounce);
    the profile the spec's peak detector measures from the image, ``image_points_laser``
    (C, 2) mm and ``image_valid`` (C,); ``camera_params`` (``names["camera_param_names"]``).
    With the arc (``[arc] probability`` above 0): ``arc_params`` (``names["arc_param_names"]``:
    on or off, the process's index in ``names["arc_process_names"]``, the current, the
    look-ahead and the filter's width); the labels stay the arc-free truth.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not (self.path / MANIFEST).is_file():
            raise OutputError(
                f"{str(self.path)!r} holds no dataset ({MANIFEST} is missing)",
                field="DIR",
                fix="give a folder written by seamtrack dataset",
            )
        manifest = read_manifest(self.path)
        assert manifest is not None
        self.manifest = manifest
        try:
            self.spec = DatasetSpec.model_validate(manifest["spec"])
        except (ValidationError, KeyError, TypeError):
            raise OutputError(
                f"{str(self.path)!r} was written by seamtrack "
                f"{manifest.get('seamtrack_version', '?')}, whose spec this version cannot read",
                field="DIR",
                fix="read it with that version, or write it anew",
            ) from None
        self.arrays = arrays_of(self.spec.images, self.spec.joint.passes[1] > 0, self.spec.arc.on)
        self.version = str(manifest.get("seamtrack_version", "?"))
        self._handles: dict[int, Any] = {}
        self._pid = os.getpid()
        self._counts = self._scan()
        self._starts = np.concatenate([[0], np.cumsum(self._counts)]).astype(np.int64)
        expected = -(-int(manifest["n"]) // self.spec.chunk_size)
        self.missing = [
            k for k in range(len(self._counts), expected) if not chunk_path(self.path, k).exists()
        ]
        self.names: dict[str, Any] = self._names()

    # ------------------------------------------------------------------ files
    def _scan(self) -> list[int]:
        """Sample counts of the chunks that can be read in order: all full but the last."""
        counts: list[int] = []
        k = 0
        while chunk_path(self.path, k).exists():
            count = int(self._file(k).attrs["count"])
            counts.append(count)
            if count < self.spec.chunk_size:
                break
            k += 1
        return counts

    def _file(self, k: int) -> Any:
        import h5py

        if os.getpid() != self._pid:  # a forked DataLoader worker: its own handles
            self._handles, self._pid = {}, os.getpid()
        handle = self._handles.get(k)
        if handle is None:
            handle = h5py.File(chunk_path(self.path, k), "r")
            self._handles[k] = handle
        return handle

    def _names(self) -> dict[str, Any]:
        if not self._counts:
            from seamtrack.datasets.store import names

            return names(self.spec)
        return dict(json.loads(self._file(0).attrs["names"]))

    def close(self) -> None:
        for handle in self._handles.values():
            handle.close()
        self._handles = {}

    def __enter__(self) -> Dataset:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __getstate__(self) -> dict[str, Any]:  # picklable (spawned DataLoader workers)
        state = self.__dict__.copy()
        state["_handles"] = {}
        return state

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return int(self._starts[-1])

    def __getitem__(self, key: int | slice | Sequence[int] | np.ndarray) -> dict[str, np.ndarray]:
        n = len(self)
        if isinstance(key, (int, np.integer)):
            i = int(key) + n if key < 0 else int(key)
            if not 0 <= i < n:
                raise IndexError(f"sample {key} of a dataset of {n}")
            k = int(np.searchsorted(self._starts, i, side="right")) - 1
            f, row = self._file(k), i - int(self._starts[k])
            return {name: np.asarray(f[name][row]) for name in self.arrays}
        if isinstance(key, slice):
            return self._rows(np.arange(n)[key])
        rows = np.asarray(key)
        if rows.dtype == bool or not np.issubdtype(rows.dtype, np.integer) or rows.ndim != 1:
            raise TypeError("index a dataset with an int, a slice or a 1-D list of ints")
        if rows.size and (rows.min() < -n or rows.max() >= n):
            raise IndexError(f"sample index out of range for a dataset of {n}")
        return self._rows(np.where(rows < 0, rows + n, rows))

    def _rows(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The samples ``rows`` (any order), stacked; contiguous runs read as one slice."""
        parts: dict[str, list[np.ndarray]] = {name: [] for name in self.arrays}
        chunk = np.searchsorted(self._starts, rows, side="right") - 1
        i = 0
        while i < len(rows):
            j = i + 1
            while j < len(rows) and chunk[j] == chunk[i] and rows[j] == rows[j - 1] + 1:
                j += 1
            f, base = self._file(int(chunk[i])), int(self._starts[chunk[i]])
            lo, hi = int(rows[i]) - base, int(rows[j - 1]) - base + 1
            for name in self.arrays:
                parts[name].append(f[name][lo:hi])
            i = j
        if not len(rows):
            empty = self[0] if len(self) else {}
            return {k: np.empty((0, *v.shape), v.dtype) for k, v in empty.items()}
        return {name: np.concatenate(p) for name, p in parts.items()}

    def column(self, name: str, stop: int | None = None) -> np.ndarray:
        """One array of every sample (``data.column("seam_point_laser")``: (n, 2)), or of the
        first ``stop`` samples."""
        if name not in self.arrays:
            raise KeyError(f"no array {name!r}; arrays: {', '.join(self.arrays)}")
        if not self._counts:
            return self[0:0][name]
        end = len(self) if stop is None else max(0, min(stop, len(self)))
        parts = []
        for k in range(len(self._counts)):
            lo = int(self._starts[k])
            if lo >= end:
                break
            parts.append(self._file(k)[name][: end - lo])
        return np.concatenate(parts) if parts else self[0:0][name]

    def joint_name(self, code: int) -> str:
        return FAMILIES[int(code)]

    def __repr__(self) -> str:
        return f"<seamtrack dataset {str(self.path)!r}: {len(self)} samples, {self.spec.rays} rays>"


def info(path: str | Path, sample_limit: int = 10_000) -> str:
    """A summary of a dataset folder (what ``seamtrack dataset --info DIR`` prints)."""
    with Dataset(path) as data:
        n = len(data)
        spec = data.spec
        size = sum(p.stat().st_size for p in data.path.glob("chunk-*.h5"))
        lines = [
            f"dataset {str(data.path)!r}: {n} samples of {spec.rays} rays "
            f"({len(data._counts)} chunk files of up to {spec.chunk_size}, {size / 1e6:.1f} MB), "
            f"seamtrack {data.version}, seed {spec.seed}",
        ]
        if data.missing:
            lines.append(
                f"incomplete: chunks {data.missing[:5]}{' ...' if len(data.missing) > 5 else ''}"
                f" of the {data.manifest['n']} samples asked for are missing; rerun the same "
                "command to finish"
            )
        if n:
            joint = data.column("joint")
            counts = np.bincount(joint, minlength=len(FAMILIES))
            lines.append(
                "joints: " + ", ".join(f"{FAMILIES[j]} {c}" for j, c in enumerate(counts) if c)
            )
            seam = data.column("seam_point_laser", sample_limit)
            valid = data.column("valid", sample_limit)
            tack = data.column("tack", sample_limit)
            has_seam = np.isfinite(seam[:, 0])
            lines.append(
                f"over the first {len(seam)} samples: {valid.mean():.1%} of the points "
                f"valid; seam point range z_L {np.nanmin(seam[:, 1]) if has_seam.any() else 0:.2f}"
                f"..{np.nanmax(seam[:, 1]) if has_seam.any() else 0:.2f} mm, lateral y_L "
                f"{np.nanmin(seam[:, 0]) if has_seam.any() else 0:.2f}.."
                f"{np.nanmax(seam[:, 0]) if has_seam.any() else 0:.2f} mm; "
                f"{tack.mean():.1%} cross a tack"
            )
            if spec.images:
                c = spec.camera
                truth = np.isfinite(data.column("image_truth_row", sample_limit))
                measured = data.column("image_valid", sample_limit)
                reflection = data.column("image_reflection", sample_limit)
                lines.append(
                    f"images {c.columns} x {c.rows} (uint16, {c.bit_depth} bits): "
                    f"{truth.mean():.1%} of the columns see the stripe, the {c.method} detector "
                    f"measures {measured[truth].mean() if truth.any() else 0:.1%} of those; "
                    f"{reflection.any(axis=1).mean():.1%} of the images show a false stripe"
                )
        lines.append(
            f"families {', '.join(spec.joint.families)}; presets {', '.join(spec.sensor.presets)}"
            f"; spec: {data.path / 'spec.toml'}"
        )
    return "\n".join(lines)
