"""The "wrote" lines of ``extractors bench --real`` and ``extractors import`` name every file
the command wrote, and no other."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from seamtrack.cli.main import main
from seamtrack.features.artefacts import real_sensor_profile

LDS_V = {"included_angle_deg": 63.0, "gap_mm": 0.0, "root_face_mm": 0.0, "thickness_mm": 7.0}


def named_files(stdout: str, folder: Path) -> set[str]:
    """The file names of the "wrote <folder>/a, b, c[: ...]" line."""
    (line,) = [ln for ln in stdout.splitlines() if ln.startswith("wrote ")]
    listed = line.removeprefix(f"wrote {folder}/").split(":")[0]
    return {name.strip() for name in listed.split(",")}


def files_in(folder: Path) -> set[str]:
    return {f.name for f in folder.iterdir() if f.is_file()}


def test_bench_real_names_every_file_it_wrote(tmp_path: Path, capsys) -> None:
    rng = np.random.default_rng(7)
    root = tmp_path / "sets"
    folder = root / "groove"  # a v-groove set: the groove table is written too
    folder.mkdir(parents=True)
    drawn = [real_sensor_profile("v-groove", rng, **LDS_V) for _ in range(6)]
    pts = np.stack([p.points_laser for p, _ in drawn])
    np.savez(folder / "profiles.npz", y_mm=pts[:, :, 0], z_mm=pts[:, :, 1])
    (folder / "set.json").write_text(json.dumps({"joint": "v-groove", "range_unit_mm": 0.05}))
    with open(folder / "labels.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "y_mm", "z_mm"])
        w.writerows([i, *t.seam_laser] for i, (_, t) in enumerate(drawn))
    out = tmp_path / "o"
    assert main(["extractors", "bench", "--real", str(root), "--out", str(out), "-q"]) == 0
    written = files_in(out)
    assert "extractors_real_groove.csv" in written  # the file the old line left out
    assert named_files(capsys.readouterr().out, out) == written


@pytest.mark.embree
def test_import_names_every_file_it_wrote(tmp_path: Path, capsys) -> None:
    """(A folder holding the user's own files is refused whole: tests/test_outputs_fresh.py.)"""
    pytest.importorskip("mcap_ros2")
    short = ["--set", "workpiece.params.seam_length_mm=20", "--set", "sensor.rays=256"]
    mcap = tmp_path / "run.mcap"
    args = ["run", "paper-v-groove", *short, "--out", str(tmp_path / "run"), "--no-plot", "-q"]
    assert main([*args, "--record", str(mcap)]) == 0
    out = tmp_path / "set"
    capsys.readouterr()
    assert main(["extractors", "import", "--real", str(mcap), "--out", str(out)]) == 0
    written = files_in(out)
    assert {"set.json", "profiles.npz", "labels.csv"} <= written  # labels: the old line's miss
    assert named_files(capsys.readouterr().out, out) == written
