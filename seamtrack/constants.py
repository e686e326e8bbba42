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
