"""load_workpiece: CAD seams on their faces, measured mesh deviation, STEP, cache, bad input."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.cad

cq = pytest.importorskip("cadquery")

from seamtrack.errors import WorkpieceError  # noqa: E402
from seamtrack.geometry.seam import paper_curve  # noqa: E402
from seamtrack.workpiece.loader import (  # noqa: E402
    cache_dir,
    clear_cache,
    load_workpiece,
    mesh_tradeoff,
)

CAD_DIR = Path(__file__).resolve().parents[1] / "cad"
SMALL = {"seam_length_mm": 20.0, "plate_width_mm": 15.0, "plate_thickness_mm": 6.0}


@pytest.fixture(scope="module")
def module_cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("cache")


def _vertex(point) -> object:
    return cq.Vertex.makeVertex(*map(float, point))


def _seam_faces(shape, edges):
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    faces = []
    for edge in edges:
        for f in ancestors.FindFromKey(edge.wrapped):
            if not any(f.IsSame(g.wrapped) for g in faces):
                faces.append(cq.Face(f))
    return faces


# ----------------------------------------------------------------------------- seam geometry
@pytest.mark.parametrize("path", ["arc", "paper", "corner"])
@pytest.mark.parametrize("family", ["v_groove", "fillet_t", "lap", "outside_corner", "square_butt"])
def test_seam_points_lie_on_the_cad_edge_and_both_faces(module_cache, family, path):
    import importlib

    joint = importlib.import_module(f"seamtrack.cad.{family}").build(path=path)
    part = load_workpiece(family, tolerance_mm=0.1, cache_dir=module_cache, path=path)
    edges = joint.seams["root"]
    faces = _seam_faces(joint.seam_solid, edges)
    assert len(faces) == 2 * len(edges) or (path == "corner" and len(faces) >= 2)
    rng = np.random.default_rng(3)
    picks = rng.choice(len(part.seam.points), size=6, replace=False)
    wire = cq.Compound.makeCompound(edges)
    for i in picks:
        v = _vertex(part.seam.points[i])
        assert wire.distance(v) < 1e-6
        near_faces = sorted(f.distance(v) for f in faces)
        assert near_faces[1] < 1e-6  # on two faces at once
    # torch direction: unit, bisector of the two outward face normals, away from the material
    n = part.seam.normals
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    bis = part.seam_face_normals.sum(axis=1)
    bis /= np.linalg.norm(bis, axis=1, keepdims=True)
    tangents = part.seam.tangents
    bis -= np.sum(bis * tangents, axis=1, keepdims=True) * tangents
    bis /= np.linalg.norm(bis, axis=1, keepdims=True)
    assert np.abs(n - bis).max() < 1e-6
    probe = part.seam.points[picks] + 1.0 * n[picks]  # well beyond the 0.1 mm chords
    assert not part.mesh.contains(probe).any()


@pytest.mark.parametrize(
    ("family", "expected"),
    [
        ("v_groove", (0.0, 0.0, 1.0)),  # up out of the V
        ("outside_corner", (0.0, 0.0, 1.0)),
        ("fillet_t", (0.0, -math.sqrt(0.5), math.sqrt(0.5))),  # out of the corner, web at +y
        ("lap", (0.0, -math.sqrt(0.5), math.sqrt(0.5))),
        ("square_butt", (0.0, 0.0, 1.0)),  # the backing under the root gap
    ],
)
def test_torch_points_away_from_the_material(module_cache, family, expected):
    part = load_workpiece(family, tolerance_mm=0.01, cache_dir=module_cache)
    assert np.allclose(part.seam.normals, expected, atol=1e-9)
    assert np.allclose(part.seam.points[[0, -1]], [[0, 0, 0], [200, 0, 0]], atol=1e-9)


@pytest.mark.parametrize(
    ("tolerance_mm", "length_mm"), [(0.1, 400.0), (0.01, 400.0), (0.001, 40.0)]
)
def test_paper_seam_matches_eq_15_17_within_the_chord_tolerance(
    module_cache, tolerance_mm, length_mm
):
    part = load_workpiece(
        "v_groove",
        tolerance_mm=tolerance_mm,
        seam_spacing_mm=50.0,  # the chord tolerance must set the spacing
        cache_dir=module_cache,
        path="paper",
        plate_width_mm=15.0,
        seam_length_mm=length_mm,
    )
    seam = part.seam
    # points on the curve (Eq. 16-17 at their own X) ...
    assert np.abs(seam.points - paper_curve(seam.points[:, 0])).max() < 1e-5
    # ... and the exact curve within the tolerance of the polyline between them
    exact = paper_curve(np.linspace(0.0, length_mm, 40001))
    assert seam.distance(exact).max() <= tolerance_mm
    assert seam.points[0] == pytest.approx([0.0, 10.0, 0.0], abs=1e-9)


# ----------------------------------------------------------------------------- mesh deviation
@pytest.mark.parametrize("tolerance_mm", [1.0, 0.1, 0.01, 0.001])
@pytest.mark.parametrize("path", ["arc", "paper"])
def test_measured_deviation_is_within_the_requested_tolerance(path, tolerance_mm):
    part = load_workpiece("v_groove", tolerance_mm=tolerance_mm, cache=False, path=path, **SMALL)
    assert 0 <= part.deviation_mm <= tolerance_mm
    assert part.mesh.is_watertight and part.mesh.is_winding_consistent
    # independent check: random points on the mesh are no further from the BRep than reported
    points = part.mesh.sample(60, seed=7)
    shape = part.shape
    dist = [shape.distance(_vertex(p)) for p in points]
    assert max(dist) <= part.deviation_mm + 1e-9


def test_deviation_shrinks_with_tolerance():
    rows = mesh_tradeoff(tolerances=(1.0, 0.01), paths=("arc",), **SMALL)
    coarse, fine = rows
    assert fine["triangles"] > coarse["triangles"]
    assert fine["deviation_mm"] < coarse["deviation_mm"]
    assert set(coarse) == {
        "joint",
        "path",
        "tolerance_mm",
        "triangles",
        "meshing_time_s",
        "deviation_mm",
    }


# ----------------------------------------------------------------------------- STEP
@pytest.mark.parametrize(("family", "path"), [("v_groove", "paper"), ("fillet_t", "corner")])
def test_step_round_trip_gives_the_same_seam(tmp_path, module_cache, family, path):
    import importlib

    joint = importlib.import_module(f"seamtrack.cad.{family}").build(path=path)
    step = tmp_path / "part.step"
    cq.exporters.export(joint.solid, str(step))
    scripted = load_workpiece(family, tolerance_mm=0.1, cache_dir=module_cache, path=path)
    n = len(scripted.seam.points)
    near = scripted.seam.points[[1, n // 3, 2 * n // 3, n - 2]]
    loaded = load_workpiece(step, tolerance_mm=0.1, seam_near_mm=near, cache_dir=tmp_path)
    assert loaded.seam.points.shape == scripted.seam.points.shape
    assert np.abs(loaded.seam.points - scripted.seam.points).max() < 1e-6
    assert np.abs(loaded.seam.normals - scripted.seam.normals).max() < 1e-6
    assert loaded.mesh.is_watertight


def test_step_seam_by_selector(tmp_path, module_cache):
    import importlib

    joint = importlib.import_module("seamtrack.cad.v_groove").build()
    step = tmp_path / "part.stp"
    cq.exporters.export(joint.solid, str(step), exportType="STEP")
    loaded = load_workpiece(step, seam="|X and not(<Z or >Z)", cache_dir=tmp_path)
    scripted = load_workpiece("v_groove", cache_dir=module_cache)
    assert np.abs(loaded.seam.points - scripted.seam.points).max() < 1e-6


def test_a_step_seam_runs_from_its_smallest_end_whatever_the_float_noise(tmp_path):
    """A seam along Y whose ends' x differ by 4e-5 mm (what a writer's rounding leaves) runs
    from its smaller y: the x difference is noise, not the lexicographic order (it used to
    decide, and the seam ran from its largest end)."""
    import importlib

    joint = importlib.import_module("seamtrack.cad.fillet_t").build(seam_length_mm=200.0)
    turn = 90.0 + math.degrees(2e-7)
    step = tmp_path / "turned.step"
    cq.exporters.export(joint.solid.rotate((0, 0, 0), (0, 0, 1), turn), str(step))
    c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
    near = [[c * x, s * x, 0.0] for x in (30.0, 90.0, 170.0)]
    loaded = load_workpiece(step, tolerance_mm=0.1, seam_near_mm=near, cache_dir=tmp_path)
    start, end = loaded.seam.points[0], loaded.seam.points[-1]
    assert abs(end[0] - start[0]) > 1e-5  # the noise is there
    assert start[1] == pytest.approx(0.0, abs=1e-9) and end[1] > 199.0


# ----------------------------------------------------------------------------- cache
def _load_in_subprocess(script: Path, cache: Path, **params) -> dict:
    code = textwrap.dedent(
        f"""
        import hashlib, json, sys
        from seamtrack.workpiece.loader import load_workpiece
        part = load_workpiece({str(script)!r}, tolerance_mm=0.01, cache_dir={str(cache)!r},
                              **{params!r})
        arrays = (part.mesh.vertices, part.mesh.faces, part.seam.points, part.seam.normals)
        digest = hashlib.sha256(b"".join(a.tobytes() for a in arrays)).hexdigest()
        print(json.dumps({{"digest": digest, "from_cache": part.from_cache,
                          "cadquery": "cadquery" in sys.modules, "OCP": "OCP" in sys.modules,
                          "triangles": part.triangle_count}}))
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_cache_hit_imports_no_cadquery_and_returns_the_same_arrays(tmp_path):
    """A cache hit skips the CAD work (no CadQuery, no OCP import) and gives back the very
    mesh and seam the miss built (how much faster it is: ``seamtrack bench cache``)."""
    script = CAD_DIR / "v_groove.py"
    first = _load_in_subprocess(script, tmp_path, path="arc")
    second = _load_in_subprocess(script, tmp_path, path="arc")
    assert not first["from_cache"] and second["from_cache"]
    assert first["cadquery"] and not second["cadquery"] and not second["OCP"]
    assert second["triangles"] == first["triangles"]
    assert second["digest"] == first["digest"]


def test_cache_misses_on_changed_parameter_or_script(tmp_path):
    script = tmp_path / "my_groove.py"
    script.write_text((CAD_DIR / "v_groove.py").read_text())
    cache = tmp_path / "cache"
    first = load_workpiece(script, cache_dir=cache, groove_angle_deg=60.0)
    again = load_workpiece(script, cache_dir=cache, groove_angle_deg=60.0)
    assert not first.from_cache and again.from_cache
    assert np.array_equal(again.mesh.faces, first.mesh.faces)
    assert np.array_equal(again.seam.points, first.seam.points)
    assert again.shape.isValid()  # rebuilt lazily from the script
    assert not load_workpiece(script, cache_dir=cache, groove_angle_deg=70.0).from_cache
    assert not load_workpiece(
        script, cache_dir=cache, tolerance_mm=0.02, groove_angle_deg=60.0
    ).from_cache
    script.write_text(script.read_text() + "\n# edited\n")
    assert not load_workpiece(script, cache_dir=cache, groove_angle_deg=60.0).from_cache
    assert clear_cache(cache) == 4
    assert clear_cache(cache) == 0


@pytest.mark.parametrize("damage", ["truncate_mesh", "garbage_meta", "swap_arrays", "delete_seam"])
def test_corrupt_cache_entry_is_rebuilt(tmp_path, damage):
    first = load_workpiece("lap", cache_dir=tmp_path)
    (entry,) = (tmp_path / "workpieces").iterdir()
    if damage == "truncate_mesh":
        blob = (entry / "mesh.npz").read_bytes()
        (entry / "mesh.npz").write_bytes(blob[: len(blob) // 2])
    elif damage == "garbage_meta":
        (entry / "meta.json").write_text("{not json")
    elif damage == "swap_arrays":
        np.savez(entry / "mesh.npz", vertices=np.zeros((3, 3)), faces=np.zeros((1, 3), int))
    else:
        (entry / "seam.npz").unlink()
    rebuilt = load_workpiece("lap", cache_dir=tmp_path)
    assert not rebuilt.from_cache
    assert np.array_equal(rebuilt.mesh.faces, first.mesh.faces)
    assert load_workpiece("lap", cache_dir=tmp_path).from_cache


def test_cache_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("SEAMTRACK_CACHE_DIR", str(tmp_path / "c"))
    assert cache_dir() == tmp_path / "c"
    monkeypatch.delenv("SEAMTRACK_CACHE_DIR")
    assert cache_dir() == Path.home() / ".cache" / "seamtrack"


# ----------------------------------------------------------------------------- bad input
def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


@pytest.mark.parametrize(
    ("make_source", "params", "field", "says"),
    [
        (lambda d: "cad/nope.py", {}, "workpiece.script", "does not exist"),
        (lambda d: "no_such_joint", {}, "workpiece.script", "does not exist"),
        (lambda d: _write(d, "part.txt", "hello"), {}, "workpiece.script", "not a Python"),
        (lambda d: _write(d, "nobuild.py", "x = 1\n"), {}, "workpiece.script", "no build"),
        (
            lambda d: _write(
                d, "boom.py", "def build():\n    raise RuntimeError('plate cracked')\n"
            ),
            {},
            "workpiece.script",
            "plate cracked",
        ),
        (
            lambda d: _write(d, "bad.py", "def build(:\n"),
            {},
            "workpiece.script",
            "failed to import",
        ),
        (
            lambda d: _write(
                d,
                "empty.py",
                "import cadquery as cq\ndef build():\n    return cq.Compound.makeCompound([])\n",
            ),
            {},
            "workpiece.params",
            "no valid solid",
        ),
        (lambda d: "v_groove", {"bogus_mm": 1.0}, "workpiece.params.bogus_mm", "no parameter"),
        (lambda d: "square_butt", {"root_gap_mm": 60.0}, "workpiece.params.root_gap_mm", "larger"),
        (lambda d: "v_groove", {"groove_angle_deg": 0.0}, "workpiece.params.groove_angle_deg", ""),
        (
            lambda d: "v_groove",
            {"groove_angle_deg": 180.0},
            "workpiece.params.groove_angle_deg",
            "",
        ),
        (lambda d: "v_groove", {"path": "zigzag"}, "workpiece.params.path", "unknown path"),
        (
            lambda d: "fillet_t",
            {"path": "arc", "arc_radius_mm": 20.0, "seam_length_mm": 60.0},
            "workpiece.params.arc_radius_mm",
            "radius",
        ),
        (lambda d: d / "missing.step", {}, "workpiece.step", "does not exist"),
        (lambda d: _write(d, "empty.step", ""), {}, "workpiece.step", "empty"),
        (
            lambda d: _write(d, "fake.stp", "solid cube\nendsolid\n"),
            {},
            "workpiece.step",
            "not a STEP",
        ),
    ],
)
def test_bad_input_names_the_field_and_a_fix(tmp_path, make_source, params, field, says):
    with pytest.raises(WorkpieceError) as info:
        load_workpiece(make_source(tmp_path), cache_dir=tmp_path / "cache", **params)
    assert info.value.field == field
    assert says in info.value.message
    assert info.value.fix


@pytest.fixture(scope="module")
def straight_step(tmp_path_factory) -> Path:
    import importlib

    step = tmp_path_factory.mktemp("step") / "v.step"
    cq.exporters.export(importlib.import_module("seamtrack.cad.v_groove").build().solid, str(step))
    return step


@pytest.mark.parametrize(
    ("kwargs", "says"),
    [
        ({}, "no seam given"),
        ({"seam": "%CIRCLE"}, "matches no edge"),
        ({"seam": "|X and <Z"}, "connected"),
        ({"seam": "((("}, "valid selector"),
        ({"seam_near_mm": [[0.0, 0.0, 0.0]]}, "equally near"),
        ({"seam_near_mm": [[1.0, 2.0]]}, "(m, 3)"),
    ],
)
def test_bad_seam_choice_names_the_field(tmp_path, straight_step, kwargs, says):
    with pytest.raises(WorkpieceError) as info:
        load_workpiece(straight_step, cache_dir=tmp_path, **kwargs)
    expected = "workpiece.seam_near_mm" if "seam_near_mm" in kwargs else "workpiece.seam"
    assert info.value.field == expected
    assert says in info.value.message


@pytest.mark.parametrize("tolerance_mm", [0.0, -0.1, float("nan")])
def test_bad_tolerance_names_the_field(tmp_path, tolerance_mm):
    with pytest.raises(WorkpieceError) as info:
        load_workpiece("v_groove", tolerance_mm=tolerance_mm, cache_dir=tmp_path)
    assert info.value.field == "workpiece.tolerance_mm"


def test_step_takes_no_parameters(tmp_path, straight_step):
    with pytest.raises(WorkpieceError) as info:
        load_workpiece(straight_step, cache_dir=tmp_path, root_gap_mm=1.0)
    assert info.value.field == "workpiece.params.root_gap_mm"


def test_a_tolerance_too_fine_for_the_parts_size_is_refused_before_meshing(tmp_path):
    """The paper's 420 mm groove at 2e-4 mm would mesh into tens of millions of triangles:
    refused, naming workpiece.tolerance_mm and the finest tolerance that fits."""
    with pytest.raises(WorkpieceError) as info:
        load_workpiece("v_groove", tolerance_mm=2e-4, path="paper", cache_dir=tmp_path)
    assert info.value.field == "workpiece.tolerance_mm"
    assert "use at least 0.0004" in str(info.value)


def test_a_mesh_over_the_triangle_budget_is_refused(tmp_path, monkeypatch):
    """The triangle budget holds for every meshing pass (lowered here so a small part hits it)."""
    from seamtrack import constants

    monkeypatch.setattr(constants, "MAX_MESH_TRIANGLES", 500)
    with pytest.raises(WorkpieceError) as info:
        load_workpiece("v_groove", tolerance_mm=0.01, path="arc", cache_dir=tmp_path)
    assert info.value.field == "workpiece.tolerance_mm"
    assert "triangles" in str(info.value)


def test_the_mesher_meshes_coarse_inside_and_the_refinement_meets_the_tolerance():
    """The mesher discretizes the edges at the tolerance and the faces' interiors at
    INTERIOR_FACTOR times it; the interiors are refined at exact surface points until every
    probe is within the tolerance. Oracles: OCCT's own mesh at the tolerance (which strays past
    it on the paper groove's twisted faces, with more triangles), and the exact distance of
    points on the refined mesh to the BRep (``Shape.distance``)."""
    import math

    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from seamtrack.cad.kit import cadmesh

    from seamtrack.workpiece.loader import DEFAULT_ANGULAR_TOLERANCE_RAD

    size = {**SMALL, "seam_length_mm": 60.0}  # 20 mm is too short to twist its faces enough
    part = load_workpiece("v_groove", tolerance_mm=3e-3, cache=False, path="paper", **size)
    shape = part.shape
    BRepTools.Clean_s(shape.wrapped)
    BRepMesh_IncrementalMesh(shape.wrapped, 3e-3, False, DEFAULT_ANGULAR_TOLERANCE_RAD, False)
    _, one_pass, strayed, _ = cadmesh.triangulation(shape)  # OCCT's own at the tolerance
    BRepTools.Clean_s(shape.wrapped)
    assert strayed > 3e-3  # OCCT's mesh misses the tolerance here
    assert len(part.mesh.faces) < len(one_pass)  # and the refined one meets it with fewer
    assert part.deviation_mm <= 3e-3
    assert part.mesh.is_watertight and part.mesh.is_winding_consistent
    # independent check: the exact distance to the BRep of points on the mesh's largest
    # triangles (where a chord strays most) and of random points on it
    rng = np.random.default_rng(0)
    large = np.argsort(part.mesh.area_faces)[-30:]
    points = np.vstack([part.mesh.triangles[large].mean(axis=1), part.mesh.sample(30, seed=rng)])
    assert max(shape.distance(_vertex(p)) for p in points) <= 3e-3 + 1e-9
    assert math.isfinite(part.deviation_mm)
