"""Fill planners of a multi-pass job: which bead goes where, how fast, with how much wire.

A planner is any class with ``plan(groove, pass_index, state) -> PassPlan | None`` (None: the
job is done) and, optionally, ``adapt(groove_ahead, plan) -> (speed_mm_s, offset_mm) | None``
called during a pass at every sensor frame with the groove the sensor measures ahead of the
torch. It is named in the scene like a tracker: a built-in name (``adaptive``, ``fixed``) or
``package.module:Class`` (:func:`planner`).

Frames and units: a groove is measured in station frames (x along the seam, z out of the
groove, y lateral), its 7 points ordered left top corner, left bottom corner, three bottom
points, right bottom corner, right top corner, y ascending. mm, s, rad; wire feed in mm/s.

The built-in :class:`AdaptivePlanner` fills equal-area layers (as many as the groove's depth
holds beads of the process's height), puts ``round(layer area / bead area)`` (at least one)
beads in each, corners first (a bead against each wall, then the middle from left to right),
then a cap layer side to side (each bead offset from a top corner, the bevel's edge, which the
bead before it has not moved; the beads after the first sized by what lies under them), and
scales the travel speed along the seam to the measured groove: the bead area at a station is
the area left to fill there over the beads left, and the speed follows from mass conservation,
bounded by the process window. :class:`FixedPlanner` lays
the same beads at one constant speed (the one for the groove's median area).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.fill_layout import (
    CAP_OVERLAP_MM,
    Layout,
    MeasuredGroove,
    Process,
    after_bead,
    cap_area_mm2,
    cap_share,
    fill_order,
    layout,
    under_line_mm2,
)
from seamtrack.control.registry import load_class
from seamtrack.errors import PluginError, PluginRuntimeError
from seamtrack.geometry.groove_points import LEFT_FOOT, LEFT_TOP, POINT_INDEX, RIGHT_TOP
from seamtrack.geometry.smoothing import station_median

FloatArray = NDArray[np.float64]

REFERENCES = ("left", "right", "centre", "left_top", "right_top")


@dataclass(frozen=True)
class PassPlan:
    """One pass as a planner wants it.

    Attributes
    ----------
    reference : "left", "right", "centre", "left_top" or "right_top"
        The groove point the tracker follows: the left or right wall's foot at the fill
        surface, or the fill surface's middle (the groove extractor's ``reference``), or the
        left or right top corner (the bevel's top edge, where the plate's line meets the wall's:
        no fill bead moves it, so a bead placed from it lands where the plan put it whatever
        the bead before did to the fill surface).
    offset_mm : float
        Lateral offset of the torch from the reference, in the station frame (+y).
    work_angle_rad : float
        Torch work angle (an arm only; a gantry refuses a non-zero one).
    travel_speed_mm_s : float
        The pass's nominal travel speed (the whole pass when no profile is given).
    wire_feed_mm_s : float
        Wire feed speed.
    layer, bead_in_layer : int
        0-based; the cap is the last layer.
    beads_in_layer : int
        How many beads the layer holds.
    cap : bool
        Whether this is a cap bead.
    speed_s_mm, speed_profile_mm_s : (k,) float or None
        The travel speed along the seam (arc length, speed); None: constant.
    offset_profile_mm : (k,) float or None
        The lateral offset along the seam (on ``speed_s_mm``); None: ``offset_mm``.
    """

    reference: str
    offset_mm: float
    work_angle_rad: float
    travel_speed_mm_s: float
    wire_feed_mm_s: float
    layer: int
    bead_in_layer: int
    beads_in_layer: int = 1
    cap: bool = False
    speed_s_mm: FloatArray | None = None
    speed_profile_mm_s: FloatArray | None = None
    offset_profile_mm: FloatArray | None = None

    def speed_at(self, s_mm: Any) -> Any:
        """Travel speed at arc length(s) ``s_mm``."""
        if self.speed_s_mm is None or self.speed_profile_mm_s is None:
            return np.full(np.shape(s_mm), self.travel_speed_mm_s)[()]
        return np.interp(s_mm, self.speed_s_mm, self.speed_profile_mm_s)

    def offset_at(self, s_mm: Any) -> Any:
        """Lateral offset at arc length(s) ``s_mm`` (the profile on ``speed_s_mm``, else
        ``offset_mm``)."""
        if self.speed_s_mm is None or self.offset_profile_mm is None:
            return np.full(np.shape(s_mm), self.offset_mm)[()]
        return np.interp(s_mm, self.speed_s_mm, self.offset_profile_mm)


@dataclass
class JobState:
    """What the job tells a planner besides the measured groove.

    Attributes
    ----------
    process : Process
    count : int or None
        The number of passes the scene asks for (None: the planner decides).
    reinforcement_mm : float
        The cap's target height over the plates' top line.
    done : list of PassPlan
        The passes laid so far, in order.
    last_bead_area_mm2 : (m,) float or None
        The area the last pass laid at the measured groove's stations (mass conservation at
        the torch's actual speed); the measured groove was seen *before* that bead.
    """

    process: Process
    count: int | None = None
    reinforcement_mm: float = 2.0
    done: list[PassPlan] = field(default_factory=list)
    last_bead_area_mm2: FloatArray | None = None


@runtime_checkable
class Planner(Protocol):
    def plan(self, groove: MeasuredGroove, pass_index: int, state: JobState) -> PassPlan | None: ...


class AdaptivePlanner:
    """Equal-area layers, corners first, a cap side to side, speed scaled to the groove.

    Parameters
    ----------
    wall_offset_fraction : float
        Where a wall bead's centre lies, as a fraction of the layer's slot width from the wall
        foot (0.5: the slot's middle; smaller pushes the bead into the corner).
    adapt_speed : bool
        Scale the travel speed along the seam to the measured groove (False: constant speed,
        the :class:`FixedPlanner`).
    wall_reference : bool
        Track a wall bead on the extractor's wall foot (``left``/``right``) with a constant
        offset; by default a bead of a layer of several tracks the nearer top corner
        (``left_top``/``right_top``, the bevel's top edge, which no fill bead moves) and a
        layer's only bead the fill surface's middle (``centre``), with an offset profile
        along the seam that puts it at its place from the walls as the last pass measured
        them (a wall's foot, where a toe wets it, jumps along the wall from one station to
        the next; the top corners do not). See :meth:`_place`.
    """

    name = "adaptive"

    def __init__(
        self,
        wall_offset_fraction: float = 0.45,
        adapt_speed: bool = True,
        wall_reference: bool = False,
    ):
        if not 0 < wall_offset_fraction <= 1:
            raise PluginError(
                f"wall_offset_fraction must be in (0, 1], got {wall_offset_fraction}",
                field="planner.params.wall_offset_fraction",
                fix="give a fraction of the slot width, e.g. 0.45",
            )
        self.wall_offset_fraction = wall_offset_fraction
        self.adapt_speed = adapt_speed
        self.wall_reference = wall_reference
        self.layout: Layout | None = None
        self._cap: tuple[FloatArray, FloatArray] | None = None  # (s, bead area) of the cap
        self._cap_corners: tuple[FloatArray, FloatArray] | None = None  # (s, (m, 2) top y)
        self._cap_rest: tuple[FloatArray, FloatArray] | None = None  # (s, (m, n - 1) areas)

    def plan(self, groove: MeasuredGroove, pass_index: int, state: JobState) -> PassPlan | None:
        if self.layout is None or pass_index == 0:
            self.layout = layout(groove, state)
            self._cap = self._cap_corners = self._cap_rest = None
        where = self.layout.locate(pass_index)
        if where is None:
            return None
        layer, slot_rank = where
        n = self.layout.beads_per_layer[layer]
        cap = layer == len(self.layout.beads_per_layer) - 1
        p = state.process
        reference, offsets = self._place(_laid_on(groove, self.layout, layer, slot_rank, state),
                                         n, slot_rank, cap)  # fmt: skip
        stations = groove.s_mm  # where the plan's profiles are given
        if cap and slot_rank >= 1 and self._cap_corners is not None:
            stations = self._cap_corners[0]  # the first cap bead's (see _place)
        offset = float(np.median(offsets))
        profile_offsets = None if reference in ("left", "right") else offsets
        remaining = np.asarray(groove.area_mm2, dtype=float)
        if state.last_bead_area_mm2 is not None:  # the groove was measured before the last bead
            remaining = remaining - np.asarray(state.last_bead_area_mm2, dtype=float)
        left = self.layout.beads_after(pass_index, cap)
        crown = cap_area_mm2(groove.top_width_mm, state.reinforcement_mm)
        if cap:  # the groove left and the crown (the mean share set at the first cap bead)
            if self._cap is None:
                share = (np.maximum(remaining, 0.0) + crown) / max(left, 1)
                self._cap = (groove.s_mm.copy(), share)
            mean = np.interp(stations, *self._cap)
            if slot_rank >= 1 and n >= 3:  # by what lies under them (_rest_of_cap)
                if self._cap_rest is None:
                    rest = self._rest_of_cap(groove, stations, mean, n, state.reinforcement_mm)
                    self._cap_rest = (stations.copy(), rest)
                s_rest, rest = self._cap_rest
                target = np.interp(stations, s_rest, rest[:, slot_rank - 1])
            else:
                target = cap_share(mean, n, slot_rank)
        else:  # what the cap will not hold, over the fill beads left
            cap_beads = self.layout.beads_per_layer[-1]
            band = cap_beads * self.layout.cap_bead_area_mm2 - crown
            target = np.maximum(remaining - band, 0.0) / max(left, 1)
        target = np.maximum(target, 0.05 * self.layout.fill_bead_area_mm2)
        profile = p.speed_for_area(target)
        if self.adapt_speed:
            nominal = float(np.median(profile))
            return PassPlan(reference, offset, 0.0, nominal, p.wire_feed_mm_s, layer, slot_rank,
                            n, cap, stations.copy(), profile, profile_offsets)  # fmt: skip
        area = self.layout.cap_bead_area_mm2 if cap else self.layout.fill_bead_area_mm2
        speed = float(p.speed_for_area(area))
        return PassPlan(reference, offset, 0.0, speed, p.wire_feed_mm_s, layer, slot_rank, n, cap,
                        stations.copy(), np.full(len(stations), speed),
                        profile_offsets)  # fmt: skip

    def _rest_of_cap(
        self,
        groove: MeasuredGroove,
        stations: FloatArray,
        mean: FloatArray,
        n: int,
        reinforcement_mm: float,
    ) -> FloatArray:
        """(m, n - 1) the areas of the cap's beads after the first (set at the second): together
        what the equal shares give them, each in proportion to what lies under its slot (the
        groove under the plates' line there, :func:`under_line_mm2` on the 7 points, a running
        median along the seam) plus an equal share of the crown.

        The fill's top layer is no flat band: its beads leave valleys between them and against
        the walls (multipass-varying-gap where the gap is widest: two wall beads 14.9 mm apart,
        the valley between them 3.3 mm under the line, the beads' crests 0.2 mm under it and
        1 mm over it), and equal cap beads over them left the valley 0.07 mm under the line
        (213 stations, planned one pass behind as the job does, perfectly tracked). The
        second cap bead's groove is the first whose measurement holds every fill bead: the
        job's planner gets the groove measured before the last pass's bead, so the first cap
        bead's lacks the last fill bead."""
        assert self._cap_corners is not None
        s_cap, top = self._cap_corners
        left = np.interp(groove.s_mm, s_cap, top[:, 0])
        right = np.interp(groove.s_mm, s_cap, top[:, 1])
        pitch = (right - left + 2 * CAP_OVERLAP_MM) / n
        start = left - CAP_OVERLAP_MM
        under = np.column_stack([np.interp(stations, groove.s_mm, _smooth(under_line_mm2(
                                     groove.points, start + k * pitch, start + (k + 1) * pitch)))
                                 for k in range(1, n)])  # fmt: skip
        width = np.interp(stations, s_cap, top[:, 1] - top[:, 0])
        crown = cap_area_mm2(width, reinforcement_mm) / n
        weight = under + crown[:, None]
        total = (n - 1) * np.asarray(cap_share(mean, n, 1))
        return total[:, None] * weight / np.maximum(weight.sum(axis=1, keepdims=True), 1e-9)

    def _place(
        self, groove: MeasuredGroove, n: int, rank: int, cap: bool
    ) -> tuple[str, FloatArray]:
        """The reference and lateral offset (per measured station) of the ``rank``-th bead
        laid in a layer of n: the cap side to side over the top width, a fill layer's beads
        in n equal slots of the fill surface's width, the wall slots first.

        The place is worked out on the groove the pass before measured: the groove *before*
        that pass's bead (its sensor looks ahead of its torch). A wall bead wets its wall and
        lifts the wall's foot up it (a 60 deg V: about a millimetre out), moving the fill
        surface's middle half as far, so a bead offset from the middle or a foot lands off
        its place by as much, every pass. The top corners, the bevels' top edges, are the
        one feature no fill bead moves: a bead of a layer of several is offset from the
        nearer one, as a welder measures a bead's place from the bevel's edge, and lands
        where the plan put it. A layer's only bead follows the surface's middle. The cap's
        beads are placed over the top corners measured before the first cap bead (which
        buries the left one and spills over the plate, moving the corner a sensor sees to
        its toe): the first from the left corner, the others from the right one, which no
        cap bead reaches before the last, laid against it.
        """
        pts = groove.points
        if cap:  # over the top width and CAP_OVERLAP_MM beyond each top corner
            if rank == 0 or self._cap_corners is None:
                top = np.column_stack([_smooth(pts[:, LEFT_TOP, 0]),
                                       _smooth(pts[:, RIGHT_TOP, 0])])  # fmt: skip
                self._cap_corners = (groove.s_mm.copy(), top)
            # on the first cap bead's stations: a later bead's groove may miss some (the
            # groove extractor found none in 32-126 mm of multipass-varying-gap's first cap
            # pass, where the gap is widest, and offsets interpolated over that hole put the
            # second cap bead up to 0.67 mm off its slot, 0.18 mm under the line beside it)
            left, right = self._cap_corners[1][:, 0], self._cap_corners[1][:, 1]
            target = left - CAP_OVERLAP_MM + (rank + 0.5) * (right - left + 2 * CAP_OVERLAP_MM) / n
            return ("left_top", target - left) if rank == 0 else ("right_top", target - right)
        if n == 1:
            return "centre", np.zeros(len(groove))
        slot = fill_order(n)[rank]
        left, width = _smooth(pts[:, LEFT_FOOT, 0]), _smooth(groove.bottom_width_mm)
        wall = self.wall_offset_fraction * width / n
        if self.wall_reference and slot in (0, n - 1):
            return ("left", wall) if slot == 0 else ("right", -wall)
        if slot == 0:
            target = left + wall
        elif slot == n - 1:
            target = left + width - wall
        else:
            target = left + (slot + 0.5) * width / n
        if 2 * slot + 1 < n:  # the left half: from the left top corner
            return "left_top", target - _smooth(pts[:, LEFT_TOP, 0])
        return "right_top", target - _smooth(pts[:, RIGHT_TOP, 0])


def _laid_on(
    groove: MeasuredGroove, plan: Layout, layer: int, rank: int, state: JobState
) -> MeasuredGroove:
    """The groove the ``rank``-th bead of ``layer`` is placed on: ``groove``, except for a
    layer's first bead over a layer of one bead, ``groove`` with that bead added
    (:func:`~seamtrack.control.fill_layout.after_bead`, its area ``state.last_bead_area_mm2``).

    The groove a planner gets was measured before the last pass's bead (the sensor looks
    ahead of the torch). Over a layer of several beads that bead was the layer's last, laid
    against beads already there; over a single bead it *is* the layer below, and the groove
    before it is the fill surface under it: a bead (4 mm on multipass-v-groove's 10- to
    14-pass plans) lower and narrower than the one the layer is laid on, whose slots put the
    layer's beads too far into the middle. With the groove as it lies (``last_bead_area_mm2``
    None: a dry run's true groove) nothing is added."""
    if rank != 0 or layer == 0 or plan.beads_per_layer[layer - 1] != 1:
        return groove
    return after_bead(groove, state.last_bead_area_mm2)


def _smooth(values: FloatArray, half_window: int = 4) -> FloatArray:
    """A running median over 2 * half_window + 1 stations (the measured groove's jitter), over
    the end station repeated at the ends.

    Known end artefact (issue 43): the last station a pass's sensor measures, where its stripe
    leaves the part, is often off (a wall's foot 0.4 mm out), and repeated it outvotes the
    stations before it (5 of 9) at the last four, so a bead's offset from its top corner jumps
    0.77 mm in the seam's last millimetre (pass 3 of multipass-v-groove: 0.387 mm of error).
    Cut short at the ends instead, that job's passes keep within 0.161 mm, but the 300 mm job's
    closed loop, which a change at a pass's end perturbs along the whole pass, then runs one
    pass 0.9 mm off mid-seam (cut at the far end only: 1.87 mm and a lost seam); kept until
    that sensitivity is understood."""
    values = np.asarray(values, dtype=float)
    if len(values) <= 2:
        return values
    return station_median(values, half_window)


class FixedPlanner(AdaptivePlanner):
    """The same beads as :class:`AdaptivePlanner`, each layer at one constant speed."""

    name = "fixed"

    def __init__(self, wall_offset_fraction: float = 0.45):
        super().__init__(wall_offset_fraction, adapt_speed=False)


def _builtin() -> dict[str, type]:
    return {"adaptive": AdaptivePlanner, "fixed": FixedPlanner}


def is_builtin(maker: Any) -> bool:
    """Whether a planner (a name or an instance) is one of seamtrack's own, not a plugin (a
    built-in that fails is seamtrack's fault, never the user's plugin's)."""
    if isinstance(maker, str):
        return maker in _builtin()
    return type(maker) in _builtin().values()


def planner_class(name: str) -> type:
    """The class behind a planner name: a built-in or ``package.module:Class``."""
    builtin = _builtin()
    if name in builtin:
        return builtin[name]
    if ":" not in name:
        raise PluginError(
            f"unknown planner {name!r}",
            field="planner.name",
            fix=f"use one of {', '.join(builtin)}, or package.module:Class",
        )
    cls = load_class(name, "planner.name")
    if not callable(getattr(cls, "plan", None)):
        raise PluginError(
            f"{name!r} lacks the planner method plan",
            field="planner.name",
            fix="implement plan(groove, pass_index, state) -> PassPlan | None",
        )
    return cls


def planner(name: str, **params: Any) -> Any:
    """Build a planner by name with its parameters."""
    cls = planner_class(name)
    try:
        return cls(**params)
    except PluginError:
        raise
    except TypeError as exc:
        raise PluginError(
            f"{name!r} could not be created: {exc}",
            field="planner.params",
            fix="give only the parameters the planner's constructor takes",
        ) from None
    except Exception as exc:
        raise PluginError(
            f"{name!r} could not be created: {exc}",
            field="planner.name",
            fix="check the planner's parameters",
        ) from None


#: A planner's answer refused: (what it returned, how to fix it) -> the error to raise.
Refuse = Callable[[str, str], PluginRuntimeError]


def checked_plan(
    plan: Any,
    name: str,
    pass_index: int,
    groove: MeasuredGroove,
    gantry: bool,
    field: str = "planner.name",
    window: tuple[float, float] | None = None,
) -> PassPlan | None:
    """A planner's answer, refused with a one-line error naming ``field`` (the planner, or the
    scene's overrides that changed the plan) when it is not a usable pass. ``window``: the
    process's travel speed window (mm/s), which every speed of the plan must keep."""

    def refuse(what: str, fix: str) -> PluginRuntimeError:
        return PluginRuntimeError(f"{name!r} plan() for pass {pass_index + 1} {what}",
                                  field=field, fix=fix)  # fmt: skip

    if plan is None:
        return None
    if not isinstance(plan, PassPlan):
        raise refuse(f"returned {type(plan).__name__}", "return a PassPlan, or None when done")
    _check_numbers(plan, refuse)
    plan = _with_speed_profile(plan, refuse)
    if window is not None:
        _check_speed_window(plan, window, refuse)
    plan = _with_offset_profile(plan, refuse)
    if gantry and plan.work_angle_rad != 0.0:
        raise refuse(f"asks for a work angle of {math.degrees(plan.work_angle_rad):.3g} deg on "
                     "a gantry, which cannot tilt its torch", "plan work_angle_rad = 0 on a "
                     "gantry, or weld on an arm (robot.model)")  # fmt: skip
    _check_over_groove(plan, groove, refuse)
    return plan


def _check_numbers(plan: PassPlan, refuse: Refuse) -> None:
    """A known reference point, finite numbers, a travel speed and a wire feed above 0."""
    if plan.reference not in REFERENCES:
        raise refuse(f"returned the reference {plan.reference!r}",
                     f"use one of {', '.join(REFERENCES)}")  # fmt: skip
    for key in ("offset_mm", "work_angle_rad", "travel_speed_mm_s", "wire_feed_mm_s"):
        value = getattr(plan, key)
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise refuse(f"returned {key} = {value!r}", f"give a finite number for {key}")
    if plan.travel_speed_mm_s <= 0:
        raise refuse(f"returned travel_speed_mm_s = {plan.travel_speed_mm_s}",
                     "give a travel speed > 0 mm/s")  # fmt: skip
    if plan.wire_feed_mm_s <= 0:
        raise refuse(f"returned wire_feed_mm_s = {plan.wire_feed_mm_s}",
                     "give a wire feed > 0 mm/s")  # fmt: skip


def _with_speed_profile(plan: PassPlan, refuse: Refuse) -> PassPlan:
    """The plan with its speed profile as arrays: finite, above 0, one speed an arc length."""
    if plan.speed_profile_mm_s is None:
        return plan
    profile, s = _along_seam(plan, plan.speed_profile_mm_s, "a speed profile",
                             "speed_profile_mm_s", refuse, positive=True)  # fmt: skip
    return replace(plan, speed_s_mm=s, speed_profile_mm_s=profile)


def _along_seam(
    plan: PassPlan, values: Any, what: str, key: str, refuse: Refuse, positive: bool = False
) -> tuple[FloatArray, FloatArray]:
    """(values, the plan's arc lengths) as arrays, refused unless the values are finite (and
    above 0 when ``positive``) and one an arc length."""
    profile = np.asarray(values, dtype=float)
    s = np.asarray(plan.speed_s_mm if plan.speed_s_mm is not None else [], dtype=float)
    usable = np.isfinite(profile).all() and (not positive or (profile > 0).all())
    if profile.shape != s.shape or not usable:
        raise refuse(
            f"returned {what} that is not finite{', > 0' if positive else ''} and as long as "
            "its arc lengths",
            f"give speed_s_mm and {key} of one length",
        )
    return profile, s


def _check_speed_window(plan: PassPlan, window: tuple[float, float], refuse: Refuse) -> None:
    """Every travel speed of the plan (its own, its profile's slowest and fastest) within the
    process's window (mm/s)."""
    slowest, fastest = window
    speeds = [plan.travel_speed_mm_s]
    if plan.speed_profile_mm_s is not None and len(plan.speed_profile_mm_s):
        profile = plan.speed_profile_mm_s
        speeds += [float(np.min(profile)), float(np.max(profile))]
    outside_window = [v for v in speeds if not slowest - 1e-9 <= v <= fastest + 1e-9]
    if outside_window:
        raise refuse(f"asks for a travel speed of {outside_window[0]:.4g} mm/s, outside the "
                     f"process window [{slowest:g}, {fastest:g}] mm/s",
                     "keep the travel speed within process.travel_speed_min_mm_s .. "
                     "_max_mm_s")  # fmt: skip


def _with_offset_profile(plan: PassPlan, refuse: Refuse) -> PassPlan:
    """The plan with its offset profile as an array: finite, one offset an arc length."""
    if plan.offset_profile_mm is None:
        return plan
    offsets, _ = _along_seam(plan, plan.offset_profile_mm, "an offset profile",
                             "offset_profile_mm", refuse)  # fmt: skip
    return replace(plan, offset_profile_mm=offsets)


def _check_over_groove(plan: PassPlan, groove: MeasuredGroove, refuse: Refuse) -> None:
    """The bead's place (the reference point plus the offset) within the groove's top width
    all along the seam."""
    reference = POINT_INDEX[plan.reference]
    # on the groove as measured, smoothed along the seam (one frame's outlier is not the groove)
    y = _smooth(groove.points[:, reference, 0]) + plan.offset_at(groove.s_mm)
    lo, hi = _smooth(groove.points[:, LEFT_TOP, 0]), _smooth(groove.points[:, RIGHT_TOP, 0])
    outside = np.flatnonzero((y < lo) | (y > hi))
    if len(outside):
        i = outside[0]
        raise refuse(f"puts the bead at y = {y[i]:.3g} mm at s = {groove.s_mm[i]:.4g} mm, "
                     f"outside the groove's top width [{lo[i]:.3g}, {hi[i]:.3g}] mm (offset "
                     f"{plan.offset_at(groove.s_mm[i]):.3g} mm from {plan.reference})",
                     "give an offset that keeps the torch over the groove")  # fmt: skip
