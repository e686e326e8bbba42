"""The cad/ joint library: valid solids, analytic volumes, seams on their faces and paths."""

from __future__ import annotations

import importlib
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.cad

cq = pytest.importorskip("cadquery")

from seamtrack.geometry.seam import paper_curve  # noqa: E402
from seamtrack.workpiece.loader import load_workpiece  # noqa: E402

FAMILIES = ("square_butt", "v_groove", "fillet_t", "lap", "outside_corner")
PATHS = ("straight", "arc", "paper", "corner")
CAD_DIR = Path(__file__).resolve().parents[1] / "cad"


def joint_module(family: str):
    return importlib.import_module(f"seamtrack.cad.{family}")


def section_area_and_moment(family: str) -> tuple[float, float]:
    """Analytic cross-section area (mm^2) and first moment about the seam along u (mm^3) of
    each family at its default parameters (u: across the seam, to the left of travel)."""
    if family == "v_groove":  # T=10, W=50, 60 deg, root face 1, no gap: symmetric
        t, w, f, half = 10.0, 50.0, 1.0, math.radians(30.0)
        return 2 * w * t - (t - f) ** 2 * math.tan(half), 0.0
    if family == "square_butt":  # T=10, W=50, gap 1 on a 3 x 20 backing: symmetric
        return 2 * 50.0 * 10.0 + 3.0 * 20.0, 0.0
    if family == "fillet_t":  # flange 100 x 10 and web 10 x 50, both centred at u = 5
        area = 100.0 * 10.0 + 10.0 * 50.0
        return area, area * 5.0
    if family == "lap":  # bottom 50 x 3 over u in [-30, 20], top 50 x 3 over u in [0, 50]
        return 300.0, 150.0 * -5.0 + 150.0 * 25.0
    if family == "outside_corner":  # 2 W T - f^2, symmetric
        return 2 * 40.0 * 6.0 - 2.0**2, 0.0
    raise AssertionError(family)


def analytic_volume(family: str, path: str) -> float:
    """Pappus-type volumes: arc and mitred corner shorten the inner side by u * turn."""
    area, moment = section_area_and_moment(family)
    if path == "straight":
        return area * 200.0
    if path == "arc":  # radius 100, length 200: turn of 2 rad
        return area * 200.0 - moment * 200.0 / 100.0
    if path == "corner":  # 90 deg mitre: each leg loses u tan(45 deg)
        return area * 200.0 - 2.0 * math.tan(math.radians(45.0)) * moment
    # paper: a full turn of a helix of radius 10 and pitch 400; the first moment's terms
    # average out over the turn
    return area * 400.0 * math.hypot(1.0, math.pi / 20.0)


@pytest.fixture(scope="module")
def joints() -> dict[tuple[str, str], object]:
    return {(f, p): joint_module(f).build(path=p) for f in FAMILIES for p in PATHS}


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("family", FAMILIES)
def test_joint_is_a_valid_solid_with_the_analytic_volume(joints, family, path):
    joint = joints[family, path]
    assert joint.solid.isValid()
    assert joint.solid.Volume() == pytest.approx(analytic_volume(family, path), rel=1e-3)
    assert next(iter(joint.seams)) == "root"


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("family", FAMILIES)
def test_joint_meshes_watertight_with_consistent_winding(tmp_path, family, path):
    part = load_workpiece(family, tolerance_mm=0.1, cache_dir=tmp_path, path=path)
    mesh = part.mesh
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0
    assert mesh.vertices.dtype == np.float64
    rel = 1e-3 if path in ("straight", "corner") else 1e-2  # chords cut curved faces
    assert mesh.volume == pytest.approx(analytic_volume(family, path), rel=rel)
    assert part.deviation_mm <= 0.1


@pytest.mark.parametrize("family", FAMILIES)
def test_root_seam_lies_on_the_path(joints, family):
    """The seam vertex of every profile sits on the path: straight seam on the X axis."""
    for edge in joints[family, "straight"].seams["root"]:
        for s in np.linspace(0.0, 1.0, 7):
            _, y, z = edge.positionAt(s).toTuple()
            assert abs(y) < 1e-9 and abs(z) < 1e-9


@pytest.mark.parametrize("family", FAMILIES)
def test_paper_seam_edge_matches_eq_15_17(joints, family):
    edge = joints[family, "paper"].seams["root"][0]
    points = np.array([edge.positionAt(s).toTuple() for s in np.linspace(0, 1, 801)])
    # The closest point of the exact curve to each edge point: refine X by Newton.
    x = points[:, 0].copy()
    k = math.pi / 200.0
    for _ in range(5):
        c = paper_curve(x)
        d1 = np.column_stack([np.ones_like(x), -10 * k * np.sin(k * x), 10 * k * np.cos(k * x)])
        d2 = np.column_stack(
            [np.zeros_like(x), -10 * k * k * np.cos(k * x), -10 * k * k * np.sin(k * x)]
        )
        r = c - points
        x -= np.sum(r * d1, axis=1) / (np.sum(d1 * d1, axis=1) + np.sum(r * d2, axis=1))
    assert np.linalg.norm(paper_curve(x) - points, axis=1).max() < 1e-5


@pytest.mark.parametrize("family", FAMILIES)
def test_tack_welds_add_material_on_the_seam(family):
    plain = joint_module(family).build()
    tacked = joint_module(family).build(tacks=3, tack_length_mm=8.0, tack_height_mm=1.5)
    assert tacked.solid.isValid()
    added = tacked.solid.Volume() - plain.solid.Volume()
    # three cylinders of radius 1.5 and length 8, at least the 60 deg V opening of each outside
    cylinder = math.pi * 1.5**2 * 8.0
    assert 3 * cylinder / 6.5 < added < 3 * cylinder
    # the seam is where the joint is, under the tacks too
    assert tacked.seams["root"][0].Length() == pytest.approx(200.0)


@pytest.mark.parametrize(
    ("family", "params"),
    [
        ("v_groove", {"root_gap_mm": 2.0}),
        ("square_butt", {"root_gap_mm": 0.0, "misalignment_mm": 2.0}),
        ("square_butt", {"misalignment_mm": 1.5}),
        ("fillet_t", {"web_gap_mm": 1.0}),
        ("fillet_t", {"web_angle_deg": 60.0}),
        ("lap", {"sheet_gap_mm": 0.5}),
    ],
)
def test_variants_build_valid_solids_with_seams_on_the_path(family, params):
    joint = joint_module(family).build(**params)
    assert joint.solid.isValid()
    assert all(s.isValid() for s in joint.solid.Solids())
    start = joint.seams["root"][0].startPoint()
    assert abs(start.y) < 1e-9 and abs(start.z) < 1e-9


def test_script_runs_alone_and_exports_step(tmp_path):
    out = tmp_path / "part.step"
    result = subprocess.run(
        [sys.executable, str(CAD_DIR / "lap.py"), "path=arc", "--step", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    assert "valid solid: True" in result.stdout
    assert out.read_bytes().startswith(b"ISO-10303-21")
