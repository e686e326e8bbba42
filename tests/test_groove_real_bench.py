"""The groove rows of `extractors bench --real`: on a V-groove set with a bead in its bottom
(a synthetic stand-in for the Keyence root-pass scans, which may not be committed; exact
profiles pixel-quantized by the wide preset, as clean as the LJ-V7200 scans), the
reference top edges are the true ones and the checks pass; the CLI writes the groove table."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from seamtrack.bench.extractors import bench_real
from seamtrack.bench.extractors_groove import reference_top_edges
from seamtrack.features.synthetic_groove import fill, groove, groove_profile, to_joint


def _set(d, n=6):
    g = groove("v", angle_deg=90.0, gap_mm=0.0, thickness_mm=10.0)
    apex = np.array([[0.0, -10.0]])  # the bevels' intersection (station frame)
    ys, zs, labels, truths = [], [], [], []
    from seamtrack.features.synthetic import line_in_laser_plane

    for i in range(n):
        rng = np.random.default_rng([i, 5])
        s = fill(g, 1, bead_area_mm2=18.0, rng=rng, jitter_mm=0.3)[0]
        p, t = groove_profile(g, s, rng=rng, roll_deg=rng.uniform(-4, 4), rays=1400, artefacts=None)
        ys.append(p.points_laser[:, 0])
        zs.append(p.points_laser[:, 1])
        labels.append(line_in_laser_plane(t.T_world_sensor, to_joint(apex))[0])
        truths.append(t)
    d.mkdir(parents=True)
    np.savez_compressed(d / "profiles.npz", y_mm=np.array(ys), z_mm=np.array(zs))
    (d / "set.json").write_text(json.dumps({"joint": "v-groove"}))
    with open(d / "labels.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "y_mm", "z_mm"])
        w.writerows([i, y, z] for i, (y, z) in enumerate(labels))
    return labels, truths, ys, zs


def test_reference_top_edges_are_the_true_corners(tmp_path):
    labels, truths, ys, zs = _set(tmp_path / "rootpass", 3)
    for lab, t, y, z in zip(labels, truths, ys, zs, strict=True):
        ref = reference_top_edges(np.column_stack([y, z]), lab)
        assert np.hypot(*(ref - t.points_laser[[0, 6]]).T).max() <= 0.2  # the check: 0.5


def test_bench_scores_the_groove_extractor_on_v_groove_sets(tmp_path):
    _set(tmp_path / "sets" / "rootpass")
    bench_real(tmp_path / "sets", tmp_path / "out", progress=False)
    with open(tmp_path / "out" / "extractors_real_groove.csv") as fh:
        rows = list(csv.DictReader(fh))

    assert len(rows) == 1 and rows[0]["set"] == "rootpass"
    assert float(rows[0]["groove_found"]) == pytest.approx(1.0)
    assert float(rows[0]["top_ok"]) == pytest.approx(1.0)
    assert float(rows[0]["bottom_ok"]) == pytest.approx(1.0)
    assert (
        "bottom points on the bead" in (tmp_path / "out" / "extractors_real_groove.md").read_text()
    )
