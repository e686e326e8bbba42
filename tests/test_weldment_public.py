"""find_seams on STEP files made by other people (tests/data/step/SOURCES.md).

What a welder names on each part was decided by hand from the part (its KCL source, its
bodies' bounding boxes and `seamtrack seams --view`), and each found seam is checked against
geometry taken independently from the solids: the faces and bounding boxes of the bodies that
meet there. False seams are counted, so that a change in them is noticed.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.cad

pytest.importorskip("cadquery")

from seamtrack.workpiece import contacts  # noqa: E402
from seamtrack.workpiece.sources import read_bodies  # noqa: E402
from seamtrack.workpiece.weldment import find_seams  # noqa: E402

DATA = Path(__file__).parent / "data" / "step"
INCH = 25.4


def _bounds(solid) -> tuple[np.ndarray, np.ndarray]:
    return contacts.bounds(solid.wrapped)


# ----------------------------------------------------------------------------- shelf bracket
# KittyCAD "Shelf Bracket": a long leg (117.5 x 8.92 x 152.4 mm, 4 holes), the 90 deg bend and
# a short leg (2 holes), modelled as three solids that meet end face to end face. Built from
# these three pieces, a welder names two square butt joints, each welded from both sides
# (the outside and the inside of the bend): 4 seams, all 152.4 mm (6 in) long. The mounting
# holes lie in one body each: no seam may come from them (false seams: 0).
BRACKET = DATA / "kittycad-shelf-bracket.step"


@pytest.fixture(scope="module")
def bracket():
    return read_bodies(BRACKET), find_seams(BRACKET)


def test_the_shelf_bracket_gives_its_two_butt_joints_on_both_sides_and_nothing_else(bracket):
    bodies, seams = bracket
    names = [n for n, _ in bodies]
    assert names == ["NONE", "NONE.2", "NONE.3"]  # long leg, bend, short leg (file order)
    assert len(seams) == 4  # 2 butt joints x 2 sides; false seams: 0
    assert all(s.joint == "butt" for s in seams)
    assert all(s.groove_angle_rad == 0.0 for s in seams)  # square butt: flush faces
    assert sorted(s.bodies for s in seams) == [("NONE", "NONE.2")] * 2 + [("NONE.2", "NONE.3")] * 2
    for s in seams:
        assert s.length_mm == pytest.approx(6 * INCH, abs=1e-6)
        assert s.gap_mm == 0.0
        assert s.reachable


def test_the_bracket_butt_seams_lie_on_the_lines_where_the_pieces_meet(bracket):
    bodies, seams = bracket
    (lo_long, hi_long), (lo_bend, hi_bend), (lo_short, hi_short) = (_bounds(b) for _, b in bodies)
    # Long leg against the bend: the end face x = 0, at the two plate faces y = min, y = max.
    assert hi_bend[0] == pytest.approx(lo_long[0], abs=1e-6)
    long_lines = [(lo_long[0], lo_long[1]), (lo_long[0], hi_long[1])]
    # Short leg against the bend: the end face y = max of the short leg, at x = min and max.
    assert lo_bend[1] == pytest.approx(hi_short[1], abs=1e-3)
    short_lines = [(lo_short[0], hi_short[1]), (hi_short[0], hi_short[1])]
    for s in seams:
        lines = long_lines if s.bodies == ("NONE", "NONE.2") else short_lines
        xy = s.points[:, :2]
        off = min(float(np.abs(xy - np.array(line)).max()) for line in lines)
        assert off < 0.01, s.label
        assert s.points[:, 2].min() == pytest.approx(lo_long[2], abs=1e-6)
        assert s.points[:, 2].max() == pytest.approx(hi_long[2], abs=1e-6)
    # ... one seam on each of the four lines.
    ends = {(round(float(s.points[0, 0]), 2), round(float(s.points[0, 1]), 2)) for s in seams}
    assert len(ends) == 4


# ----------------------------------------------------------------------------- exhaust manifold
# KittyCAD "Exhaust Manifold, a welded exhaust header": four swept primary tubes (1.625 in OD)
# modelled through the ports of a 1/8 in flange (each tube starts at the flange's underside;
# the ports have the tubes' inner diameter, so the bores run flush). A welder names one weld
# per tube: the fillet all round where the tube comes out of the flange's top face (4). Not
# welds: the flush bores at the underside, the four mounting holes (one body), the tubes'
# free ends. The tubes do not touch each other. Found: the 4 fillets, false seams: 0. These
# seams come from where the two bodies' surfaces cross (`crossings.crossing_pieces`), not
# from facing planar faces: there are none between a tube and the flange.
EXHAUST = DATA / "kittycad-exhaust-manifold.step.gz"
TUBE_OD_MM = 1.625 * INCH


@pytest.fixture(scope="module")
def exhaust(tmp_path_factory):
    path = tmp_path_factory.mktemp("public") / "exhaust-manifold.step"
    path.write_bytes(gzip.decompress(EXHAUST.read_bytes()))
    # Coarser sampling than the default keeps this swept-surface part to well under a minute.
    return read_bodies(path), find_seams(path, tolerance_mm=0.2, spacing_mm=5.0)


@pytest.mark.slow
def test_each_exhaust_tube_has_its_fillet_all_round_at_the_flange_top(exhaust):
    bodies, seams = exhaust
    names = [n for n, _ in bodies]
    flange = names[-1]
    assert len(bodies) == 5
    assert len(seams) == 4  # one per tube; false seams: 0
    assert sorted(s.bodies for s in seams) == [(n, flange) for n in names[:4]]
    lo_f, hi_f = _bounds(bodies[-1][1])
    for s, (_, tube) in zip(sorted(seams, key=lambda s: s.bodies), bodies[:4], strict=True):
        assert s.joint == "fillet"
        assert math.degrees(s.opening_rad) == pytest.approx(90.0, abs=0.1)
        assert np.allclose(s.points[0], s.points[-1], atol=1e-6)  # closed round the tube
        # Independently: the tube's start cap (its planar face on the flange's underside)
        # gives the tube's axis and outer radius; its first 3 in run straight up through the
        # flange, so the weld is that circle lifted to the flange's top face.
        cap = next(
            f
            for f in contacts.planar_faces(tube.wrapped)
            if abs(f.normal[1]) > 0.999 and abs(f.point[1] - lo_f[1]) < 1e-6
        )
        centre = 0.5 * (cap.lo + cap.hi)
        radius = 0.5 * (cap.hi[0] - cap.lo[0])
        assert radius == pytest.approx(TUBE_OD_MM / 2, abs=1e-3)
        assert np.abs(s.points[:, 1] - hi_f[1]).max() < 0.01
        r = np.linalg.norm(s.points[:, [0, 2]] - centre[[0, 2]], axis=1)
        assert np.abs(r - radius).max() < 0.01
        assert s.length_mm == pytest.approx(2 * math.pi * radius, rel=2e-3)
        # The torch looks up and out of the corner: square to the tube's axis (y) at 45 deg.
        assert np.allclose(s.normals[:, 1], math.sqrt(0.5), atol=1e-3)
