"""find_seams: every weld of a weldment, on the exact geometry, named by joint type.

Oracles are the analytic geometry of the cad/weldment_* parts: lines of contact, groove and
opening angles, bisectors of the faces' normals, where a gusset interrupts a fillet.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.cad

cq = pytest.importorskip("cadquery")

from seamtrack.errors import WorkpieceError  # noqa: E402
from seamtrack.workpiece.weldment import classify, find_seams  # noqa: E402


def _export(tmp: Path, script: str, **params) -> Path:
    import importlib

    path = tmp / f"{script}.step"
    importlib.import_module(f"seamtrack.cad.{script}").build(**params).export_step(str(path))
    return path


@pytest.fixture(scope="module")
def steps(tmp_path_factory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("weldments")
    return {
        name: _export(tmp, f"weldment_{name}", **params)
        for name, params in (("t", {}), ("bracket", {"length_mm": 60.0}), ("uprights", {}))
    }


def _line_distance(points, a, b) -> float:
    """Largest distance of points (n, 3) from the segment a-b."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
    return float(np.linalg.norm(points - (a + t[:, None] * d), axis=1).max())


# ----------------------------------------------------------------------------- T joints
@pytest.mark.parametrize(
    ("angle_deg", "gap_mm", "thickness_mm"),
    [(90.0, 0.0, 10.0), (60.0, 0.0, 10.0), (90.0, 0.5, 8.0), (75.0, 0.8, 12.0)],
)
def test_t_fillets_lie_on_the_analytic_lines_of_contact(angle_deg, gap_mm, thickness_mm):
    seams = find_seams(
        "weldment_t", web_angle_deg=angle_deg, web_gap_mm=gap_mm, web_thickness_mm=thickness_mm
    )
    assert [s.joint for s in seams] == ["fillet", "fillet"]
    half = thickness_mm / math.sin(math.radians(angle_deg)) / 2  # half the web's foot
    a = math.radians(angle_deg)
    for s, y, opening, wall in (
        (seams[0], -half, a, [0.0, -math.sin(a), -math.cos(a)]),
        (seams[1], half, math.pi - a, [0.0, math.sin(a), math.cos(a)]),
    ):
        assert _line_distance(s.points, [0, y, 0], [100, y, 0]) < 0.01
        assert s.points[0] == pytest.approx([0, y, 0], abs=1e-9)
        assert s.points[-1] == pytest.approx([100, y, 0], abs=1e-9)
        assert s.length_mm == pytest.approx(100.0, abs=1e-9)
        assert s.opening_rad == pytest.approx(opening, abs=1e-9)
        assert s.gap_mm == pytest.approx(gap_mm, abs=1e-9)
        # Torch: bisector of the flange's normal (+Z) and the web's outward side normal.
        bisector = np.add([0.0, 0.0, 1.0], wall)
        assert np.abs(s.normals - bisector / np.linalg.norm(bisector)).max() < 1e-9
        assert s.bodies == ("flange", "web") and s.reachable


def test_the_t_from_step_gives_the_same_seams_as_its_script(steps):
    scripted = find_seams("weldment_t")
    read = find_seams(steps["t"])
    assert [(s.id, s.name, s.joint) for s in read] == [(s.id, s.name, s.joint) for s in scripted]
    for a, b in zip(read, scripted, strict=True):
        assert np.abs(a.points - b.points).max() < 1e-9
        assert np.abs(a.normals - b.normals).max() < 1e-9


def test_a_gap_wider_than_max_gap_is_no_joint():
    with pytest.raises(WorkpieceError, match="come within 1 mm") as info:
        find_seams("weldment_t", web_gap_mm=1.5)
    assert "flange and web, 1.5 mm" in str(info.value)
    assert len(find_seams("weldment_t", web_gap_mm=1.5, max_gap_mm=2.0)) == 2


# ----------------------------------------------------------------------------- the bracket
#: Every weld a welder names on the bracket (length 60): joint, bodies, start, end.
BRACKET_WELDS = [
    ("lap", ("base", "strap"), (0, -40, 0), (60, -40, 0)),  # base edge under the strap
    ("lap", ("base", "strap"), (0, -30, 0), (60, -30, 0)),  # the strap's edge on the base
    ("fillet", ("base", "web"), (0, -5, 0), (60, -5, 0)),
    ("fillet", ("base", "web"), (0, 5, 0), (25, 5, 0)),  # up to the gusset
    ("butt", ("base", "extension"), (0, 40, -10), (60, 40, -10)),  # the root side
    ("butt", ("base", "extension"), (0, 40, -8), (60, 40, -8)),  # the V groove's root
    ("fillet", ("web", "gusset"), (25, 5, 0), (25, 5, 30)),
    ("fillet", ("base", "gusset"), (25, 5, 0), (25, 30, 0)),
    ("fillet", ("web", "gusset"), (25, 5, 30), (35, 5, 30)),  # end return at its top
    ("fillet", ("base", "gusset"), (25, 30, 0), (35, 30, 0)),  # end return at its toe
    ("fillet", ("web", "gusset"), (35, 5, 0), (35, 5, 30)),
    ("fillet", ("base", "gusset"), (35, 5, 0), (35, 30, 0)),
    ("fillet", ("base", "web"), (35, 5, 0), (60, 5, 0)),  # on from the gusset
]


def test_every_weld_of_the_bracket_is_found_with_its_joint_type_and_nothing_else(steps):
    seams = find_seams(steps["bracket"])
    found = [(s.joint, s.bodies, s.points[0], s.points[-1]) for s in seams]
    unmatched = list(range(len(found)))
    for joint, bodies, start, end in BRACKET_WELDS:
        match = [
            k
            for k in unmatched
            if found[k][:2] == (joint, bodies)
            and np.allclose(found[k][2], start, atol=1e-6)
            and np.allclose(found[k][3], end, atol=1e-6)
        ]
        assert len(match) == 1, (joint, bodies, start, end)
        unmatched.remove(match[0])
    assert unmatched == []  # no false seam
    for s in seams:
        line = _line_distance(s.points, s.points[0], s.points[-1])
        assert line < 1e-9  # every weld here is straight, and the polyline lies on it


def test_the_butt_joints_groove_angle_is_measured():
    for angle in (60.0, 45.0):
        butt = [
            s
            for s in find_seams("weldment_bracket", groove_angle_deg=angle, length_mm=40.0)
            if s.joint == "butt"
        ]
        root, back = sorted(butt, key=lambda s: -s.points[0][2])
        assert root.groove_angle_rad == pytest.approx(math.radians(angle), abs=1e-9)
        assert root.normals[0] == pytest.approx([0, 0, 1], abs=1e-9)
        assert back.groove_angle_rad == 0.0  # the flush root side: a square butt from below
        assert back.normals[0] == pytest.approx([0, 0, -1], abs=1e-9)


def test_ids_follow_position_and_names_count_per_pair(steps):
    seams = find_seams(steps["bracket"])
    assert [s.id for s in seams] == [f"s{k + 1}" for k in range(len(seams))]
    starts = [tuple(np.round(s.points[0], 6)) for s in seams]
    assert starts == sorted(starts)
    assert [s.name for s in seams if s.bodies == ("base", "web")] == [
        "base/web/0",
        "base/web/1",
        "base/web/2",
    ]


def test_seams_run_from_their_lexicographically_smallest_end(steps):
    for path in steps.values():
        for s in find_seams(path):
            assert tuple(s.points[0]) < tuple(s.points[-1]), s.label


def test_reachability_sees_the_neighbouring_upright(steps):
    seams = find_seams(steps["uprights"])
    # Outer fillets look out over the base; inner ones at 45 deg meet the next upright (20 mm
    # away, 40 mm tall) within 100 mm of torch, and clear it with a 25 mm torch.
    assert [s.reachable for s in seams] == [True, False, False, False, False, True]
    assert all(s.reachable for s in find_seams(steps["uprights"], torch_length_mm=25.0))


def test_records_carry_degrees_only_at_the_edge(steps):
    record = find_seams(steps["t"])[0].record()
    assert set(record) >= {
        "id",
        "joint",
        "bodies",
        "points_mm",
        "normals",
        "length_mm",
        "opening_deg",
        "gap_mm",
        "reachable",
    }
    assert record["opening_deg"] == pytest.approx(90.0)


@pytest.mark.parametrize(
    ("ends", "lying", "opening_deg", "joint"),
    [
        ((True, False), (False, True), 90, "fillet"),
        ((False, True), (True, True), 90, "lap"),
        ((True, True), (False, False), 60, "butt"),
        ((True, True), (False, False), 180, "butt"),
        ((True, True), (True, True), 180, "edge"),
        ((True, True), (True, False), 180, "outside_corner"),
        ((True, True), (False, False), 270, "outside_corner"),
    ],
)
def test_the_rules_name_the_joint(ends, lying, opening_deg, joint):
    assert classify(ends, lying, math.radians(opening_deg)) == joint


# ----------------------------------------------------------------------------- bad input
def test_a_step_without_solids_is_refused(tmp_path):
    path = tmp_path / "sheet.step"
    cq.exporters.export(cq.Workplane().rect(10, 10).extrude(1).faces(">Z").val(), str(path))
    with pytest.raises(WorkpieceError, match="holds no solid") as info:
        find_seams(path)
    assert info.value.field == "workpiece.step"


def test_solids_that_never_touch_are_refused(tmp_path):
    import importlib

    weldment = importlib.import_module("seamtrack.cad.kit.cadweldment")
    apart = weldment.Weldment(
        bodies={
            "a": weldment.box((0, 10), (0, 10), (0, 10)),
            "b": weldment.box((30, 40), (0, 10), (0, 10)),
        }
    )
    path = tmp_path / "apart.step"
    apart.export_step(str(path))
    with pytest.raises(WorkpieceError, match=r"nearest: a and b, 20 mm"):
        find_seams(path)


def test_one_solid_is_no_weldment(tmp_path):
    path = tmp_path / "one.step"
    cq.exporters.export(cq.Workplane().box(10, 10, 10), str(path))
    with pytest.raises(WorkpieceError, match="holds 1 solid"):
        find_seams(path)


def test_a_step_file_edited_in_place_is_searched_again(tmp_path):
    upright = _export(tmp_path, "weldment_t")
    first = find_seams(upright)
    tilted = _export(tmp_path, "weldment_t", web_angle_deg=60.0)
    assert tilted == upright  # the same path, new content
    again = find_seams(tilted)
    assert math.degrees(first[0].opening_rad) == pytest.approx(90.0)
    assert math.degrees(again[0].opening_rad) == pytest.approx(60.0)
    with pytest.raises(ValueError):
        again[0].points[0, 0] = 1.0  # shared results are read-only
