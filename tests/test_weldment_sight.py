"""A seam between two bodies needs a free line of sight between their faces: blocks in a row weld
only to their neighbours, a body in a gap hides the stretch it fills; and when no seam is left,
the refusal says what is really wrong (containment, coincident bodies, seams too short)."""

from __future__ import annotations

import time

import numpy as np
import pytest

pytestmark = [pytest.mark.cad]

cq = pytest.importorskip("cadquery")

from seamtrack.errors import WorkpieceError  # noqa: E402
from seamtrack.workpiece.weldment import SeamSearch, find_seams, seams_of_bodies  # noqa: E402


def _box(lo, hi):
    size = np.subtract(hi, lo)
    return cq.Solid.makeBox(*size, cq.Vector(*lo))


def _row(n: int, size: float = 1.0) -> list[tuple[str, object]]:
    return [(f"c{i}", _box((i * size, 0, 0), ((i + 1) * size, size, size))) for i in range(n)]


def _square_edges(x: float) -> set[tuple[tuple[float, ...], tuple[float, ...]]]:
    """The four edges of the unit contact square in the plane at x (start, end rounded)."""
    corners = [(x, 0.0, 0.0), (x, 1.0, 0.0), (x, 1.0, 1.0), (x, 0.0, 1.0)]
    out = set()
    for k in range(4):
        a, b = sorted((corners[k], corners[(k + 1) % 4]))
        out.add((a, b))
    return out


@pytest.mark.parametrize("n", [3, 10, 50])
def test_blocks_in_a_row_weld_only_to_their_neighbours(n):
    started = time.perf_counter()
    seams = seams_of_bodies(_row(n))
    spent = time.perf_counter() - started
    print(f"{n} blocks: {len(seams)} seams in {spent:.2f} s")
    by_pair: dict[tuple[str, str], set] = {}
    for s in seams:
        ends = tuple(
            tuple(round(float(v), 9) + 0.0 for v in p) for p in (s.points[0], s.points[-1])
        )
        by_pair.setdefault(s.bodies, set()).add(ends)
        assert s.gap_mm == pytest.approx(0.0, abs=1e-9)
        assert s.length_mm == pytest.approx(1.0, abs=1e-9)
    # Exactly the n - 1 touching pairs, each with the four free edges of its contact square.
    assert set(by_pair) == {(f"c{i}", f"c{i + 1}") for i in range(n - 1)}
    for i in range(n - 1):
        assert by_pair[(f"c{i}", f"c{i + 1}")] == _square_edges(float(i + 1))
    assert len(seams) == 4 * (n - 1)


def test_three_blocks_from_a_step_assembly(tmp_path):
    assembly = cq.Assembly(name="row")
    for name, solid in _row(3):
        assembly.add(solid, name=name)
    path = tmp_path / "row.step"
    assembly.export(str(path), exportType="STEP")
    seams = find_seams(path)
    assert {s.bodies for s in seams} == {("c0", "c1"), ("c1", "c2")}
    assert all(s.gap_mm == 0.0 for s in seams) and len(seams) == 8


def test_a_body_in_part_of_a_gap_hides_that_stretch_of_the_seam():
    """Plates x in [0, 1] and [2, 3] (y in [0, 4]) face each other across 1 mm; a block fills
    the gap for y < 2: their two seams along the gap run from y = 2 to y = 4 only."""
    bodies = [
        ("a", _box((0, 0, 0), (1, 4, 1))),
        ("b", _box((2, 0, 0), (3, 4, 1))),
        ("c", _box((1, 0, 0), (2, 2, 1))),
    ]
    across = [s for s in seams_of_bodies(bodies) if s.bodies == ("a", "b")]
    assert len(across) == 2
    for s in across:
        assert s.gap_mm == pytest.approx(1.0)
        assert s.length_mm == pytest.approx(2.0, abs=1e-6)
        assert s.points[:, 1].min() == pytest.approx(2.0, abs=1e-6)
        assert s.points[:, 1].max() == pytest.approx(4.0, abs=1e-9)
        assert np.allclose(s.points[:, 0], 1.5)  # the middle of the gap


def test_a_gap_filled_by_a_third_body_gives_no_seam_and_says_so():
    bodies = [("a", _box((0, 0, 0), (1, 1, 1))), ("b", _box((1.5, 0, 0), (2.5, 1, 1)))]
    bodies.insert(1, ("m", _box((1, 0, 0), (1.5, 1, 1))))
    seams = seams_of_bodies(bodies)
    assert {s.bodies for s in seams} == {("a", "m"), ("m", "b")}


def test_tiny_blocks_are_told_about_min_length_and_the_value_that_finds_them():
    bodies = _row(2, size=0.01)
    with pytest.raises(WorkpieceError) as err:
        seams_of_bodies(bodies)
    message = str(err.value)
    assert "min_length_mm" in message and "0.005" in message
    seams = seams_of_bodies(bodies, SeamSearch(min_length_mm=0.005))
    assert len(seams) == 4
    assert all(s.length_mm == pytest.approx(0.01) for s in seams)


def test_a_box_inside_another_is_containment():
    bodies = [("outer", _box((0, 0, 0), (10, 10, 10))), ("inner", _box((4, 4, 4), (6, 6, 6)))]
    with pytest.raises(WorkpieceError, match="inner lies wholly inside outer"):
        seams_of_bodies(bodies)


def test_two_coincident_boxes_are_told_so():
    bodies = [("a", _box((0, 0, 0), (10, 10, 10))), ("b", _box((0, 0, 0), (10, 10, 10)))]
    with pytest.raises(WorkpieceError, match="coincident"):
        seams_of_bodies(bodies)
