"""The joint's motion while it is welded (seamtrack.heat.motion): physical oracles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.errors import SeamtrackError
from seamtrack.heat.constraints import Clamp, Tack
from seamtrack.heat.distortion import permanent_angle_rad, transverse_shrinkage_mm
from seamtrack.heat.materials import thermal_material
from seamtrack.heat.motion import joint_motion

STEEL = thermal_material("carbon_steel")


def _motion(power_w: float = 800.0, **kw: object) -> object:
    args: dict = dict(
        power_w=power_w, speed_mm_s=4.0, material=STEEL, thickness_mm=2.0,
        plate_width_mm=100.0, seam_length_mm=200.0, angle_peak_rad=math.radians(2.0),
        angle_peak_q_per_h2=40.0, gap_rotation_rad=math.radians(0.3),
    )  # fmt: skip
    args.update(kw)
    return joint_motion(**args)


def test_zero_heat_moves_nothing() -> None:
    m = _motion(power_w=0.0, gap_rotation_rad=0.0)
    s = np.linspace(0, 200, 41)
    for t in (0.0, 10.0, 40.0, 80.0):
        lat, ver = m.shift_mm(s, t)
        assert np.all(lat == 0) and np.all(ver == 0)


def test_mirror_and_no_fixed_plate_symmetry() -> None:
    s = np.linspace(0, 200, 41)
    left, right, none = (_motion(fixed_plate=f) for f in ("left", "right", "none"))
    ll, lv = left.shift_mm(s, 30.0)
    rl, rv = right.shift_mm(s, 30.0)
    nl, _ = none.shift_mm(s, 30.0)
    np.testing.assert_array_equal(ll, -rl)  # mirror: the other plate clamped
    np.testing.assert_array_equal(lv, rv)
    assert np.all(nl == 0)  # both plates free: the centre does not move across
    assert np.abs(ll).max() > 0


def test_cold_weld_moves_by_the_cited_relations() -> None:
    # Far behind the arc the weld is cold: the seam sits W * beta / 2 lower and, one plate
    # clamped, half the Okerblom shrinkage across.
    m = _motion(gap_rotation_rad=0.0)
    lat, ver = m.shift_mm(np.array([5.0]), 200.0)
    q = 800.0 / 4.0
    beta = permanent_angle_rad(q, thickness_mm=2.0, peak_rad=math.radians(2.0), peak_q_per_h2=40.0)
    s = transverse_shrinkage_mm(q, thickness_mm=2.0, material=STEEL)
    assert ver[0] == pytest.approx(-100.0 * beta / 2, rel=1e-6)
    assert abs(lat[0]) == pytest.approx(s / 2, rel=1e-6)


def test_shrinkage_grows_with_heat_and_falls_with_thickness() -> None:
    a = transverse_shrinkage_mm(200.0, thickness_mm=2.0, material=STEEL)
    assert transverse_shrinkage_mm(400.0, thickness_mm=2.0, material=STEEL) == pytest.approx(2 * a)
    assert transverse_shrinkage_mm(200.0, thickness_mm=4.0, material=STEEL) == pytest.approx(a / 2)


def test_angle_peaks_at_its_heat_input_parameter() -> None:
    peak = math.radians(2.0)
    angles = [
        permanent_angle_rad(p * 4.0, thickness_mm=2.0, peak_rad=peak, peak_q_per_h2=40.0)
        for p in (10.0, 40.0, 160.0)
    ]
    assert angles[1] == pytest.approx(peak)
    assert angles[0] < angles[1] and angles[2] < angles[1]


def test_a_clamp_ahead_holds_the_gap() -> None:
    s = np.array([150.0])
    free = _motion()
    held = _motion(constraints=[Clamp(180.0)])
    assert abs(free.shift_mm(s, 10.0)[0][0]) > 0.1
    assert held.shift_mm(s, 10.0)[0][0] == 0.0


def test_a_weak_tack_breaks_a_strong_one_holds() -> None:
    weak = _motion(constraints=[Tack(150.0, 1.0, 0.5)])
    strong = _motion(constraints=[Tack(150.0, 1.0, 0.5, electrode_strength_mpa=1e12)])
    assert weak.broken() == [True]
    assert strong.broken() == [False]


def test_a_tack_outside_the_seam() -> None:
    with pytest.raises(SeamtrackError, match="outside the seam"):
        _motion(constraints=[Tack(250.0, 10.0, 2.0)])
