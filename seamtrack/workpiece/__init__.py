"""Workpieces: run a ``cad/`` script or read a STEP file, mesh with a measured tolerance, cache;
find the seams of a weldment (``find_seams``); build weldx ISO 9692-1 grooves.

CadQuery, OCP and weldx are imported only inside the functions that need them.
"""

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
    "FoundSeam",
    "Workpiece",
    "builtin_joints",
    "builtin_weldments",
    "cache_dir",
    "clear_cache",
    "find_seams",
    "load_workpiece",
    "mesh_tradeoff",
]
