"""A weld's cross-sections judged by ISO 5817: the quality level (B, C or D) that every station
along the seam meets, and the worst station of each imperfection.

The limits are ISO 5817:2014's, Table 1, for butt welds in plate thicker than 3 mm (mm; ``t``
the plate thickness, ``b`` the weld's width):

====  ==========================  ===================  ===================  ===================
No.   imperfection (ISO 6520-1)   D                    C                    B
====  ==========================  ===================  ===================  ===================
1.9   502 excess weld metal h     1 + 0.25 b, max 10   1 + 0.15 b, max 7    1 + 0.1 b, max 5
1.14  511 incompletely filled     short: 0.2 t, max 2  short: 0.1 t, max 1  not permitted
1.7   5011/5012 undercut h        0.2 t, max 1         0.1 t, max 0.5       0.05 t, max 0.5
1.5   401 lack of fusion          short only           not permitted        not permitted
====  ==========================  ===================  ===================  ===================

"Short imperfections" (ISO 5817:2014, clause 3): in any 100 mm of weld, the imperfections add up
to at most 25 mm; in a weld shorter than 100 mm, to at most 25 % of its length. A station stands
for the length of seam halfway to its neighbours.

The rows for sheet of 0.5-3 mm differ and are not implemented: :func:`inspect_weld` refuses
``t <= 3 mm``. Everything here is arrays in, a frozen record out; the job summary and the
plots read the record.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: The quality levels, strictest first.
LEVELS = ("B", "C", "D")

#: Excess weld metal on a butt weld (No. 1.9, 502): h <= 1 mm + k b, but at most h_max.
EXCESS_WELD_METAL = {"B": (0.10, 5.0), "C": (0.15, 7.0), "D": (0.25, 10.0)}
#: Incompletely filled groove (No. 1.14, 511), t > 3 mm: short imperfections of depth <= f t,
#: but at most h_max; None: not permitted.
INCOMPLETELY_FILLED = {"B": None, "C": (0.1, 1.0), "D": (0.2, 2.0)}
#: Undercut, continuous or intermittent (No. 1.7, 5011/5012), t > 3 mm: h <= f t, at most h_max.
UNDERCUT = {"B": (0.05, 0.5), "C": (0.1, 0.5), "D": (0.2, 1.0)}
#: Lack of fusion (No. 1.5, 401): permitted as short imperfections at D only.
LACK_OF_FUSION_SHORT_OK = {"B": False, "C": False, "D": True}

#: The short-imperfection rule: at most this much flagged length ...
SHORT_LENGTH_MM = 25.0
#: ... in any window of this length (a shorter weld: at most SHORT_FRACTION of it).
SHORT_WINDOW_MM = 100.0
SHORT_FRACTION = 0.25

#: Only thicker plate is covered (the thin-sheet rows of Table 1 differ).
MIN_THICKNESS_MM = 3.0


@dataclass(frozen=True)
class Imperfection:
    """One imperfection along the weld: its worst station and the level it meets."""

    name: str
    #: The measured value at each station (mm; 0 where there is none).
    value_mm: FloatArray
    #: Each level's limit at each station (level -> (m,)); inf: no bound, nan: not permitted.
    limit_mm: dict[str, FloatArray]
    #: The strictest level the whole weld meets for this imperfection ("" for none).
    level: str
    #: Where the worst station stands (mm along the seam) and its value.
    worst_s_mm: float
    worst_mm: float
    #: Stations over each level's limit.
    over: dict[str, int]

    def as_dict(self) -> dict[str, Any]:
        return {
            "level": self.level or "none",
            "worst_s_mm": round(self.worst_s_mm, 3),
            "worst_mm": round(self.worst_mm, 4),
            "stations_over": dict(self.over),
        }


@dataclass(frozen=True)
class Inspection:
    """The weld judged station by station; ``level`` is what every station meets."""

    s_mm: FloatArray
    thickness_mm: float
    imperfections: tuple[Imperfection, ...]

    @property
    def level(self) -> str:
        """The strictest level that every imperfection meets ("" when D is not met)."""
        met = [LEVELS.index(i.level) if i.level else len(LEVELS) for i in self.imperfections]
        worst = max(met, default=0)
        return LEVELS[worst] if worst < len(LEVELS) else ""

    def __getitem__(self, name: str) -> Imperfection:
        for imperfection in self.imperfections:
            if imperfection.name == name:
                return imperfection
        raise KeyError(name)

    def as_dict(self) -> dict[str, Any]:
        return {
            "standard": "ISO 5817:2014 Table 1 (butt welds, t > 3 mm)",
            "level": self.level or "none",
            "thickness_mm": self.thickness_mm,
            **{i.name: i.as_dict() for i in self.imperfections},
        }


def station_lengths_mm(s_mm: FloatArray) -> FloatArray:
    """The length of seam each station stands for: halfway to each neighbour."""
    s = np.asarray(s_mm, dtype=float)
    if len(s) < 2:
        return np.zeros(len(s))
    edges = np.concatenate([[s[0]], 0.5 * (s[1:] + s[:-1]), [s[-1]]])
    return np.diff(edges)


def only_short(flagged: NDArray[np.bool_], s_mm: FloatArray) -> bool:
    """Whether the flagged stations are "short imperfections": at most 25 mm of them in any
    100 mm of weld, or at most 25 % of a weld shorter than 100 mm."""
    s = np.asarray(s_mm, dtype=float)
    if not flagged.any():
        return True
    lengths = np.where(flagged, station_lengths_mm(s), 0.0)
    total = float(s[-1] - s[0])
    if total < SHORT_WINDOW_MM:
        return float(lengths.sum()) <= SHORT_FRACTION * total + 1e-9
    # The flagged length in the window [s_i, s_i + 100 mm) for every start station i.
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    ends = np.searchsorted(s, s + SHORT_WINDOW_MM, side="left")
    in_window = cumulative[ends] - cumulative[: len(s)]
    return float(in_window.max()) <= SHORT_LENGTH_MM + 1e-9


def _judged(
    name: str,
    s: FloatArray,
    value: FloatArray,
    limits: dict[str, FloatArray],
    short_only: dict[str, bool],
) -> Imperfection:
    """The level met for one imperfection, given each level's per-station limit (nan: not
    permitted at all, so any value > 0 fails) and whether the level admits short ones only."""
    over: dict[str, int] = {}
    level = ""
    present = value > 0.0
    for name_level in LEVELS:
        limit = limits[name_level]
        beyond = np.where(np.isnan(limit), present, value > limit + 1e-9)
        over[name_level] = int(np.count_nonzero(beyond))
        ok = not beyond.any() and (not short_only[name_level] or only_short(present, s))
        if ok and not level:  # the strictest level met (the limits only widen from B to D)
            level = name_level
    worst = int(np.argmax(value)) if len(value) else 0
    return Imperfection(
        name=name,
        value_mm=value,
        limit_mm=limits,
        level=level,
        worst_s_mm=float(s[worst]) if len(s) else float("nan"),
        worst_mm=float(value[worst]) if len(value) else 0.0,
        over=over,
    )


def _array(name: str, values: ArrayLike, m: int) -> FloatArray:
    out = np.broadcast_to(np.asarray(values, dtype=float), (m,)).copy()
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name}: every station needs a finite value")
    return out


def inspect_weld(
    s_mm: ArrayLike,
    *,
    thickness_mm: float,
    width_mm: ArrayLike,
    excess_mm: ArrayLike,
    underfill_mm: ArrayLike,
    undercut_mm: ArrayLike = 0.0,
    unfused: ArrayLike = False,
) -> Inspection:
    """Judge a butt weld's stations by ISO 5817 (levels B, C, D).

    Parameters
    ----------
    s_mm : (m,) array
        The stations' arc lengths along the seam, increasing (mm).
    thickness_mm : float
        The plate thickness t (> 3 mm).
    width_mm : (m,) array or float
        The weld's width b at each station: its face from toe to toe (mm).
    excess_mm : (m,) array or float
        The excess weld metal h: the face's height above the plates' top line (mm; <= 0 none).
    underfill_mm : (m,) array or float
        The depth of an incompletely filled groove: how far the face lies below the plates' top
        line (mm; <= 0 none).
    undercut_mm : (m,) array or float
        The undercut's depth at the worse toe (mm; <= 0 none).
    unfused : (m,) bool array or bool
        Where a bead's toe stayed off a groove wall (lack of sidewall fusion).
    """
    if not thickness_mm > MIN_THICKNESS_MM:
        raise ValueError(
            f"thickness_mm: {thickness_mm} mm; ISO 5817's rows for plate of 0.5-3 mm are not "
            f"implemented (give t > {MIN_THICKNESS_MM:g} mm)"
        )
    s = np.asarray(s_mm, dtype=float)
    if s.ndim != 1 or len(s) == 0 or np.any(np.diff(s) <= 0) or not np.all(np.isfinite(s)):
        raise ValueError("s_mm: give the stations' arc lengths, finite and increasing")
    m = len(s)
    t = float(thickness_mm)
    b = _array("width_mm", width_mm, m)
    h = np.maximum(_array("excess_mm", excess_mm, m), 0.0)
    under = np.maximum(_array("underfill_mm", underfill_mm, m), 0.0)
    cut = np.maximum(_array("undercut_mm", undercut_mm, m), 0.0)
    gap = np.broadcast_to(np.asarray(unfused, dtype=bool), (m,)).astype(float)

    full = np.ones(m)
    excess = _judged(
        "excess_weld_metal",
        s,
        h,
        {lv: np.minimum(1.0 + k * b, h_max) for lv, (k, h_max) in EXCESS_WELD_METAL.items()},
        dict.fromkeys(LEVELS, False),
    )
    filled = _judged(
        "incompletely_filled_groove",
        s,
        under,
        {
            lv: full * np.nan if rule is None else full * min(rule[0] * t, rule[1])
            for lv, rule in INCOMPLETELY_FILLED.items()
        },
        {lv: rule is not None for lv, rule in INCOMPLETELY_FILLED.items()},
    )
    undercut = _judged(
        "undercut",
        s,
        cut,
        {lv: full * min(f * t, h_max) for lv, (f, h_max) in UNDERCUT.items()},
        dict.fromkeys(LEVELS, False),
    )
    fusion = _judged(
        "lack_of_fusion",
        s,
        gap,
        {lv: full * (np.inf if short else np.nan) for lv, short in LACK_OF_FUSION_SHORT_OK.items()},
        dict(LACK_OF_FUSION_SHORT_OK),
    )
    return Inspection(s_mm=s, thickness_mm=t, imperfections=(excess, filled, undercut, fusion))
