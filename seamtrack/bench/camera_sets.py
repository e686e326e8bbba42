"""Image-mode profiles as labelled sets in the real-data bench's layout, and their rows.

``seamtrack bench camera`` renders every joint family's scene at 20 poses on two materials and
measures a profile from each image (section 4). This module keeps those profiles with their true
seam points and writes them as sets the real-data extractor bench reads
(:func:`seamtrack.bench.extractors.load_real_set`: ``set.json``, ``profiles.npz``,
``labels.csv``), then runs that bench on them (section 6): each set's own family extractor
against the label, the other families' false joints, and the classifier. A real-like set whose
errors are born in the image (speckle, a bright groove's false stripe, saturation), with an exact
label, which no recorded scan can give.

The label is where the CAD seam crosses the laser plane (``x_L = 0``), found on the seam
polyline in the laser frame (:func:`seam_in_laser_plane`): analytic geometry, independent of
any extractor.
"""

from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.geometry import frames

FloatArray = NDArray[np.float64]


def seam_in_laser_plane(seam_points_world: ArrayLike, T_world_sensor: ArrayLike) -> FloatArray:
    """Where a seam polyline crosses the laser plane, as ``(y_L, z_L)`` in mm.

    Parameters
    ----------
    seam_points_world : (n, 3) float
        The seam's vertices in the world frame, in order.
    T_world_sensor : (4, 4) float
        Pose of the laser frame {L} in the world.

    Returns
    -------
    (2,) float
        The crossing nearest the emitter (linear between the two vertices whose ``x_L``
        changes sign); NaN when the seam does not cross the plane.
    """
    p = frames.apply(frames.invert(np.asarray(T_world_sensor, dtype=np.float64)),
                     np.asarray(seam_points_world, dtype=np.float64))  # fmt: skip
    x = p[:, 0]
    cross = np.flatnonzero(np.signbit(x[:-1]) != np.signbit(x[1:]))
    if cross.size == 0:
        return np.full(2, np.nan)
    hits = []
    for i in cross:
        f = x[i] / (x[i] - x[i + 1]) if x[i] != x[i + 1] else 0.0
        hits.append(p[i] + f * (p[i + 1] - p[i]))
    best = min(hits, key=lambda q: float(np.hypot(q[1], q[2])))
    return np.array([best[1], best[2]])


@dataclass
class ImageSet:
    """Profiles measured from camera images of one scene's joint on one material.

    ``family`` names the scene's joint; ``joint`` the extractor family whose seam point the
    labels follow (the scene's extractor: the outside corner's stripe shows the V groove its
    end faces leave, which the v-groove extractor finds). ``offset_mm``: the scene's torch
    target relative to the feature (laser frame); the label is the CAD seam's crossing minus
    it (the square butt's extractor finds the gap at the plate surface, a plate thickness
    above the root where the CAD seam runs).
    """

    family: str
    joint: str
    material: str
    scene: str
    offset_mm: tuple[float, float] = (0.0, 0.0)
    points_laser: list[FloatArray] = field(default_factory=list)  # (m, 2) each, NaN: none
    labels: list[FloatArray] = field(default_factory=list)  # (2,) each

    @property
    def name(self) -> str:
        return f"{self.family}-{self.material.replace(' ', '-')}"

    def add(self, profile: Any, seam_points_world: ArrayLike, T_world_sensor: ArrayLike) -> None:
        """Keep one frame's profile (invalid columns as NaN) and its true seam point."""
        p = np.array(profile.points_laser, dtype=np.float64)
        p[~np.asarray(profile.valid, dtype=bool)] = np.nan
        self.points_laser.append(p)
        crossing = seam_in_laser_plane(seam_points_world, T_world_sensor)
        self.labels.append(crossing - np.asarray(self.offset_mm, dtype=np.float64))

    def write(self, out_dir: str | Path, meta: dict[str, Any]) -> Path:
        """Write the set as ``out_dir/<name>/`` in the real-data layout; return its folder."""
        d = Path(out_dir) / self.name
        d.mkdir(parents=True, exist_ok=True)
        width = max(len(p) for p in self.points_laser)
        y = np.full((len(self.points_laser), width), np.nan)
        z = np.full_like(y, np.nan)
        for k, p in enumerate(self.points_laser):
            y[k, : len(p)], z[k, : len(p)] = p[:, 0], p[:, 1]
        np.savez_compressed(d / "profiles.npz", y_mm=y, z_mm=z)
        rows = ["index,y_mm,z_mm"] + [
            f"{k},{lab[0]:.9g},{lab[1]:.9g}" for k, lab in enumerate(self.labels)
        ]
        (d / "labels.csv").write_text("\n".join(rows) + "\n")
        info = {
            "joint": self.joint,
            "family": self.family,
            "material": self.material,
            "scene": self.scene,
            "offset_mm": list(self.offset_mm),
            "source": "seamtrack image mode (seamtrack bench camera, section 6)",
            **meta,
        }
        (d / "set.json").write_text(json.dumps(info, indent=2) + "\n")
        return d


def bench_image_sets(sets: list[ImageSet], meta: dict[str, Any],
                     out_dir: str | Path | None = None) -> list[dict[str, Any]]:  # fmt: skip
    """Write the sets (into ``out_dir``, else a temporary folder) and run the real-data
    extractor bench on them: one row per set (:func:`seamtrack.bench.extractors.bench_real`)."""
    from seamtrack.bench.extractors import bench_real

    with tempfile.TemporaryDirectory(prefix="seamtrack-image-sets-") as tmp:
        root = Path(out_dir) if out_dir is not None else Path(tmp) / "sets"
        for s in sets:
            s.write(root, meta)
        rows = bench_real(root, Path(tmp) / "bench", progress=False)
    by_name = {s.name: s for s in sets}
    for row in rows:
        row["family"] = by_name[row["set"]].family
        row["material"] = by_name[row["set"]].material
    return rows


def markdown_rows(rows: list[dict[str, Any]], table: Any) -> list[str]:
    """Section 6 of ``camera.md`` (``table``: the bench's table formatter)."""
    lines = [
        "",
        "**6. Image-mode profiles as labelled sets through the real-data bench** "
        "(`seamtrack extractors bench --real`): label = the CAD seam where it crosses the laser "
        "plane; detect within 0.5 mm; false joints: share of (profile, other family's extractor) "
        "answers that found a seam; classified: share the classifier names the set's family.",
        "",
    ]
    lines += table(
        ["scene joint", "extractor", "material", "n", "detect", "wrong", "median mm", "p95 mm",
         "false joints", "worst false", "classified"],
        [[r["family"], r["joint"], r["material"], r["n"], r["detection_rate"], r["wrong_rate"],
          r["median_error_mm"], r["p95_error_mm"], r["false_joint_rate"], r["worst_false"],
          r["classified_rate"]] for r in rows],
    )  # fmt: skip
    return lines
