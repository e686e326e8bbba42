"""What a joint should look like: expectations that make a family extractor refuse implausible
answers (the scene's ``[extractor.expect]``, or ``expect={...}`` in Python).

Keys (degrees only at this edge, with the ``_deg`` suffix; radians inside):

=================  ===========================================================  =========
key                meaning                                                      default
=================  ===========================================================  =========
``angle_deg``      included angle of a groove's bevels or a corner's faces      none
``angle_tol_deg``  how far the measured angle may stray                          10
``depth_mm``       seam point below the plates (a groove); a lap's step height  none
``depth_tol_mm``   how far the measured depth may stray                          1.0
``gap_mm``         root gap (a groove, a square butt)                            none
``gap_tol_mm``     how far the measured gap may stray                            0.5
=================  ===========================================================  =========

A tolerance without its value is refused, and so is a quantity the family does not measure
(:data:`MEASURES`). A groove expected without a gap (``gap_mm`` within its tolerance of 0)
takes the bevels' intersection as its seam point, whatever lies between the bevels' lower
ends.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from seamtrack.errors import PluginError

#: The quantities each family extractor measures.
MEASURES: dict[str, tuple[str, ...]] = {
    "v-groove": ("angle", "depth", "gap"),
    "fillet": ("angle",),
    "outside-corner": ("angle",),
    "square-butt": ("gap",),
    "lap": ("depth",),
}
_DEFAULT_TOL = {"angle_tol_deg": 10.0, "depth_tol_mm": 1.0, "gap_tol_mm": 0.5}
_KEYS = ("angle_deg", "angle_tol_deg", "depth_mm", "depth_tol_mm", "gap_mm", "gap_tol_mm")


@dataclass(frozen=True)
class Expect:
    """Expected joint geometry, in mm and radians; None where nothing is expected."""

    angle: float | None = None
    angle_tol: float = math.radians(_DEFAULT_TOL["angle_tol_deg"])
    depth_mm: float | None = None
    depth_tol_mm: float = _DEFAULT_TOL["depth_tol_mm"]
    gap_mm: float | None = None
    gap_tol_mm: float = _DEFAULT_TOL["gap_tol_mm"]

    @property
    def gapless(self) -> bool:
        """Whether no root gap is expected (0 lies within the gap's tolerance)."""
        return self.gap_mm is not None and self.gap_mm <= self.gap_tol_mm

    def angle_range(self, lo: float, hi: float) -> tuple[float, float]:
        """The family's own angle range (rad) narrowed to the expectation."""
        if self.angle is None:
            return lo, hi
        return max(lo, self.angle - self.angle_tol), min(hi, self.angle + self.angle_tol)

    def check(self, *, angle: float | None = None, depth: float | None = None,
              gap: float | None = None) -> str:  # fmt: skip
        """Why measured values break the expectation ("" when they keep it)."""
        for name, value, want, tol, unit, scale in (
            ("included angle", angle, self.angle, self.angle_tol, "deg", math.degrees(1.0)),
            ("depth", depth, self.depth_mm, self.depth_tol_mm, "mm", 1.0),
            ("gap", gap, self.gap_mm, self.gap_tol_mm, "mm", 1.0),
        ):
            if want is None or value is None or not math.isfinite(value):
                continue
            if abs(value - want) > tol:
                return (
                    f"implausible {name}: {value * scale:.3g} {unit}, expected "
                    f"{want * scale:.3g} +- {tol * scale:.3g} {unit}"
                )
        return ""


def parse_expect(value: Any, joint: str) -> Expect | None:
    """An :class:`Expect` from a mapping of the keys above (or an ``Expect``, or None).

    Raises
    ------
    PluginError
        An unknown key, a value that is no finite number in range, a tolerance without its
        value, or a quantity ``joint`` does not measure (``field`` =
        ``"extractor.expect.<key>"``, with a fix).
    """
    if value is None or isinstance(value, Expect):
        return value
    if not isinstance(value, Mapping):
        raise PluginError(
            f"expect must be a table of expected values, got {value!r}",
            field="extractor.expect",
            fix="e.g. expect = {angle_deg = 60, depth_mm = 7, gap_mm = 1}",
        )
    measured = MEASURES.get(joint, ())
    numbers: dict[str, float] = {}
    for key, raw in value.items():
        field = f"extractor.expect.{key}"
        if key not in _KEYS:
            raise PluginError(
                f"unknown expectation {key!r}", field=field, fix=f"use {', '.join(_KEYS)}"
            )
        quantity = key.split("_")[0]
        if quantity not in measured:
            keys = [k for k in _KEYS if k.split("_")[0] in measured]
            raise PluginError(
                f"{joint} measures no {quantity}",
                field=field,
                fix=f"drop it; {joint} takes {', '.join(keys) or 'no expectations'}",
            )
        if isinstance(raw, bool) or not isinstance(raw, int | float) or not math.isfinite(raw):
            raise PluginError(
                f"must be a finite number, got {raw!r}", field=field, fix="give a number"
            )
        x = float(raw)
        bad = (
            (key == "angle_deg" and not 0.0 < x < 180.0)
            or ("_tol_" in key and not x > 0.0)
            or (key in ("depth_mm", "gap_mm") and x < 0.0)
        )
        if bad:
            fix = {
                "angle_deg": "an included angle between 0 and 180 deg",
                "depth_mm": "a depth >= 0 mm",
                "gap_mm": "a gap >= 0 mm",
            }.get(key, "a tolerance > 0")
            raise PluginError(f"out of range: {raw!r}", field=field, fix=f"give {fix}")
        numbers[key] = x
    for key in ("angle_tol_deg", "depth_tol_mm", "gap_tol_mm"):
        base = key.replace("_tol", "")
        if key in numbers and base not in numbers:
            raise PluginError(
                f"a tolerance without its value ({base})",
                field=f"extractor.expect.{key}",
                fix=f"give {base} too, or drop {key}",
            )
    tol = {**_DEFAULT_TOL, **{k: v for k, v in numbers.items() if "_tol_" in k}}
    return Expect(
        angle=math.radians(numbers["angle_deg"]) if "angle_deg" in numbers else None,
        angle_tol=math.radians(tol["angle_tol_deg"]),
        depth_mm=numbers.get("depth_mm"),
        depth_tol_mm=tol["depth_tol_mm"],
        gap_mm=numbers.get("gap_mm"),
        gap_tol_mm=tol["gap_tol_mm"],
    )
