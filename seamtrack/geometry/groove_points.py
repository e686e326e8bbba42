"""The 7 points of a groove's cross-section, by name.

A groove (a V, a narrow gap, a U, empty or partly filled with beads) is read as 7 points in a
plane across the seam, y ascending from the left plate to the right: the left top corner (where
the left plate's surface meets its wall), the left wall's foot at the fill surface (or the
groove's bottom), three points along the bottom between the feet (the middle one is the
groove's centre), the right wall's foot and the right top corner. The groove extractor finds
them in a laser profile (laser frame, (y_L, z_L)), a multi-pass job keeps them per station
(station frame, (y, z)), and a fill planner places its beads from them.

The rows are named here once; every reader indexes a (..., 7, 2) array by these names.
"""

from __future__ import annotations

#: Row of the left top corner: the left plate's surface meets its wall (the bevel's edge).
LEFT_TOP = 0
#: Row of the left wall's foot at the fill surface.
LEFT_FOOT = 1
#: Row of the bottom point between the left foot and the middle.
BOTTOM_LEFT = 2
#: Row of the bottom's middle: the groove's centre.
MIDDLE = 3
#: Row of the bottom point between the middle and the right foot.
BOTTOM_RIGHT = 4
#: Row of the right wall's foot at the fill surface.
RIGHT_FOOT = 5
#: Row of the right top corner.
RIGHT_TOP = 6
#: How many points: rows 0-6.
N_POINTS = 7
#: The bottom five (the feet and the three bottom points), as a slice of the rows.
BOTTOM = slice(LEFT_FOOT, RIGHT_FOOT + 1)
#: The two top corners' rows, left then right.
TOPS = [LEFT_TOP, RIGHT_TOP]
#: The two feet's rows, left then right.
FEET = [LEFT_FOOT, RIGHT_FOOT]

#: A tracker's or a bead's reference (the scene's and the extractor's names) -> its row.
POINT_INDEX = {
    "left": LEFT_FOOT,
    "right": RIGHT_FOOT,
    "centre": MIDDLE,
    "left_top": LEFT_TOP,
    "right_top": RIGHT_TOP,
}
