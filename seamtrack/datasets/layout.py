"""The layout of a dataset folder (names only: reading it needs neither numba nor the
generator). :mod:`seamtrack.datasets.store` writes it, :mod:`seamtrack.datasets.reader` reads it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from seamtrack.errors import OutputError

MANIFEST = "dataset.json"
SPEC_FILE = "spec.toml"
FORMAT = "seamtrack-dataset"
FORMAT_VERSION = 1

#: The arrays of a chunk file, in the order they are written.
ARRAYS = (
    "points_laser", "valid", "reason", "seam_point_laser", "features_laser", "joint", "path",
    "material", "preset", "tack", "params", "T_seam_sensor", "T_world_seam", "index",
)  # fmt: skip
#: The arrays a chunk file adds with images (``images = true``, ``--images``).
IMAGE_ARRAYS = (
    "image", "image_truth_row", "image_truth_laser", "image_reflection", "image_reflection_row",
    "image_points_laser", "image_valid", "camera_params",
)  # fmt: skip
#: The array a chunk file adds when its spec's arc can be on (``[arc] probability`` above 0).
ARC_ARRAYS = ("arc_params",)
#: The arrays a chunk file adds with beads in the V-grooves (``[joint] passes``): the groove's
#: 7 points (issue 25) and the number of layers laid.
PASS_ARRAYS = ("groove_points_laser", "layers")
REASON_NAMES = ("valid", "miss", "occluded", "out_of_range", "incidence", "dropout")


def arrays(images: bool, passes: bool = False, arc: bool = False) -> tuple[str, ...]:
    """The arrays of a chunk file of a dataset with or without images, passes and the arc."""
    return (
        ARRAYS
        + (PASS_ARRAYS if passes else ())
        + (IMAGE_ARRAYS if images else ())
        + (ARC_ARRAYS if images and arc else ())
    )


def chunk_path(out: Path, k: int) -> Path:
    return out / f"chunk-{k:06d}.h5"


def read_manifest(out: Path) -> dict[str, Any] | None:
    path = out / MANIFEST
    if not path.exists():
        return None
    try:
        manifest = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise OutputError(
            f"{str(path)!r} cannot be read ({exc})", field="--out", fix="give a new folder"
        ) from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise OutputError(f"{str(path)!r} is no seamtrack dataset", field="--out",
                          fix="give a new folder")  # fmt: skip
    return manifest
