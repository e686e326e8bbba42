"""The layout arithmetic of a multi-pass fill: the measured groove, the process's bead, and how
many beads go in each layer (:func:`layout`), for the planners in :mod:`seamtrack.control.planner`.

Frames and units: a groove is measured in station frames (x along the seam, z out of the
groove, y lateral), its 7 points ordered left top corner, left bottom corner, three bottom
points, right bottom corner, right top corner, y ascending. mm, s, rad; wire feed in mm/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import PluginRuntimeError
from seamtrack.geometry.groove_points import LEFT_FOOT, LEFT_TOP, MIDDLE, RIGHT_FOOT, RIGHT_TOP

FloatArray = NDArray[np.float64]

#: Cross-section area of a bead over width * height on a flat plate, per shape model
#: (parabola 2/3, cosine 2/pi (Ding et al. 2015), circular arc ~ a parabola for w/h >= 2).
SHAPE_FILL = {"parabola": 2.0 / 3.0, "cosine": 2.0 / math.pi, "arc": 2.0 / 3.0}

#: The cap's outer beads reach this far (mm) beyond the groove's top corners (a cap overlaps
#: the plates' edges, so no notch is left at the corner).
CAP_OVERLAP_MM = 1.0
#: The fill stops this fraction of a bead's height below the plates' top line: the cap fills
#: that band between its beads' overlaps and lays the crown.
CAP_BAND_FRACTION = 0.3
#: The first cap bead's area over each other's (a cap of 3 beads or more): laid first, against
#: the left top corner with no bead beside it, it fills the groove's edge under it alone and
#: stood lower than the rest, the valley between it and the second bead 0.06-0.36 mm under the
#: plates' line (multipass-v-groove forced into 10 and 20 passes, multipass-varying-gap, with
#: perfect tracking); at 1.2 those fill to 0.10-0.26 mm over it, -0.09 mm at 10 passes.
CAP_FIRST_WEIGHT = 1.2


@dataclass(frozen=True)
class MeasuredGroove:
    """The groove as the sensor measured it, station by station.

    Attributes
    ----------
    s_mm : (m,) float
        Arc length of each station along the seam, ascending.
    points : (m, 7, 2) float
        The 7 groove points (y, z) in each station's frame.
    area_mm2 : (m,) float
        The groove's remaining area below its top-corner line.
    """

    s_mm: FloatArray
    points: FloatArray
    area_mm2: FloatArray

    def __post_init__(self) -> None:
        s = np.asarray(self.s_mm, dtype=float).reshape(-1)
        points = np.asarray(self.points, dtype=float).reshape(len(s), 7, 2)
        area = np.asarray(self.area_mm2, dtype=float).reshape(len(s))
        object.__setattr__(self, "s_mm", s)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "area_mm2", area)

    def __len__(self) -> int:
        return len(self.s_mm)

    @property
    def top_width_mm(self) -> FloatArray:
        """(m,) distance between the top corners across the seam."""
        return self.points[:, RIGHT_TOP, 0] - self.points[:, LEFT_TOP, 0]

    @property
    def bottom_width_mm(self) -> FloatArray:
        """(m,) width of the fill surface (or root) between the walls' feet."""
        return self.points[:, RIGHT_FOOT, 0] - self.points[:, LEFT_FOOT, 0]

    @property
    def depth_mm(self) -> FloatArray:
        """(m,) the top-corner line's height over the middle bottom point."""
        top = 0.5 * (self.points[:, LEFT_TOP, 1] + self.points[:, RIGHT_TOP, 1])
        return top - self.points[:, MIDDLE, 1]

    def at(self, s_mm: Any, values: FloatArray) -> FloatArray:
        """``values`` (m,) interpolated at arc lengths ``s_mm`` (held beyond the ends)."""
        return np.interp(np.asarray(s_mm, dtype=float), self.s_mm, values)


@dataclass(frozen=True)
class Process:
    """What a planner knows of the welding process (from the scene's ``[process]``)."""

    wire_diameter_mm: float = 1.2
    wire_feed_mm_s: float = 8000.0 / 60.0
    deposition_efficiency: float = 0.97
    speed_min_mm_s: float = 2.0
    speed_max_mm_s: float = 15.0
    nominal_speed_mm_s: float = 5.0
    bead_model: str = "parabola"
    width_to_height: float = 3.0

    def bead_area_mm2(self, speed_mm_s: Any, wire_feed_mm_s: float | None = None) -> Any:
        """Mass conservation: ``efficiency * pi * (d/2)^2 * v_wire / v_travel`` (mm^2)."""
        wire = self.wire_feed_mm_s if wire_feed_mm_s is None else wire_feed_mm_s
        r = 0.5 * self.wire_diameter_mm
        return self.deposition_efficiency * math.pi * r * r * wire / np.asarray(speed_mm_s)

    def speed_for_area(self, area_mm2: Any, wire_feed_mm_s: float | None = None) -> Any:
        """The travel speed that lays a bead of ``area_mm2``, within the speed window."""
        wire = self.wire_feed_mm_s if wire_feed_mm_s is None else wire_feed_mm_s
        r = 0.5 * self.wire_diameter_mm
        area = np.maximum(np.asarray(area_mm2, dtype=float), 1e-9)
        speed = self.deposition_efficiency * math.pi * r * r * wire / area
        return np.clip(speed, self.speed_min_mm_s, self.speed_max_mm_s)

    def bead_height_mm(self, area_mm2: float) -> float:
        """A bead's height on a flat plate: area = fill * (w/h) * h^2."""
        fill = SHAPE_FILL.get(self.bead_model, 2.0 / 3.0)
        return math.sqrt(area_mm2 / (fill * self.width_to_height))

    def bead_width_mm(self, area_mm2: float) -> float:
        return self.width_to_height * self.bead_height_mm(area_mm2)


class LayoutState(Protocol):
    """What :func:`layout` reads of the job's state (a planner's ``JobState``)."""

    process: Process
    count: int | None
    reinforcement_mm: float


@dataclass(frozen=True)
class Layout:
    """The plan of the whole job: beads per layer (the last layer the cap)."""

    beads_per_layer: tuple[int, ...]
    fill_bead_area_mm2: float
    cap_bead_area_mm2: float

    @property
    def passes(self) -> int:
        return sum(self.beads_per_layer)

    def locate(self, pass_index: int) -> tuple[int, int] | None:
        """(layer, bead_in_layer) of the 0-based pass, or None past the end."""
        for layer, n in enumerate(self.beads_per_layer):
            if pass_index < n:
                return layer, pass_index
            pass_index -= n
        return None

    def beads_after(self, pass_index: int, cap: bool) -> int:
        """Beads left in the fill (cap False) or the cap (True), this one included."""
        fill = sum(self.beads_per_layer[:-1])
        if cap:
            return self.passes - max(pass_index, fill)
        return max(fill - pass_index, 0)


def fill_order(n: int) -> list[int]:
    """Corners first: the order in which the n lateral slots of a fill layer (0 = left wall)
    are laid: left wall, right wall, then the middle slots from left to right."""
    if n <= 2:
        return list(range(n))
    return [0, n - 1, *range(1, n - 1)]


def cap_share(area_mm2: Any, n: int, rank: int) -> Any:
    """The ``rank``-th of a cap's ``n`` beads' area, from the mean bead area ``area_mm2``: the
    first bead :data:`CAP_FIRST_WEIGHT` times each other's (a cap of 3 or more), the total
    kept."""
    if n < 3:
        return area_mm2
    weight = CAP_FIRST_WEIGHT if rank == 0 else 1.0
    return np.asarray(area_mm2) * n * weight / (CAP_FIRST_WEIGHT + n - 1)


def cap_area_mm2(top_width_mm: Any, reinforcement_mm: float) -> Any:
    """The crown of a cap ``reinforcement_mm`` high over the top width (a parabola: 2/3 w h)."""
    return (2.0 / 3.0) * np.asarray(top_width_mm) * reinforcement_mm


def layout(groove: MeasuredGroove, state: LayoutState) -> Layout:
    """Equal-area fill layers and a cap, for the groove's median section.

    The fill stops :data:`CAP_BAND_FRACTION` of a bead's height below the plates' top line;
    that band and the crown (:func:`cap_area_mm2`) are the cap's, laid in equal beads side to
    side, as many as cover the top width and :data:`CAP_OVERLAP_MM` beyond each corner with a
    bead every 0.7 bead widths (none smaller than the fastest travel speed lays). The fill is
    split into as many equal-area layers as its depth holds beads of the process's height,
    each with ``round(layer area / bead area)`` (>= 1) beads. The bead area is the process's
    at its nominal speed, or, with ``state.count``, the one that makes the plan hold that many
    passes (the largest remainder decides which layers take the rounding).
    """
    p = state.process
    fill_area = float(np.median(groove.area_mm2))
    depth = float(np.median(groove.depth_mm))
    top = float(np.median(groove.top_width_mm))
    if not (fill_area > 0 and depth > 0 and top > 0):
        raise PluginRuntimeError(
            f"the measured groove has no room to fill (area {fill_area:.3g} mm^2, depth "
            f"{depth:.3g} mm, top width {top:.3g} mm)",
            field="passes",
            fix="check the workpiece is a groove and the extractor finds its 7 points",
        )
    total = fill_area + float(cap_area_mm2(top, state.reinforcement_mm))
    bead = float(p.bead_area_mm2(p.nominal_speed_mm_s))
    if state.count is not None:
        bead = total / state.count
    cap_beads = max(1, math.ceil((top + 2 * CAP_OVERLAP_MM) / (0.7 * p.bead_width_mm(bead))))
    if state.count is not None:
        cap_beads = min(cap_beads, state.count)
    # The fill stops CAP_BAND_FRACTION of a bead's height below the plates' top line; the cap
    # fills that band and lays the crown.
    band = min(CAP_BAND_FRACTION * p.bead_height_mm(bead) * top, fill_area)
    fill_total = fill_area - band
    cap_bead = (band + total - fill_area) / cap_beads
    for _ in range(5):  # the cap's beads as many as cover the width at their own size
        n = max(1, math.ceil((top + 2 * CAP_OVERLAP_MM) / (0.7 * p.bead_width_mm(cap_bead))))
        # no bead smaller than the fastest travel speed lays
        n = min(n, max(1, int((band + total - fill_area) / p.bead_area_mm2(p.speed_max_mm_s))))
        if state.count is not None:  # and at least one fill bead left of a forced count
            n = min(n, max(1, state.count - 1))
        if n == cap_beads:
            break
        cap_beads, cap_bead = n, (band + total - fill_area) / n
    if fill_total < 0.5 * bead or (state.count is not None and cap_beads == state.count):
        n = state.count if state.count is not None else max(1, round(total / bead))
        return Layout((n,), 0.0, total / n)
    fill_depth = depth * min(1.0, fill_total / fill_area)
    layers = max(1, round(fill_depth / p.bead_height_mm(bead)))
    if state.count is not None:
        fill_beads = state.count - cap_beads
        layers = min(layers, fill_beads)
        share = np.full(layers, fill_beads / layers)
        per_layer = np.floor(share).astype(int)
        order = np.argsort(-(share - per_layer), kind="stable")[::-1]  # the upper layers first
        per_layer[order[: fill_beads - int(per_layer.sum())]] += 1
        counts = [int(n) for n in per_layer]
    else:
        counts = [max(1, round(fill_total / layers / bead))] * layers
    return Layout((*counts, cap_beads), fill_total / sum(counts), cap_bead)
