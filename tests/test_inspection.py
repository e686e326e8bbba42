"""ISO 5817 on a weld's stations: the limits of Table 1 worked by hand for a few stations, and the
short-imperfection rule (25 mm in any 100 mm)."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.workpiece.inspection import inspect_weld, only_short, station_lengths_mm

S = np.arange(0.0, 300.5, 1.0)  # a 300 mm weld, a station a millimetre
T = 20.0  # plate thickness: the 20 mm V of the multi-pass scenes


def _weld(**kw):
    base = {"thickness_mm": T, "width_mm": 24.0, "excess_mm": 1.0, "underfill_mm": 0.0}
    return inspect_weld(S, **{**base, **kw})


def test_a_clean_weld_meets_level_b() -> None:
    weld = _weld()
    assert weld.level == "B"
    assert all(i.level == "B" for i in weld.imperfections)


@pytest.mark.parametrize(
    ("width", "h", "level"),
    [
        # b = 24 mm: B allows 1 + 2.4 = 3.4 mm, C 1 + 3.6 = 4.6 mm, D 1 + 6 = 7 mm.
        (24.0, 3.4, "B"),
        (24.0, 3.5, "C"),
        (24.0, 4.6, "C"),
        (24.0, 4.7, "D"),
        (24.0, 7.0, "D"),
        (24.0, 7.1, ""),
        # b = 60 mm: 1 + 6 = 7 mm for B, but B's maximum is 5 mm; C: min(1 + 9, 7) = 7 mm.
        (60.0, 5.0, "B"),
        (60.0, 5.1, "C"),
        (60.0, 7.1, "D"),
        # b = 100 mm: D's 1 + 25 mm is capped at 10 mm.
        (100.0, 10.0, "D"),
        (100.0, 10.1, ""),
    ],
)
def test_excess_weld_metal_by_hand(width: float, h: float, level: str) -> None:
    excess = np.full(len(S), 1.0)
    excess[150] = h  # one station: the limit is per station, not an average
    weld = _weld(width_mm=width, excess_mm=excess)
    assert weld["excess_weld_metal"].level == level
    assert weld["excess_weld_metal"].worst_s_mm == 150.0
    assert weld.level == level


def test_an_incompletely_filled_groove_is_never_level_b() -> None:
    under = np.zeros(len(S))
    under[100:105] = 0.05  # 5 mm of weld 0.05 mm below the plates' line
    weld = _weld(underfill_mm=under)
    # t = 20 mm: C allows short ones to 0.1 t = 2 mm, capped at 1 mm; D to 0.2 t, capped at 2.
    assert weld["incompletely_filled_groove"].level == "C"
    assert weld["incompletely_filled_groove"].over == {"B": 5, "C": 0, "D": 0}
    under[100:105] = 1.5  # deeper than C's 1 mm, within D's 2 mm
    assert _weld(underfill_mm=under).level == "D"
    under[100:105] = 2.5  # deeper than D's 2 mm
    assert _weld(underfill_mm=under).level == ""


def test_an_underfill_longer_than_short_fails_every_level() -> None:
    under = np.zeros(len(S))
    under[100:125] = 0.3  # 25 stations of 1 mm: 25 mm in 100 mm, still short
    assert _weld(underfill_mm=under).level == "C"
    under[100:127] = 0.3  # 27 mm: no longer short
    assert _weld(underfill_mm=under).level == ""
    under[:] = 0.0
    under[0:20], under[200:220] = 0.3, 0.3  # 40 mm in all, but never 25 mm in one 100 mm
    assert _weld(underfill_mm=under).level == "C"


def test_undercut_by_hand() -> None:
    # t = 20 mm: B 0.05 t = 1 mm capped at 0.5; C 0.1 t capped at 0.5; D 0.2 t capped at 1.
    assert _weld(undercut_mm=0.5).level == "B"
    assert _weld(undercut_mm=0.6).level == "D"
    assert _weld(undercut_mm=1.1).level == ""
    thin = inspect_weld(S, thickness_mm=6.0, width_mm=12.0, excess_mm=1.0, underfill_mm=0.0,
                        undercut_mm=0.35)  # fmt: skip
    # t = 6 mm: B 0.3 mm, C 0.5 mm (0.6 capped), D 1 mm (1.2 capped).
    assert thin["undercut"].level == "C"


def test_lack_of_sidewall_fusion_is_level_d_at_best_and_only_when_short() -> None:
    gap = np.zeros(len(S), dtype=bool)
    gap[10:30] = True  # 20 mm unfused
    weld = _weld(unfused=gap)
    assert weld["lack_of_fusion"].level == "D"
    assert weld.level == "D"
    gap[10:40] = True  # 30 mm: not short
    assert _weld(unfused=gap).level == ""


def test_the_short_rule_on_a_weld_under_100_mm() -> None:
    s = np.arange(0.0, 40.5, 0.5)  # 40 mm: 25 % is 10 mm
    flagged = np.zeros(len(s), dtype=bool)
    flagged[4:24] = True  # 20 stations of 0.5 mm = 10 mm
    assert only_short(flagged, s)
    flagged[4:26] = True  # 11 mm
    assert not only_short(flagged, s)


def test_station_lengths_add_up_to_the_weld() -> None:
    s = np.array([0.0, 1.0, 3.0, 6.0])
    assert station_lengths_mm(s) == pytest.approx([0.5, 1.5, 2.5, 1.5])
    assert station_lengths_mm(s).sum() == pytest.approx(6.0)


def test_the_record_names_the_worst_station_and_the_level() -> None:
    excess = np.full(len(S), 1.0)
    excess[42] = 4.0
    out = _weld(excess_mm=excess).as_dict()
    assert out["level"] == "C"
    assert out["excess_weld_metal"] == {
        "level": "C",
        "worst_s_mm": 42.0,
        "worst_mm": 4.0,
        "stations_over": {"B": 1, "C": 0, "D": 0},
    }


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"thickness_mm": 3.0}, "thickness_mm"),
        ({"width_mm": np.nan}, "width_mm"),
        ({"excess_mm": np.inf}, "excess_mm"),
    ],
)
def test_bad_input_names_the_field(kw: dict, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        _weld(**kw)


def test_stations_must_increase() -> None:
    with pytest.raises(ValueError, match="s_mm"):
        inspect_weld([0.0, 2.0, 1.0], thickness_mm=T, width_mm=20.0, excess_mm=1.0,
                     underfill_mm=0.0)  # fmt: skip
