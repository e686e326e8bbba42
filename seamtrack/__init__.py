"""seamtrack: simulate robotic weld seam tracking with a laser vision sensor.

The public names below are imported lazily, so ``import seamtrack`` stays cheap and a seam-mode
scene never imports CadQuery, Embree or PyVista.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    "LaserLineSensor": "seamtrack.sensor",
    "Seam": "seamtrack.seam",
    "Profile": "seamtrack.profiles",
    "Feature": "seamtrack.profiles",
    "Reason": "seamtrack.profiles",
    "CartesianRobot": "seamtrack.robot",
    "Command": "seamtrack.trackers",
    "Measurement": "seamtrack.trackers",
    "Tracker": "seamtrack.trackers",
    "tracker": "seamtrack.trackers",
    "load_scene": "seamtrack.scene",
    "Scene": "seamtrack.scene",
    "simulate": "seamtrack.simulation",
    "Result": "seamtrack.simulation",
    "extractor": "seamtrack.features",
    "FeatureExtractor": "seamtrack.features",
    "load_workpiece": "seamtrack.workpiece",
    "SeamtrackError": "seamtrack.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'seamtrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
