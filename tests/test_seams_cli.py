"""``seamtrack seams PART``: the table, ``--json`` and ``--view``, and bad parts refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.cad

cq = pytest.importorskip("cadquery")

from seamtrack.cli.main import main  # noqa: E402


@pytest.fixture(scope="module")
def bracket(tmp_path_factory) -> Path:
    import importlib

    path = tmp_path_factory.mktemp("seams") / "bracket.step"
    build = importlib.import_module("seamtrack.cad.weldment_bracket").build
    build(length_mm=60.0).export_step(str(path))
    return path


def test_the_table_lists_every_seam(bracket, capsys):
    assert main(["seams", str(bracket)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"{bracket}: 13 seams (2 lap, 9 fillet, 2 butt)"
    assert out[1].split()[:4] == ["id", "name", "joint", "length_mm"]
    assert [line.split()[0] for line in out[2:]] == [f"s{k}" for k in range(1, 14)]
    assert out[2].split()[1:3] == ["base/strap/0", "lap"]


def test_json_holds_the_seams_with_their_torch_frames(bracket, capsys):
    assert main(["seams", str(bracket), "--json"]) == 0
    seams = json.loads(capsys.readouterr().out)
    assert len(seams) == 13
    for s in seams:
        assert set(s) >= {"id", "joint", "bodies", "points_mm", "normals", "length_mm",
                          "opening_deg", "gap_mm", "reachable"}  # fmt: skip
        points, normals = np.array(s["points_mm"]), np.array(s["normals"])
        assert points.shape == normals.shape and points.shape[1] == 3
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
        arc = np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))
        assert arc == pytest.approx(s["length_mm"], rel=1e-9)
    butt = [s for s in seams if s["joint"] == "butt"]
    assert sorted(round(s["groove_deg"], 6) for s in butt) == [0.0, 60.0]


def test_view_draws_the_part_with_numbered_seams(bracket, tmp_path, capsys):
    out = tmp_path / "pictures" / "bracket.png"
    assert main(["seams", str(bracket), "--view", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {out}" in capsys.readouterr().out


def test_a_weldment_script_takes_parameters(capsys):
    assert main(["seams", "weldment_t", "--param", "web_angle_deg=60", "--json"]) == 0
    seams = json.loads(capsys.readouterr().out)
    assert [round(s["opening_deg"], 6) for s in seams] == [60.0, 120.0]


def _no_solid(tmp: Path) -> Path:
    path = tmp / "sheet.step"
    cq.exporters.export(cq.Workplane().rect(10, 10).extrude(1).faces(">Z").val(), str(path))
    return path


def _apart(tmp: Path) -> Path:
    import importlib

    w = importlib.import_module("seamtrack.cad.kit.cadweldment")
    path = tmp / "apart.step"
    w.Weldment(
        bodies={"a": w.box((0, 10), (0, 10), (0, 10)), "b": w.box((12, 20), (0, 10), (0, 10))}
    ).export_step(str(path))
    return path


@pytest.mark.parametrize(
    ("make", "says"),
    [
        (_no_solid, "holds no solid"),
        (_apart, "nearest: a and b, 2 mm"),
        (lambda tmp: tmp / "missing.step", "does not exist"),
    ],
)
def test_a_bad_part_is_one_line_exit_2_and_draws_nothing(make, says, tmp_path, capsys):
    part = make(tmp_path)
    view = tmp_path / "out" / "view.png"
    assert main(["seams", str(part), "--view", str(view)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("seamtrack: error: PART: ") and says in err[0]
    assert not view.parent.exists()
