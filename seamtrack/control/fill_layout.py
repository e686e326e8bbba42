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
from seamtrack.geometry.groove_points import (
    FEET,
    LEFT_FOOT,
    LEFT_TOP,
    MIDDLE,
    RIGHT_FOOT,
    RIGHT_TOP,
    TOPS,
)

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
#: A forced pass count's cap (:func:`counted_layout`): the band under the plates' line that the
#: cap fills is at most this fraction of a cap bead's height deep. Deeper, the valleys between
#: the cap's beads stay under the line: 3 cap beads of 34 mm^2 over a band 3 mm deep (0.71 of
#: their height) left multipass-v-groove's 10 passes 0.21 mm under it with perfect tracking;
#: 4 of 19 mm^2 (0.60) 0.09 mm over it; 5 of 12 mm^2 (0.49) 0.24 mm over it.
CAP_BAND_DEPTH_MAX = 0.5
#: A forced pass count's fill layer (:func:`counted_layout`): its beads, each of its bead's
#: width on a flat plate, span at least its width at its top over this. multipass-v-groove's
#: 10 passes as measured by its scan pass (the groove 1 mm deeper than the CAD's, to the
#: backing bar) were cut into 5 layers of 1 bead of 44 mm^2 (14 mm wide), the top one 22 mm
#: wide (1.57 of the bead's width): 0.61 mm under the plates' line in closed loop. The single
#: bead layers of the plans that fill span up to 1.3 of their bead's width (12 passes: 1.2;
#: 16: 1.3), which 1.25 cut into fewer layers of more beads, 0.06 mm under the line.
LAYER_SPAN_MAX = 1.35


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
    """The plan of the job for the groove's median section: the process's own
    (:func:`nominal_layout`), or with ``state.count`` one of that many passes
    (:func:`counted_layout`)."""
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
    section = Section(fill_area, depth, top, float(np.median(groove.bottom_width_mm)))
    if state.count is not None:
        return counted_layout(section, p, state.count, state.reinforcement_mm)
    return nominal_layout(section, p, state.reinforcement_mm)


@dataclass(frozen=True)
class Section:
    """A groove's median section: its area below the top-corner line (mm^2), depth, top
    width and the width of its fill surface (mm)."""

    area_mm2: float
    depth_mm: float
    top_mm: float
    bottom_mm: float

    def height_of(self, area_mm2: float) -> float:
        """The height over the fill surface below which the section holds ``area_mm2``, its
        walls straight from the fill surface's width to the top width (the area scaled to the
        measured one)."""
        b, d = max(self.bottom_mm, 0.0), self.depth_mm
        k = 0.5 * (self.top_mm - b) / d
        a = min(max(area_mm2, 0.0), self.area_mm2) * (b + k * d) * d / self.area_mm2
        if k <= 1e-12:
            return a / max(b, 1e-12)
        return (-b + math.sqrt(b * b + 4.0 * k * a)) / (2.0 * k)

    def width_at(self, z: Any) -> Any:
        """The section's width at heights z over the fill surface."""
        b = max(self.bottom_mm, 0.0)
        return b + (self.top_mm - b) * np.asarray(z, dtype=float) / self.depth_mm

    def slice_mm2(self, z0: float, z1: float) -> float:
        """The section's area between heights z0 and z1 over the fill surface."""
        b, d = max(self.bottom_mm, 0.0), self.depth_mm
        k = 0.5 * (self.top_mm - b) / d
        whole = (b + k * d) * d
        return self.area_mm2 * (b * (z1 - z0) + k * (z1 * z1 - z0 * z0)) / whole


def nominal_layout(section: Section, p: Process, reinforcement_mm: float) -> Layout:
    """Equal-area fill layers and a cap, with the process's bead at its nominal speed.

    The fill stops :data:`CAP_BAND_FRACTION` of a bead's height below the plates' top line;
    that band and the crown (:func:`cap_area_mm2`) are the cap's, laid in equal beads side to
    side, as many as cover the top width and :data:`CAP_OVERLAP_MM` beyond each corner with a
    bead every 0.7 bead widths (none smaller than the fastest travel speed lays). The fill is
    split into as many equal-area layers as its depth holds beads of the process's height,
    each with ``round(layer area / bead area)`` (>= 1) beads.
    """
    fill_area, depth, top = section.area_mm2, section.depth_mm, section.top_mm
    total = fill_area + float(cap_area_mm2(top, reinforcement_mm))
    bead = float(p.bead_area_mm2(p.nominal_speed_mm_s))
    cap_beads = max(1, math.ceil((top + 2 * CAP_OVERLAP_MM) / (0.7 * p.bead_width_mm(bead))))
    # The fill stops CAP_BAND_FRACTION of a bead's height below the plates' top line; the cap
    # fills that band and lays the crown.
    band = min(CAP_BAND_FRACTION * p.bead_height_mm(bead) * top, fill_area)
    fill_total = fill_area - band
    cap_bead = (band + total - fill_area) / cap_beads
    for _ in range(5):  # the cap's beads as many as cover the width at their own size
        n = max(1, math.ceil((top + 2 * CAP_OVERLAP_MM) / (0.7 * p.bead_width_mm(cap_bead))))
        # no bead smaller than the fastest travel speed lays
        n = min(n, max(1, int((band + total - fill_area) / p.bead_area_mm2(p.speed_max_mm_s))))
        if n == cap_beads:
            break
        cap_beads, cap_bead = n, (band + total - fill_area) / n
    if fill_total < 0.5 * bead:
        n = max(1, round(total / bead))
        return Layout((n,), 0.0, total / n)
    fill_depth = depth * min(1.0, fill_total / fill_area)
    layers = max(1, round(fill_depth / p.bead_height_mm(bead)))
    counts = [max(1, round(fill_total / layers / bead))] * layers
    return Layout((*counts, cap_beads), fill_total / sum(counts), cap_bead)


def counted_layout(section: Section, p: Process, count: int, reinforcement_mm: float) -> Layout:
    """A plan of ``count`` passes, as a welder lays one out: a cap of as many beads as cover
    the top width (:func:`covering_area_mm2`), fill layers whose bead counts grow with the
    groove's width, every bead within the process's travel speed window.

    For each cap of n beads (1 .. count - 1) the cap's bead is the larger of the one that
    covers the top width and :data:`CAP_OVERLAP_MM` beyond each corner every 0.7 bead widths
    and the one that fills the nominal band (:data:`CAP_BAND_FRACTION` of a bead's height
    under the top line) and the crown; the band grows to what the cap's beads lay beyond the
    crown, and the fill's ``count - n`` beads share the rest. The cap kept is the one of the
    fewest beads whose band is at most :data:`CAP_BAND_DEPTH_MAX` of a cap bead's height deep
    and whose beads, cap and fill, are all within the travel speed window (when none is, the
    one that misses by the smallest factor). The fewest: the fill's beads are then the most
    and the smallest. The fill is cut into layers of equal height, as many as keep each
    within a fill bead's height, each layer's beads in proportion to its area
    (:func:`layer_counts`): the counts grow with the groove's width.

    multipass-v-groove's V (20 mm, 60 deg, 2 mm gap), perfectly tracked: 10 passes
    [1, 1, 1, 2, 5] (fill beads of 44 mm^2, cap beads 12 mm^2), 12 [1, 1, 1, 2, 2, 5], 14
    [1, 1, 1, 2, 2, 2, 5], 20 [1, 1, 1, 2, 3, 3, 4, 5], each at level B. The cap of 3 beads
    that a welder might lay at 10 passes ([1, 1, 2, 3, 3]) is 34 mm^2 a bead over a band 3 mm
    deep: the valleys between its beads stay 0.21 mm under the line in this bead model."""
    fill_area, top = section.area_mm2, section.top_mm
    crown = float(cap_area_mm2(top, reinforcement_mm))
    total = fill_area + crown
    if count < 2:
        return Layout((max(count, 1),), 0.0, total / max(count, 1))
    smallest = float(p.bead_area_mm2(p.speed_max_mm_s))
    largest = float(p.bead_area_mm2(p.speed_min_mm_s))
    band0 = CAP_BAND_FRACTION * p.bead_height_mm(total / count) * top

    def option(n: int) -> tuple[float, float, float]:
        cap = max(covering_area_mm2(p, top, n), (band0 + crown) / n, smallest)
        fill = (total - n * cap) / (count - n)
        if fill <= 0.0:
            return math.inf, cap, fill
        deep = (n * cap - crown) / top / p.bead_height_mm(cap)
        out = max(cap / largest, fill / largest, smallest / fill, deep / CAP_BAND_DEPTH_MAX, 1.0)
        return out, cap, fill

    best = min(range(1, count), key=lambda n: (option(n)[0], n))
    score, cap, fill = option(best)
    if not math.isfinite(score):  # the cap alone holds the groove: one layer
        return Layout((count,), 0.0, total / count)
    fill_total = total - best * cap
    height = section.height_of(fill_total)
    layers = max(1, min(count - best, math.ceil(height / p.bead_height_mm(fill))))
    span = LAYER_SPAN_MAX * p.bead_width_mm(fill)
    while True:  # fewer, wider layers until each layer's beads span its width
        counts = layer_counts(section, height, layers, count - best)
        tops = section.width_at(np.linspace(0.0, height, layers + 1)[1:])
        if layers == 1 or np.all(tops <= span * np.asarray(counts)):
            return Layout((*counts, best), fill, cap)
        layers -= 1


def covering_area_mm2(p: Process, top_mm: float, n: int) -> float:
    """The bead area whose width covers the top width and :data:`CAP_OVERLAP_MM` beyond each
    corner in n beads laid every 0.7 bead widths."""
    width = (top_mm + 2 * CAP_OVERLAP_MM) / (0.7 * n)
    h = width / p.width_to_height
    return SHAPE_FILL.get(p.bead_model, 2.0 / 3.0) * p.width_to_height * h * h


def layer_counts(section: Section, height_mm: float, layers: int, beads: int) -> list[int]:
    """``beads`` fill beads in ``layers`` layers of equal height up to ``height_mm``, each
    layer's share in proportion to its area (the largest remainders, the upper layers first on
    a tie, at least one a layer), never fewer than the layer below."""
    z = np.linspace(0.0, height_mm, layers + 1)
    areas = np.array([section.slice_mm2(z[i], z[i + 1]) for i in range(layers)])
    share = beads * areas / max(float(areas.sum()), 1e-12)
    counts = np.maximum(np.floor(share), 1.0).astype(int)
    order = sorted(range(layers), key=lambda i: (counts[i] - share[i], -i))
    for i in order[: max(beads - int(counts.sum()), 0)]:  # the largest remainders
        counts[i] += 1
    while counts.sum() > beads:  # the ones the floor of 1 added, from the widest layers
        counts[int(np.argmax(counts))] -= 1
    return sorted(int(n) for n in counts)


def after_bead(groove: MeasuredGroove, area_mm2: Any) -> MeasuredGroove:
    """The groove a pass's sensor measured *before* its torch laid its bead, with that bead
    added: the fill surface (the 5 bottom points) lifted by the height ``dz`` at which the
    groove between the walls holds the bead's area (``area_mm2``, (m,) at its stations; None:
    ``groove`` itself), ``w dz + k dz^2 / 2 = area`` with w the fill surface's width and k the
    walls' widening per mm of height (their slopes from the 7 points), the feet moved up their
    walls, the top corners (which no bead moves) kept.

    What the pass after expects where its sensor has not yet measured the groove (its start,
    :func:`~seamtrack.multipass.aim.planned_feature`): the groove before the last bead
    lies a bead lower (a single-bead layer of the 12-pass plan: 4 mm), and a torch started
    there dived under the fill and overshot it by 2-4 mm over the next 15 mm. And the groove
    a planner lays a layer's first bead on when the layer below is a single bead
    (:class:`~seamtrack.control.planner.AdaptivePlanner`): measured before that bead, its fill
    surface is the layer below's, a bead lower and narrower."""
    if area_mm2 is None or not len(groove):
        return groove
    p = groove.points.copy()
    area = np.maximum(np.asarray(area_mm2, dtype=float).reshape(len(groove)), 0.0)
    rise = np.maximum(p[:, TOPS, 1] - p[:, FEET, 1], 1e-9)  # (m, 2) the walls' heights
    widen = np.abs(p[:, FEET, 0] - p[:, TOPS, 0]) / rise  # mm of width per mm of height
    w = np.maximum(p[:, RIGHT_FOOT, 0] - p[:, LEFT_FOOT, 0], 0.0)
    k = widen.sum(axis=1)
    dz = np.where(k > 1e-9, (np.sqrt(w * w + 2 * k * area) - w) / np.maximum(k, 1e-9),
                  area / np.maximum(w, 1e-9))  # fmt: skip
    dz = np.minimum(dz, rise.min(axis=1))
    left = p[:, LEFT_FOOT, 0] - widen[:, 0] * dz
    right = p[:, RIGHT_FOOT, 0] + widen[:, 1] * dz
    old_left, old_w = p[:, LEFT_FOOT, 0].copy(), np.maximum(w, 1e-9)
    # the bottom points stretched between the new feet, lifted
    for row in range(LEFT_FOOT, RIGHT_FOOT + 1):
        frac = (p[:, row, 0] - old_left) / old_w
        p[:, row, 0] = left + frac * (right - left)
        p[:, row, 1] += dz
    remaining = np.maximum(groove.area_mm2 - area, 0.0)
    return MeasuredGroove(groove.s_mm, p, remaining)


def under_line_mm2(points: FloatArray, lo_mm: Any, hi_mm: Any, samples: int = 24) -> FloatArray:
    """(m,) the area (mm^2) between the plates' top line (the line joining the top corners)
    and the groove's surface below it, from y = ``lo_mm`` to ``hi_mm`` ((m,) each), at each of
    the m stations of ``points`` (m, 7, 2): the surface the piecewise-linear profile through
    the 7 points (y ascending), held level beyond the top corners; where it stands over the
    line, nothing. The midpoint rule on ``samples`` points."""
    pts = np.asarray(points, dtype=float)
    lo, hi = np.asarray(lo_mm, dtype=float), np.asarray(hi_mm, dtype=float)
    t = (np.arange(samples) + 0.5) / samples
    y = lo[:, None] + (hi - lo)[:, None] * t[None, :]  # (m, q)
    py, pz = pts[:, :, 0], pts[:, :, 1]
    y = np.clip(y, py[:, :1], py[:, -1:])
    z = np.repeat(pz[:, :1], samples, axis=1)
    for j in range(pts.shape[1] - 1):  # each segment, where the samples lie beyond its start
        y0, y1 = py[:, j : j + 1], py[:, j + 1 : j + 2]
        frac = np.clip((y - y0) / np.maximum(y1 - y0, 1e-12), 0.0, 1.0)
        z = np.where(
            y >= y0, pz[:, j : j + 1] + frac * (pz[:, j + 1 : j + 2] - pz[:, j : j + 1]), z
        )
    line_t = (y - py[:, LEFT_TOP, None]) / np.maximum(
        py[:, RIGHT_TOP, None] - py[:, LEFT_TOP, None], 1e-12
    )
    line = pz[:, LEFT_TOP, None] + line_t * (pz[:, RIGHT_TOP, None] - pz[:, LEFT_TOP, None])
    return np.maximum(line - z, 0.0).mean(axis=1) * np.maximum(hi - lo, 0.0)
