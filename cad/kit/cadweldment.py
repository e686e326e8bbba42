"""Shared helpers of the weldment scripts (``cad/weldment_*.py``): named bodies, STEP export.

A weldment is an assembly of separate solids (plates, gussets, profiles) that touch or face
each other where they are to be welded; nothing is fused, so the joints stay between bodies,
as in the STEP file of a CAD assembly. Every ``build(**params)`` of a weldment script returns
a :class:`Weldment`; ``python cad/weldment_x.py [key=value ...] [--step out.step]`` prints a
summary and exports the bodies, with their names, as one STEP assembly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import cadquery as cq

try:
    from seamtrack.cad.kit.cadpaths import ParamError, require, script_args
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit.cadpaths import ParamError, require, script_args  # type: ignore[no-redef]

__all__ = ["ParamError", "Weldment", "box", "prism", "require", "run_script"]


@dataclass(frozen=True)
class Weldment:
    """What every weldment ``build(**params)`` returns.

    Attributes
    ----------
    bodies : dict of str to cadquery.Solid
        The bodies by name (unique, no ``/``), in a fixed order; units mm.
    params : dict
        The parameters the weldment was built with.
    """

    bodies: dict[str, cq.Solid]
    params: dict[str, object] = field(default_factory=dict)

    def compound(self) -> cq.Compound:
        """All bodies as one compound (nothing fused)."""
        return cq.Compound.makeCompound(list(self.bodies.values()))

    def export_step(self, path: str) -> None:
        """Write the bodies as a STEP assembly, one named part per body."""
        assembly = cq.Assembly(name="weldment")
        for name, solid in self.bodies.items():
            assembly.add(solid, name=name)
        assembly.export(path, exportType="STEP")

    def summary(self) -> str:
        """A short human-readable description (what ``python cad/weldment_x.py`` prints)."""
        lines = []
        for name, solid in self.bodies.items():
            bb = solid.BoundingBox()
            lines.append(
                f"{name}: valid {solid.isValid()}, volume {solid.Volume():.1f} mm^3, "
                f"x {bb.xmin:.1f}..{bb.xmax:.1f}, y {bb.ymin:.1f}..{bb.ymax:.1f}, "
                f"z {bb.zmin:.1f}..{bb.zmax:.1f} mm"
            )
        return "\n".join(lines)


def box(x: tuple[float, float], y: tuple[float, float], z: tuple[float, float]) -> cq.Solid:
    """An axis-aligned box between the given (min, max) coordinates, mm."""
    for name, (lo, hi) in (("x", x), ("y", y), ("z", z)):
        if not hi > lo:
            raise ParamError(name, f"empty box extent {lo}..{hi}")
    return cq.Solid.makeBox(x[1] - x[0], y[1] - y[0], z[1] - z[0], cq.Vector(x[0], y[0], z[0]))


def prism(profile_yz: Sequence[tuple[float, float]], x: tuple[float, float]) -> cq.Solid:
    """A closed (y, z) polygon extruded along +X from ``x[0]`` to ``x[1]``, mm."""
    points = [cq.Vector(x[0], y, z) for y, z in profile_yz]
    face = cq.Face.makeFromWires(cq.Wire.makePolygon(points, close=True))
    solid = cq.Solid.extrudeLinear(face, cq.Vector(x[1] - x[0], 0, 0))
    if solid.Volume() < 0:
        solid = cq.Solid(solid.wrapped.Reversed())
    return solid


def run_script(build, argv: Sequence[str] | None = None) -> None:  # type: ignore[no-untyped-def]
    """Command line of a weldment script: ``python cad/weldment_x.py [k=v ...] [--step F]``."""
    params, out = script_args(argv)
    weldment = build(**params)
    print(weldment.summary())
    if out:
        weldment.export_step(out)
        print(f"wrote {out}")
