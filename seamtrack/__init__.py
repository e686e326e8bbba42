"""seamtrack: simulate robotic weld seam tracking with a laser vision sensor.

The public names below are imported lazily, so ``import seamtrack`` stays cheap and a seam-mode
scene never imports CadQuery, Embree or PyVista.
"""

from __future__ import annotations

import importlib
from typing import Any

from seamtrack._version import __version__ as __version__

_EXPORTS = {
    "LaserLineSensor": "seamtrack.sensing.sensor",
    "Seam": "seamtrack.geometry.seam",
    "Profile": "seamtrack.sensing.profiles",
    "Feature": "seamtrack.sensing.profiles",
    "Reason": "seamtrack.sensing.profiles",
    "CartesianRobot": "seamtrack.control.robot",
    "Command": "seamtrack.control.tracking",
    "Measurement": "seamtrack.control.tracking",
    "Tracker": "seamtrack.control.tracking",
    "tracker": "seamtrack.control.registry",
    "load_scene": "seamtrack.simulation.scene",
    "Scene": "seamtrack.simulation.scene",
    "simulate": "seamtrack.simulation.loop",
    "Result": "seamtrack.simulation.loop",
    "extractor": "seamtrack.features.extractors",
    "FeatureExtractor": "seamtrack.features.extractors",
    "load_workpiece": "seamtrack.workpiece.loader",
    "find_seams": "seamtrack.workpiece.weldment",
    "SeamtrackError": "seamtrack.errors",
}

#: Subpackages reachable as attributes (``st.workpiece.find_seams``), imported on first use.
_SUBPACKAGES = {"workpiece"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        return importlib.import_module(f"seamtrack.{name}")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'seamtrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | _SUBPACKAGES)
