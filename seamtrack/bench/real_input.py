"""The checks a real-profile set passes before the bench measures anything on it
(:func:`seamtrack.bench.extractors.load_real_set`): the npz's array sizes read from their
headers before a byte is decompressed, the profiles' scale against what a laser profiler
measures, and every label a finite number in mm.

Where the memory of a set goes: ``profiles.npz`` is a zip of ``.npy`` arrays, and NaN (what a
profile holds where the sensor saw nothing) compresses about 600:1, so a 0.5 MB file can hold a
(20000, 2048) array. Loading it decompresses 8 bytes a point, the profiles made from it take 16
more (a (m, 2) copy each) and their masks a few more: some 30 bytes a point, 1.2 GB for that
file and 5 GB for a 2 MB one. :data:`MAX_REAL_POINTS` bounds the points a set may hold, read
from the arrays' headers, so nothing is allocated for a set that is refused.
"""

from __future__ import annotations

import csv
import math
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.errors import SeamtrackError
from seamtrack.sensing.sensor import PRESET_SPECS

#: Most points (profiles x points a profile) one set may hold: about 30 bytes each once loaded
#: (see the module's docstring), so 2e7 keep a set under 1 GB: 10,000 profiles of 2048 points.
MAX_REAL_POINTS = 20_000_000

#: The smallest lateral field of view of the sensors seamtrack knows (mm): a set whose points
#: all lie within a tenth of it is not in millimetres.
SMALLEST_FIELD_MM = min(spec["fov_near_mm"] for spec in PRESET_SPECS.values())

LAYOUT = "see docs/extractors.md, 'Real data' (set.json, profiles.npz, labels.csv)"


def _error(message: str, path: Path, fix: str) -> SeamtrackError:
    return SeamtrackError(f"{path}: {message}", field="--real", fix=fix)


def check_npz_sizes(path: Path, names: tuple[str, ...] = ("y_mm", "z_mm")) -> None:
    """Refuse arrays of ``path`` (an npz) that would hold more than :data:`MAX_REAL_POINTS`
    values, from their ``.npy`` headers (nothing is decompressed beyond them). A file that is
    not a zip, or lacks an array, is left to ``numpy.load`` to report."""
    try:
        archive = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile):
        return
    with archive:
        for name in names:
            try:
                member = archive.open(f"{name}.npy")
            except KeyError:
                continue
            with member:
                try:
                    version = np.lib.format.read_magic(member)
                    read = {
                        (1, 0): np.lib.format.read_array_header_1_0,
                        (2, 0): np.lib.format.read_array_header_2_0,
                    }.get(version)
                    if read is None:
                        continue
                    shape, _, _ = read(member)
                except ValueError:
                    continue  # numpy.load names what is wrong
            count = math.prod(shape)
            if count > MAX_REAL_POINTS:
                raise _error(
                    f"profiles.npz's {name} holds {count:.3g} values {tuple(shape)}, more than "
                    f"the {MAX_REAL_POINTS:.0e} a set may (about 30 bytes each once loaded)",
                    path.parent,
                    "split the set into folders of at most "
                    f"{MAX_REAL_POINTS // max(1, shape[-1] if shape else 1):,} profiles",
                )


def check_profiles(y: np.ndarray, z: np.ndarray, path: Path) -> None:
    """Refuse a set of no profiles, of no measured point, or whose points are not in mm (they
    all lie within a tenth of the smallest field of view of any known sensor: metres)."""
    if z.shape[0] == 0 or z.shape[1] == 0:
        raise _error(
            f"profiles.npz holds {z.shape[0]} profiles of {z.shape[1]} points",
            path,
            "give at least one profile with measured points",
        )
    valid = np.isfinite(y) & np.isfinite(z)
    if not valid.any():
        raise _error(
            f"all {z.size:,} points of its {z.shape[0]} profiles are NaN or inf: the sensor saw "
            "nothing",
            path,
            "give profiles with measured points (NaN only where the sensor saw nothing)",
        )
    ys, zs = y[valid], z[valid]
    extent = float(max(np.ptp(ys), np.ptp(zs), np.abs(zs).max()))
    if extent < 0.1 * SMALLEST_FIELD_MM:
        metres = 1000.0 * extent >= 0.1 * SMALLEST_FIELD_MM
        raise _error(
            f"the profiles' points span {np.ptp(ys):.3g} mm across and reach {np.abs(zs).max():.3g}"
            f" mm in range, where the smallest field of view of a known sensor is "
            f"{SMALLEST_FIELD_MM:g} mm" + ("; looks like metres" if metres else ""),
            path,
            "give y_mm and z_mm in millimetres (multiply metres by 1000)"
            if metres
            else "give y_mm and z_mm in millimetres, the emitter at the origin",
        )


def read_labels(path: Path, n: int) -> np.ndarray:
    """``labels.csv`` (``index,y_mm,z_mm``, one row per profile, in order) as an (n, 2) array;
    text, NaN or inf in a cell is refused with its line (a label that is no number would count
    as a miss and lower the detection rate without a word)."""
    file = path / "labels.csv"
    try:
        with file.open(newline="", encoding="utf-8-sig") as handle:
            rows = [(i, row) for i, row in enumerate(csv.reader(handle), 1) if row]
    except (OSError, UnicodeDecodeError) as exc:
        raise _error(f"no usable labels.csv ({exc})", path, LAYOUT) from None
    if not rows or [c.strip() for c in rows[0][1]] != ["index", "y_mm", "z_mm"]:
        raise _error("labels.csv does not start with the header index,y_mm,z_mm", path, LAYOUT)
    labels = np.empty((len(rows) - 1, 2))
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != 3:
            raise _error(f"labels.csv line {line}: {len(row)} cells, not 3", path, LAYOUT)
        try:
            index, y, z = int(row[0]), float(row[1]), float(row[2])
        except ValueError:
            raise _error(
                f"labels.csv line {line}: {','.join(row)!r} is not an index and two numbers",
                path,
                "give every profile's seam point as numbers in mm (drop a profile without one)",
            ) from None
        if not (math.isfinite(y) and math.isfinite(z)):
            raise _error(
                f"labels.csv line {line}: the seam point ({y}, {z}) is not finite",
                path,
                "give every profile's seam point as numbers in mm (drop a profile without one)",
            )
        if index != k:
            raise _error(
                f"labels.csv line {line}: index {index} where {k} is due",
                path,
                "give one label per profile, in order",
            )
        labels[k] = y, z
    if len(labels) != n:
        raise _error(
            f"labels.csv has {len(labels)} rows for {n} profiles",
            path,
            "give one label per profile, in order",
        )
    return labels


def check_label_scale(labels: np.ndarray, y: np.ndarray, z: np.ndarray, path: Path) -> None:
    """Refuse labels in metres beside profiles in mm: labels that all lie within a tenth of the
    smallest field of view while the profiles' ranges reach beyond it."""
    reach = float(np.nanmax(np.abs(z)))
    label_reach = float(np.abs(labels).max()) if labels.size else 0.0
    if labels.size and label_reach < 0.1 * SMALLEST_FIELD_MM <= reach:
        raise _error(
            f"labels.csv's seam points reach {label_reach:.3g} mm, the profiles {reach:.4g} mm: "
            "the labels look like metres",
            path,
            "give y_mm and z_mm of labels.csv in millimetres (multiply metres by 1000)",
        )


def check_recorded(profiles: list[Any], labels: np.ndarray | None, path: Path) -> None:
    """A recording's profiles (and labels) held to a set's checks: some profile, some measured
    point, millimetres, finite labels."""
    width = max((len(p) for p in profiles), default=0)
    y = np.full((len(profiles), width), np.nan)
    z = np.full_like(y, np.nan)
    for i, p in enumerate(profiles):
        pts = (
            p.points_laser
            if p.valid is None
            else np.where(p.valid[:, None], p.points_laser, np.nan)
        )
        y[i, : len(pts)], z[i, : len(pts)] = pts[:, 0], pts[:, 1]
    check_profiles(y, z, path)
    if labels is None:
        return
    bad = np.flatnonzero(~np.isfinite(labels).all(axis=1))
    if bad.size:
        raise _error(
            f"the label of profile {int(bad[0])} is {labels[bad[0]].tolist()}, not a finite point",
            path,
            "record finite seam points, or give --labels a topic that has them",
        )
    check_label_scale(labels, y, z, path)
