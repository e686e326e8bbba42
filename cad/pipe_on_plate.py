"""A pipe standing on a plate, fillet-welded all the way round (a girth fillet seam).

Run alone: ``python cad/pipe_on_plate.py [key=value ...] [--step out.step]`` prints a summary
(and exports STEP). ``build(**params)`` returns a :class:`seamtrack.cad.kit.cadpaths.Joint` whose
``"root"`` seam is the circle where the pipe's outer wall meets the plate's top face (z = 0),
closed: it ends where it starts. The torch direction there is the bisector of the plate's
normal (+Z) and the pipe wall's outward normal, 45 deg above the plate.

Frame: the plate's top face is z = 0, the pipe's axis the +Z axis through the origin.
"""

from __future__ import annotations

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

import cadquery as cq

Joint = cadpaths.Joint


def build(
    *,
    pipe_outer_diameter_mm: float = 100.0,
    wall_thickness_mm: float = 5.0,
    pipe_height_mm: float = 80.0,
    plate_size_mm: float = 220.0,
    plate_thickness_mm: float = 10.0,
) -> cadpaths.Joint:
    """Build the pipe on its plate; see the module docstring."""
    params = dict(locals())
    radius = pipe_outer_diameter_mm / 2
    cadpaths.require(radius > 0, "pipe_outer_diameter_mm", f"must be > 0, got {radius * 2}")
    cadpaths.require(
        0 < wall_thickness_mm < radius,
        "wall_thickness_mm",
        f"must be in (0, {radius}), got {wall_thickness_mm}",
    )
    cadpaths.require(pipe_height_mm > 0, "pipe_height_mm", f"must be > 0, got {pipe_height_mm}")
    cadpaths.require(
        plate_size_mm > 2 * radius,
        "plate_size_mm",
        f"the plate must be wider than the pipe ({2 * radius} mm), got {plate_size_mm}",
    )
    cadpaths.require(
        plate_thickness_mm > 0, "plate_thickness_mm", f"must be > 0, got {plate_thickness_mm}"
    )
    plate = cq.Workplane("XY").box(
        plate_size_mm, plate_size_mm, plate_thickness_mm, centered=(True, True, False)
    )
    plate = plate.translate((0, 0, -plate_thickness_mm))
    pipe = (
        cq.Workplane("XY").circle(radius).circle(radius - wall_thickness_mm).extrude(pipe_height_mm)
    )
    solid = plate.union(pipe).val().clean()
    seam = [
        e
        for e in solid.Edges()
        if e.geomType() == "CIRCLE" and abs(e.radius() - radius) < 1e-6 and abs(e.Center().z) < 1e-6
    ]
    if not seam:  # pragma: no cover - OCCT always keeps the foot circle
        raise cadpaths.ParamError("pipe_outer_diameter_mm", "no foot circle in the fused part")
    return Joint(solid=solid, seams={"root": seam}, seam_solid=solid, params=params)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
