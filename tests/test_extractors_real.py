"""``seamtrack extractors bench --real DIR``: the layout of real-data sets, its checks, and the
rows per set. Real scans may not be committed (no licence allows it): the sets here are drawn
from the real-sensor artefact model and written in the same layout."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from seamtrack.bench.extractors import bench_real, load_real_set, load_real_sets
from seamtrack.cli.main import main
from seamtrack.errors import SeamtrackError
from seamtrack.features.artefacts import real_sensor_profile
from seamtrack.features.classify import classify
from seamtrack.features.extractors import extractor

LDS_V = {"included_angle_deg": 63.0, "gap_mm": 0.0, "root_face_mm": 0.0, "thickness_mm": 7.0}


def _write_set(d, shape, n, seed, **params):
    rng = np.random.default_rng(seed)
    drawn = [
        real_sensor_profile(shape, rng, roll_deg=rng.uniform(-11, 11), **params) for _ in range(n)
    ]
    d.mkdir(parents=True)
    pts = np.stack([p.points_laser for p, _ in drawn])
    np.savez(d / "profiles.npz", y_mm=pts[:, :, 0], z_mm=pts[:, :, 1])
    joint = shape if shape != "block" else "none"
    (d / "set.json").write_text(json.dumps({"joint": joint, "range_unit_mm": 0.05}))
    if joint != "none":
        with open(d / "labels.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["index", "y_mm", "z_mm"])
            w.writerows([i, *t.seam_laser] for i, (_, t) in enumerate(drawn))
    return drawn


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    root = tmp_path_factory.mktemp("real")
    drawn = {
        "groove": _write_set(root / "groove", "v-groove", 12, 41, **LDS_V),
        "block": _write_set(root / "block", "block", 8, 42),
    }
    return root, drawn


def test_rows_per_set_match_the_extractors_run_directly(sets, tmp_path):
    root, drawn = sets
    rows = {r["set"]: r for r in bench_real(root, tmp_path, progress=False)}
    assert set(rows) == {"groove", "block"}
    g = rows["groove"]
    errors = []
    for profile, truth in drawn["groove"]:
        f = extractor("v-groove")(profile)
        errors.append(np.hypot(*(f.point_laser - truth.seam_laser)) if f else np.inf)
    assert g["detection_rate"] == pytest.approx(np.mean(np.array(errors) <= 0.5))
    assert g["detection_rate"] >= 0.9 and g["p95_error_mm"] <= 0.5
    assert g["classified_rate"] == pytest.approx(
        np.mean([classify(p)[0] == "v-groove" for p, _ in drawn["groove"]])
    )
    b = rows["block"]
    assert np.isnan(b["detection_rate"]) and b["false_joint_rate"] <= 0.1
    assert b["classified_rate"] >= 0.9
    for r in rows.values():  # timings are reported (the bench), never asserted
        assert {"us_per_profile", "classify_us"} <= set(r)
    text = (tmp_path / "extractors_real.md").read_text()
    assert "| groove | v-groove | 12 |" in text and "| block | none | 8 |" in text
    with open(tmp_path / "extractors_real.csv") as fh:
        assert len(list(csv.DictReader(fh))) == 2


def test_one_set_folder_is_a_set(sets):
    root, _ = sets
    (only,) = load_real_sets(root / "groove")
    assert only.name == "groove" and only.joint == "v-groove" and len(only.profiles) == 12
    assert only.labels is not None and only.labels.shape == (12, 2)


def _broken(tmp_path, what):
    d = tmp_path / "s"
    d.mkdir()
    y = np.linspace(-5, 5, 100)
    z = np.full((3, 100), 90.0)
    joint = {"joint": "v-groove"}
    if what == "joint":
        joint = {"joint": "butt"}
    if what != "no-json":
        (d / "set.json").write_text(json.dumps(joint))
    np.savez(d / "profiles.npz", y_mm=y[:50] if what == "shape" else y, z_mm=z)
    rows = 2 if what == "labels" else 3
    (d / "labels.csv").write_text("index,y_mm,z_mm\n" + "".join(f"{i},0,91\n" for i in range(rows)))
    return d


@pytest.mark.parametrize("what", ["no-json", "joint", "shape", "labels"])
def test_bad_sets_are_refused_naming_the_flag(tmp_path, what):
    with pytest.raises(SeamtrackError) as info:
        load_real_sets(_broken(tmp_path, what))
    assert info.value.field == "--real" and info.value.fix


def test_cli_bench_real_prints_the_table_and_refuses_a_bad_folder(sets, tmp_path, capsys):
    root, _ = sets
    assert (
        main(
            [
                "extractors",
                "bench",
                "--real",
                str(root / "block"),
                "--out",
                str(tmp_path / "o"),
                "-q",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "| block | none | 8 |" in out and "extractors_real.csv" in out
    assert (
        main(
            [
                "extractors",
                "bench",
                "--real",
                str(tmp_path / "nothing"),
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--real" in err[0]
    assert not (tmp_path / "p").exists()


def test_a_single_set_reads_like_the_loader_says(sets):
    root, drawn = sets
    rs = load_real_set(root / "groove")
    first = drawn["groove"][0][0]
    assert np.array_equal(rs.profiles[0].valid, first.valid)
    assert np.allclose(rs.profiles[0].valid_points, first.valid_points)
