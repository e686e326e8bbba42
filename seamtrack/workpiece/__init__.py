"""Workpieces: run a ``cad/`` script or read a STEP file, mesh with a measured tolerance, cache;
find the seams of a weldment (``find_seams``); build weldx ISO 9692-1 grooves; the beads of a
multi-pass weld and the fill of a groove along its seam (``beads``, ``fill``).

CadQuery, OCP and weldx are imported only inside the functions that need them.
"""

from seamtrack.workpiece.beads import BeadShape, bead_area_mm2, lay_bead
from seamtrack.workpiece.fill import FillState
from seamtrack.workpiece.loader import (
    Workpiece,
    builtin_joints,
    builtin_weldments,
    cache_dir,
    clear_cache,
    load_workpiece,
    mesh_tradeoff,
)
from seamtrack.workpiece.weldment import FoundSeam, find_seams

__all__ = [
    "BeadShape",
    "FillState",
    "FoundSeam",
    "Workpiece",
    "bead_area_mm2",
    "builtin_joints",
    "builtin_weldments",
    "cache_dir",
    "clear_cache",
    "find_seams",
    "lay_bead",
    "load_workpiece",
    "mesh_tradeoff",
]
