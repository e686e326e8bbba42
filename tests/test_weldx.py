"""weldx in and out: ISO 9692-1 grooves built along our paths, runs written as weldx files."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = [pytest.mark.cad]

pytest.importorskip("cadquery")
weldx = pytest.importorskip("weldx")

from seamtrack.cli.main import main  # noqa: E402
from seamtrack.errors import SeamtrackError, WorkpieceError  # noqa: E402
from seamtrack.geometry.seam import paper_curve  # noqa: E402
from seamtrack.io.weldx_file import read_weldx  # noqa: E402
from seamtrack.simulation.scene import load_scene  # noqa: E402
from seamtrack.workpiece.grooves import groove_spec, plate_profiles  # noqa: E402
from seamtrack.workpiece.loader import load_workpiece  # noqa: E402

V = {"type": "VGroove", "t_mm": 10, "alpha_deg": 60, "b_mm": 1, "c_mm": 1}


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("cache")


def test_the_v_groove_profile_is_weldx_s_with_its_root_at_the_origin():
    plates, walls, normals = plate_profiles(groove_spec(V), 40.0, 0.01)
    left, right = sorted(plates, key=lambda p: p[:, 0].mean())
    # Root faces 1 mm tall at u = -+0.5 (the gap), bevels up to the top 9 mm above the root.
    assert [-0.5, 0.0] in left.tolist() and [-0.5, -1.0] in left.tolist()
    assert [0.5, 0.0] in right.tolist() and [0.5, -1.0] in right.tolist()
    bevel = 0.5 + 9.0 * math.tan(math.radians(30.0))
    assert np.abs(left - [-bevel, 9.0]).sum(axis=1).min() < 1e-9
    assert math.degrees(math.acos(walls[0] @ walls[1])) == pytest.approx(60.0)
    assert (normals[0] + normals[1]) / np.linalg.norm(normals[0] + normals[1]) == pytest.approx(
        [0.0, 1.0]
    )


@pytest.mark.parametrize("path", ["straight", "arc", "paper"])
def test_a_groove_builds_its_plates_along_our_paths(path, cache):
    length = 60.0
    part = load_workpiece(
        groove=V, cache_dir=cache, tolerance_mm=0.01, path=path, seam_length_mm=length
    )
    assert part.joint == "butt" and part.opening_rad == pytest.approx(math.radians(60.0))
    assert part.mesh.is_watertight and part.mesh.body_count == 2
    pts = part.seam.points
    if path == "straight":
        assert np.abs(pts[:, 1:]).max() < 1e-12 and pts[-1, 0] == pytest.approx(length)
    elif path == "arc":  # circular, radius 100, turning left from the origin
        assert np.abs(np.linalg.norm(pts - [0.0, 100.0, 0.0], axis=1) - 100.0).max() < 1e-6
    else:
        assert np.abs(pts - paper_curve(pts[:, 0])).max() < 1e-4
    # The torch points up out of the groove, square to the path.
    tangents = np.gradient(pts, axis=0)
    assert np.abs(np.sum(part.seam.normals * tangents, axis=1)).max() < 1e-3
    # Each plate's root face lies b/2 = 0.5 mm from the seam, across it.
    for solid in part.shape.Solids():
        gap = solid.distance(__import__("cadquery").Vertex.makeVertex(*pts[len(pts) // 2]))
        assert gap == pytest.approx(0.5, abs=1e-6)


@pytest.mark.parametrize(
    "groove",
    [
        {"type": "IGroove", "t_mm": 6, "b_mm": 1},
        {"type": "UGroove", "t_mm": 12, "beta_deg": 8, "R_mm": 3, "c_mm": 1.5, "b_mm": 1},
        {"type": "HVGroove", "t_mm": 10, "beta_deg": 45, "c_mm": 1, "b_mm": 2},
        {"type": "DVGroove", "t_mm": 20, "alpha_1_deg": 60, "alpha_2_deg": 60, "c_mm": 2},
        {"type": "VVGroove", "t_mm": 20, "alpha_deg": 70, "beta_deg": 10, "h_mm": 5},
        {"type": "UVGroove", "t_mm": 12, "alpha_deg": 60, "beta_deg": 8, "R_mm": 3, "h_mm": 4},
        {"type": "HUGroove", "t_mm": 12, "beta_deg": 8, "R_mm": 3, "c_mm": 1.5, "b_mm": 1},
        {"type": "DHVGroove", "t_mm": 20, "beta_1_deg": 45, "beta_2_deg": 45, "c_mm": 2},
    ],
    ids=lambda g: g["type"],
)
def test_every_groove_weldx_defines_makes_a_part(groove, cache):
    part = load_workpiece(groove=groove, cache_dir=cache, tolerance_mm=0.05, seam_length_mm=30.0)
    assert part.mesh.is_watertight and part.mesh.body_count == 2
    assert np.allclose(np.linalg.norm(part.seam.normals, axis=1), 1.0)
    assert part.seam.normals[0][2] > 0.3  # out of the groove, upwards
    opening = math.degrees(part.opening_rad)
    assert (opening == pytest.approx(180.0)) if groove["type"] == "IGroove" else opening < 90


@pytest.mark.parametrize(
    ("groove", "field", "says"),
    [
        ({"type": "ZGroove", "t_mm": 10}, "workpiece.groove.type", "VGroove"),
        ({"type": "VGroove", "t_mm": 10}, "workpiece.groove.alpha_deg", "needs alpha_deg"),
        ({**V, "alpha_mm": 3}, "workpiece.groove.alpha_mm", "takes no 'alpha_mm'"),
        ({**V, "t_mm": "ten"}, "workpiece.groove.t_mm", "finite number"),
        ({"t_mm": 10}, "workpiece.groove.type", "needs a type"),
    ],
)
def test_a_groove_weldx_does_not_define_is_refused_with_its_field(groove, field, says):
    with pytest.raises(WorkpieceError) as info:
        load_scene("weldx-v-groove", {"workpiece.groove": groove})
    assert info.value.field == field and says in str(info.value)


def test_without_weldx_asking_for_it_says_which_pip_install(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "weldx", None)  # import weldx raises ImportError
    with pytest.raises(WorkpieceError, match=r"pip install 'seamtrack\[weldx\]'"):
        groove_spec(V)
    from seamtrack.io.weldx_file import check_weldx_target

    with pytest.raises(SeamtrackError, match=r"pip install 'seamtrack\[weldx\]'") as info:
        check_weldx_target(tmp_path / "run.wx")
    assert info.value.field == "--weldx"


def test_a_run_written_as_weldx_holds_the_numbers_of_summary_and_trace(tmp_path, capsys):
    out, wx = tmp_path / "run", tmp_path / "run.wx"
    args = ["run", "weldx-v-groove", "--set", "workpiece.params.seam_length_mm=25",
            "--out", str(out), "--weldx", str(wx), "--no-plot", "-q"]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    trace = np.genfromtxt(out / "trace.csv", delimiter=",", names=True)
    with read_weldx(wx) as f:
        assert dict(f["summary"]) == summary
        t = f["tcp"].time.as_quantity().to("s").m
        assert np.abs(t - trace["t_s"]).max() <= 5e-7  # the CSV prints 6 decimals
        tcp = f["tcp"].coordinates.data.to("mm").m
        csv_tcp = np.column_stack([trace["tcp_x_mm"], trace["tcp_y_mm"], trace["tcp_z_mm"]])
        assert np.abs(tcp - csv_tcp).max() <= 5e-7
        for name, column in (("error", "error_mm"), ("error_lateral", "error_lateral_mm")):
            data = f["trace"][name].data.to("mm").m
            assert np.abs(data - trace[column]).max() <= 5e-7
        assert np.array_equal(f["trace"]["welding"], trace["welding"].astype(bool))
        groove = f["groove"]
        assert type(groove).__name__ == "VGroove"
        assert groove.alpha.to("deg").m == pytest.approx(60.0)
        assert groove.b.to("mm").m == pytest.approx(1.0)
        assert f["sensor"]["frame_rate"].to("Hz").m == pytest.approx(100.0)
        assert f["sensor"]["baseline"].to("mm").m == pytest.approx(26.41, abs=0.01)
        points = f["seam"]["points"].to("mm").m
        assert points[-1] == pytest.approx([25.0, 0.0, 0.0])


def test_a_bad_weldx_target_writes_nothing(tmp_path, capsys):
    (tmp_path / "a_file").write_text("x")
    args = ["run", "weldx-v-groove", "--out", str(tmp_path / "run"),
            "--weldx", str(tmp_path / "a_file" / "run.wx")]  # fmt: skip
    assert main(args) == 2
    assert "--weldx" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
