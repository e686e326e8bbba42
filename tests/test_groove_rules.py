"""Every weldx groove type's fields checked against ISO 9692-1's meaning before meshing: each type
refuses its bad neighbours naming the right field, and each type's valid example is drawn (and
two of them meshed) as before."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytestmark = [pytest.mark.cad]

pytest.importorskip("cadquery")
pytest.importorskip("weldx")

from seamtrack.errors import WorkpieceError  # noqa: E402
from seamtrack.workpiece.groove_rules import check_path_params, check_plate_width  # noqa: E402
from seamtrack.workpiece.grooves import groove_classes, groove_spec, plate_profiles  # noqa: E402
from seamtrack.workpiece.loader import load_workpiece  # noqa: E402

#: A valid groove of every type (ISO 9692-1-like values).
VALID = {
    "IGroove": {"t_mm": 4, "b_mm": 1},
    "VGroove": {"t_mm": 10, "alpha_deg": 60, "b_mm": 1, "c_mm": 1},
    "VVGroove": {"t_mm": 20, "alpha_deg": 70, "beta_deg": 10, "h_mm": 5, "c_mm": 1, "b_mm": 1},
    "UVGroove": {"t_mm": 20, "alpha_deg": 60, "beta_deg": 10, "R_mm": 6, "h_mm": 4, "b_mm": 1},
    "UGroove": {"t_mm": 15, "beta_deg": 9, "R_mm": 6, "c_mm": 3, "b_mm": 1},
    "HVGroove": {"t_mm": 10, "beta_deg": 45, "c_mm": 1, "b_mm": 1},
    "HUGroove": {"t_mm": 15, "beta_deg": 9, "R_mm": 6, "c_mm": 3, "b_mm": 1},
    "DVGroove": {"t_mm": 20, "alpha_1_deg": 60, "alpha_2_deg": 60, "c_mm": 2, "b_mm": 1},
    "DUGroove": {"t_mm": 40, "beta_1_deg": 8, "beta_2_deg": 8, "R_mm": 6, "R2_mm": 6, "b_mm": 1},
    "DHVGroove": {"t_mm": 20, "beta_1_deg": 45, "beta_2_deg": 45, "c_mm": 2, "b_mm": 1},
    "DHUGroove": {"t_mm": 40, "beta_1_deg": 8, "beta_2_deg": 8, "R_mm": 6, "R2_mm": 6},
}

#: Bad neighbours of the valid grooves: (type, changed fields, the field the error names).
BAD = [
    # every field of every type: not a number, not finite, a boolean
    *[
        (kind, {key: value}, key)
        for kind, fields in VALID.items()
        for key in fields
        for value in (True, "1", math.nan, math.inf, 1e300, -1e300)
    ],
    # angles: strictly above 0, no flatter than the caps
    ("VGroove", {"alpha_deg": 0}, "alpha_deg"),
    ("VGroove", {"alpha_deg": -30}, "alpha_deg"),
    ("VGroove", {"alpha_deg": 180}, "alpha_deg"),
    ("DVGroove", {"alpha_1_deg": -30}, "alpha_1_deg"),
    ("DVGroove", {"alpha_2_deg": 170}, "alpha_2_deg"),
    ("VVGroove", {"beta_deg": 0}, "beta_deg"),
    ("UVGroove", {"alpha_deg": -60}, "alpha_deg"),
    ("UGroove", {"beta_deg": 90}, "beta_deg"),
    ("HVGroove", {"beta_deg": -45}, "beta_deg"),
    ("HUGroove", {"beta_deg": 85}, "beta_deg"),
    ("DUGroove", {"beta_2_deg": 0}, "beta_2_deg"),
    ("DHVGroove", {"beta_1_deg": 90}, "beta_1_deg"),
    ("DHUGroove", {"beta_2_deg": -8}, "beta_2_deg"),
    # thickness, gap, root face, radii within the plate
    ("IGroove", {"t_mm": 0}, "t_mm"),
    ("IGroove", {"b_mm": 5}, "b_mm"),
    ("VGroove", {"b_mm": -1}, "b_mm"),
    ("VGroove", {"c_mm": 12}, "c_mm"),
    ("VGroove", {"c_mm": 10}, "c_mm"),
    ("HVGroove", {"c_mm": 10}, "c_mm"),
    ("UGroove", {"R_mm": 50}, "R_mm"),
    ("UGroove", {"R_mm": 12}, "R_mm"),  # c 3 + R 12 reaches the top of t 15
    ("UGroove", {"R_mm": 0}, "R_mm"),
    ("HUGroove", {"R_mm": 13}, "R_mm"),
    ("UVGroove", {"R_mm": 1}, "R_mm"),  # cannot meet the V (4 mm deep at 60 deg: 2.3 wide)
    ("UVGroove", {"h_mm": 20}, "h_mm"),
    ("UVGroove", {"R_mm": 19.9}, "R_mm"),  # its arc ends 20.3 mm up, above the plate
    ("VVGroove", {"h_mm": 19}, "h_mm"),
    ("VVGroove", {"h_mm": 1}, "h_mm"),
    # a double groove's depths and root face within t
    ("DVGroove", {"h1_mm": 10, "h2_mm": 10}, "h1_mm"),
    ("DVGroove", {"h2_mm": 10}, "h2_mm"),  # h1 takes h2: 10 + 10 + 2 > 20
    ("DHVGroove", {"h1_mm": 15}, "h1_mm"),
    ("DUGroove", {"R2_mm": 30}, "R2_mm"),
    ("DUGroove", {"t_mm": 2, "R_mm": 0.5, "R2_mm": 0.5}, "c_mm"),  # weldx's default c is 3
    ("DHUGroove", {"c_mm": 50}, "c_mm"),
    ("DHUGroove", {"h1_mm": 4}, "R_mm"),
]


@pytest.mark.parametrize("kind", sorted(VALID))
def test_every_type_s_valid_example_passes_and_is_drawn_inside_its_plate(kind):
    spec = groove_spec({"type": kind, **VALID[kind]})
    plates, walls, _ = plate_profiles(spec, 40.0, 0.01)
    t = VALID[kind]["t_mm"]
    for plate in plates:
        assert np.isfinite(plate).all()
        assert np.ptp(plate[:, 1]) == pytest.approx(t)  # from the plate's bottom to its top
    assert np.isfinite(walls).all()


def test_the_valid_table_covers_every_groove_the_code_builds():
    assert set(VALID) == set(groove_classes())


@pytest.mark.parametrize(
    ("kind", "change", "field"),
    BAD,
    ids=[f"{k}-{'-'.join(f'{a}={b}' for a, b in c.items())}" for k, c, _ in BAD],
)
def test_bad_neighbours_are_refused_naming_their_field(kind, change, field):
    with pytest.raises(WorkpieceError) as err:
        groove_spec({"type": kind, **VALID[kind], **change})
    assert err.value.field == f"workpiece.groove.{field}"
    assert err.value.fix


def test_ffgroove_is_refused_as_no_butt_groove():
    with pytest.raises(WorkpieceError) as err:
        groove_spec({"type": "FFGroove", "t_mm": 2})
    assert err.value.field == "workpiece.groove.type" and "frame" in str(err.value)


@pytest.mark.parametrize("value", ["abc", True, -5.0, 0.0, 1e300, math.nan, [40]])
def test_plate_width_is_a_number_in_range(value):
    with pytest.raises(WorkpieceError) as err:
        check_plate_width(value)
    assert err.value.field == "workpiece.params.plate_width_mm"


@pytest.mark.parametrize(
    ("params", "field"),
    [
        ({"seam_length_mm": "abc"}, "seam_length_mm"),
        ({"seam_length_mm": True}, "seam_length_mm"),
        ({"seam_length_mm": 1e300}, "seam_length_mm"),
        ({"arc_radius_mm": False}, "arc_radius_mm"),
        ({"path": 3}, "path"),
    ],
)
def test_path_parameters_are_checked(params, field):
    with pytest.raises(WorkpieceError) as err:
        check_path_params(params)
    assert err.value.field == f"workpiece.params.{field}"


@pytest.mark.parametrize("kind", ["DUGroove", "HVGroove"])
def test_valid_grooves_still_mesh(kind, tmp_path):
    part = load_workpiece(
        groove={"type": kind, **VALID[kind]},
        cache_dir=tmp_path,
        tolerance_mm=0.05,
        path="straight",
        seam_length_mm=10.0,
        plate_width_mm=30.0,
    )
    assert part.mesh.is_watertight and part.mesh.body_count == 2
    assert part.joint == "butt"
