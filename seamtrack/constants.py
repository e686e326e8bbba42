"""Numerical tolerances, in one place (mm unless the name says otherwise)."""

#: Two seam points closer than this are the same point (a repeated point is an error).
SEAM_POINT_TOL_MM = 1e-9

#: Relative slack on the chip-edge test, so that a point exactly on the edge of the field of
#: view counts as inside despite rounding in Eq. 1-3.
CHIP_EDGE_RTOL = 1e-12

#: Shadow rays start this far from the hit towards the camera: embreex fixes tnear at 0, and
#: 10 um keeps false self-occlusion of float32 hits under 0.01 % (DESIGN.md, measured).
SHADOW_RAY_OFFSET_MM = 1e-2

#: A robot axis counts as at rest below this speed.
AT_REST_SPEED_MM_S = 1e-6

#: Progress along the seam smaller than this is no progress (stall detection).
PROGRESS_EPS_MM = 1e-3

#: Barycentric slack (dimensionless) of the float64 inside test that refines Embree's hits: a
#: point this far outside its triangle still belongs to it (rays through shared edges/vertices).
BARYCENTRIC_TOL = 1e-9


# --------------------------------------------------------------------------- size limits
# Every knob that sets an array size is bounded when a scene is validated, so that a typo is
# refused in one line instead of exhausting the memory (each bound leaves room for real use).

#: Rays of one laser fan; a real sensor's profile has at most a few thousand points.
MAX_RAYS = 100_000

#: Points of a seam polyline (the paper's curve at 2 mm has 201; 1e6 points take ~0.2 GB).
MAX_SEAM_POINTS = 1_000_000

#: Control ticks of one run (time limit / control period); the loop logs ~100 bytes a tick and
#: scoring takes a few hundred more, so the bound keeps a run under 2 GB.
MAX_TICKS = 4_000_000

#: Cases (values x seeds) of one sweep.
MAX_SWEEP_CASES = 100_000

#: Finest chordal meshing tolerance: below it a curved CAD face meshes into more triangles
#: than fit in memory (and Embree's float32 cannot resolve the difference anyway).
MIN_MESH_TOLERANCE_MM = 1e-4

#: Coarsest chordal meshing tolerance a scene may ask for: the facets stand off a curved face by
#: up to the tolerance, so a coarser mesh moves the surface the sensor sees by more than a
#: millimetre (pipe-on-plate at 1e308 mm "completed" with a 14.6 mm error).
MAX_MESH_TOLERANCE_MM = 1.0

#: Finest meshing tolerance relative to the part's bounding-box diagonal, checked once the part
#: is built (the paper's part at 1e-3 mm, 2.4e-6 of its size, meshes into 1.7e6 triangles).
MIN_MESH_TOLERANCE_RATIO = 1e-6

#: Most triangles a part may mesh into. Meshing and measuring the deviation peak at about 200-300
#: bytes a triangle over what the process held before (`seamtrack bench mesh`; cad/kit/cadmesh.py
#: meshes coarse inside and refines in numpy), and a whole mesh-mode scan adds about 270 bytes a
#: triangle over the 0.7 GB the libraries take (`seamtrack scan paper-v-groove --set
#: workpiece.tolerance_mm=0.0005`: 782 MB; 0.1 mm: 710 MB): 2 million keep a run under 2 GB.
MAX_MESH_TRIANGLES = 2_000_000

#: Seams run from their lexicographically smallest end (x, then y, then z); coordinates closer
#: than this count as equal, so float noise in a STEP file never decides the direction.
LEXICOGRAPHIC_TIE_MM = 1e-3
