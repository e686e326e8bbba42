"""Tacks and clamps: what holds a butt joint's plates at positions along the seam while it is
welded. A clamp holds whatever the force; a tack breaks when the force on it exceeds its
strength, the nominal strength of a partial-penetration groove weld in tension normal to its
axis, ``0.60 * F_EXX * throat * length`` (ANSI/AISC 360-16, *Specification for Structural
Steel Buildings*, Table J2.5).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from seamtrack.errors import SeamtrackError

#: The weld metal's classified tensile strength, MPa: 70 ksi, the E70 / ER70S classes of
#: carbon-steel electrodes and wires (AWS A5.1, A5.18).
E70_STRENGTH_MPA = 70.0 * 6.894757


@dataclass(frozen=True)
class Clamp:
    """A clamp at ``position_mm`` along the seam: it holds whatever the force."""

    position_mm: float

    def holds(self, force_n: float) -> bool:
        return True


@dataclass(frozen=True)
class Tack:
    """A tack weld at ``position_mm`` along the seam, ``length_mm`` long, its throat (the
    depth it fuses) ``throat_mm``; ``electrode_strength_mpa`` is F_EXX."""

    position_mm: float
    length_mm: float
    throat_mm: float
    electrode_strength_mpa: float = E70_STRENGTH_MPA

    @property
    def break_force_n(self) -> float:
        """``0.60 * F_EXX * throat * length`` (AISC 360-16 Table J2.5), N."""
        return 0.60 * self.electrode_strength_mpa * self.throat_mm * self.length_mm

    def holds(self, force_n: float) -> bool:
        """Whether the tack holds a force of ``force_n`` (N, either sign) across the joint."""
        return abs(force_n) <= self.break_force_n


def check_constraints(
    constraints: Sequence[Tack | Clamp], seam_length_mm: float, *, field: str
) -> None:
    """Raise :class:`SeamtrackError` naming ``field[i]`` for a constraint off the seam
    (position outside 0 .. ``seam_length_mm``) or a tack of no size."""
    for i, c in enumerate(constraints):
        where = f"{field}[{i}]"
        if not math.isfinite(c.position_mm) or not 0.0 <= c.position_mm <= seam_length_mm:
            raise SeamtrackError(
                f"a {type(c).__name__.lower()} at {c.position_mm:g} mm lies outside the seam "
                f"(0 to {seam_length_mm:g} mm)",
                field=f"{where}.position_mm",
                fix=f"give a position along the seam, from 0 to {seam_length_mm:g} mm",
            )
        if isinstance(c, Tack):
            for name in ("length_mm", "throat_mm", "electrode_strength_mpa"):
                value = getattr(c, name)
                if not math.isfinite(value) or value <= 0:
                    raise SeamtrackError(
                        f"a tack's {name} of {value:g}", field=f"{where}.{name}",
                        fix="give a value > 0",
                    )  # fmt: skip
