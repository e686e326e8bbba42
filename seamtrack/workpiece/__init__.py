"""Workpieces: run a ``cad/`` script or read a STEP file, mesh with a measured tolerance, cache.

CadQuery and OCP are imported only inside the functions that need them.
"""

from seamtrack.workpiece.loader import (
    Workpiece,
    builtin_joints,
    cache_dir,
    clear_cache,
    load_workpiece,
    mesh_tradeoff,
)

__all__ = [
    "Workpiece",
    "builtin_joints",
    "cache_dir",
    "clear_cache",
    "load_workpiece",
    "mesh_tradeoff",
]
