"""Tacks and clamps (seamtrack.heat.constraints): a tack's strength is AISC's for a partial-
penetration groove weld; constraints off the seam are refused by name."""

from __future__ import annotations

import pytest

from seamtrack.errors import SeamtrackError
from seamtrack.heat.constraints import E70_STRENGTH_MPA, Clamp, Tack, check_constraints


def test_e70_is_70_ksi() -> None:
    assert E70_STRENGTH_MPA == pytest.approx(482.6, abs=0.1)


def test_tack_breaks_above_0_6_fexx_times_its_throat_area() -> None:
    tack = Tack(position_mm=10.0, length_mm=8.0, throat_mm=2.0, electrode_strength_mpa=500.0)
    limit = 0.6 * 500.0 * 2.0 * 8.0  # N: MPa * mm^2
    assert tack.break_force_n == pytest.approx(limit)
    assert tack.holds(limit * 0.999) and tack.holds(-limit * 0.999)
    assert not tack.holds(limit * 1.001) and not tack.holds(-limit * 1.001)
    assert Clamp(position_mm=0.0).holds(1e12)


@pytest.mark.parametrize(
    ("constraints", "field"),
    [
        ([Tack(-1.0, 8.0, 2.0)], "tacks[0].position_mm"),
        ([Clamp(5.0), Tack(120.1, 8.0, 2.0)], "tacks[1].position_mm"),
        ([Tack(50.0, 0.0, 2.0)], "tacks[0].length_mm"),
        ([Tack(50.0, 8.0, -2.0)], "tacks[0].throat_mm"),
    ],
)
def test_a_constraint_off_the_seam_names_its_field(constraints, field: str) -> None:
    with pytest.raises(SeamtrackError) as info:
        check_constraints(constraints, 120.0, field="tacks")
    assert info.value.field == field


def test_constraints_on_the_seam_pass() -> None:
    check_constraints([Clamp(0.0), Tack(60.0, 8.0, 2.0), Clamp(120.0)], 120.0, field="tacks")
