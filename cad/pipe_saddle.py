"""A branch pipe set on a main pipe at 90 deg (a tee), fillet-welded round the saddle.

Run alone: ``python cad/pipe_saddle.py [key=value ...] [--step out.step]`` prints a summary
(and exports STEP). ``build(**params)`` returns a :class:`seamtrack.cad.kit.cadpaths.Joint` whose
``"root"`` seam is the saddle: the closed 3D curve where the branch's outer wall (x^2 + y^2 =
r^2) meets the main pipe's outer wall (y^2 + z^2 = R^2), z = sqrt(R^2 - r^2 sin^2 phi) at
x = r cos phi, y = r sin phi. Its height changes by R - sqrt(R^2 - r^2) round the branch and
the angle between the two walls changes with it: a truly 3D seam. The torch direction is the
bisector of the two walls' outward normals.

Frame: the main pipe's axis is the X axis, the branch's axis the +Z axis; the branch's bore
runs through the main pipe's wall into its bore.
"""

from __future__ import annotations

import math

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

import cadquery as cq

Joint = cadpaths.Joint


def build(
    *,
    main_outer_diameter_mm: float = 200.0,
    branch_outer_diameter_mm: float = 100.0,
    wall_thickness_mm: float = 6.0,
    main_length_mm: float = 320.0,
    branch_height_mm: float = 80.0,
) -> cadpaths.Joint:
    """Build the tee; see the module docstring."""
    params = dict(locals())
    R, r, t = main_outer_diameter_mm / 2, branch_outer_diameter_mm / 2, wall_thickness_mm
    cadpaths.require(R > 0, "main_outer_diameter_mm", f"must be > 0, got {2 * R}")
    cadpaths.require(
        0 < r < R,
        "branch_outer_diameter_mm",
        f"must be in (0, {2 * R}) (smaller than the main pipe), got {2 * r}",
    )
    cadpaths.require(0 < t < r, "wall_thickness_mm", f"must be in (0, {r}), got {t}")
    cadpaths.require(
        main_length_mm > 2 * r + 2 * t,
        "main_length_mm",
        f"must exceed the branch's diameter plus two walls ({2 * r + 2 * t} mm)",
    )
    cadpaths.require(
        branch_height_mm > 0, "branch_height_mm", f"must be > 0, got {branch_height_mm}"
    )
    top = R + branch_height_mm
    main = cq.Solid.makeCylinder(R, main_length_mm, cq.Vector(-main_length_mm / 2, 0, 0),
                                 cq.Vector(1, 0, 0))  # fmt: skip
    branch = cq.Solid.makeCylinder(r, top, cq.Vector(0, 0, 0), cq.Vector(0, 0, 1))
    main_bore = cq.Solid.makeCylinder(R - t, main_length_mm + 2,
                                      cq.Vector(-main_length_mm / 2 - 1, 0, 0),
                                      cq.Vector(1, 0, 0))  # fmt: skip
    branch_bore = cq.Solid.makeCylinder(r - t, top + 1, cq.Vector(0, 0, 0), cq.Vector(0, 0, 1))
    solid = main.fuse(branch).cut(main_bore).cut(branch_bore).clean()

    def on_saddle(edge: cq.Edge) -> bool:
        for u in (0.2, 0.5, 0.8):
            p = edge.positionAt(u)
            if abs(math.hypot(p.x, p.y) - r) > 1e-5 or abs(math.hypot(p.y, p.z) - R) > 1e-5:
                return False
            if p.z <= 0:
                return False
        return True

    seam = [e for e in solid.Edges() if on_saddle(e)]
    if not seam:  # pragma: no cover - the fuse always leaves the intersection curve
        raise cadpaths.ParamError("branch_outer_diameter_mm", "no saddle edge in the fused part")
    return Joint(solid=solid, seams={"root": seam}, seam_solid=solid, params=params)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
