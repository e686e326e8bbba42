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
    "Camera": "seamtrack.sensing.camera",
    "StripeImage": "seamtrack.sensing.camera",
    "Material": "seamtrack.sensing.materials",
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
    "classify": "seamtrack.features.classify",
    "load_workpiece": "seamtrack.workpiece.loader",
    "find_seams": "seamtrack.workpiece.weldment",
    "SeamtrackError": "seamtrack.errors",
    "rosenthal_temperature": "seamtrack.heat.rosenthal",
    "image_source_temperature": "seamtrack.heat.rosenthal",
}

__all__ = sorted(_EXPORTS)


#: Subpackages reached as attributes (``st.datasets.open(...)``, ``st.workpiece.find_seams``),
#: imported on first use.
_SUBPACKAGES = {"datasets": "seamtrack.datasets", "workpiece": "seamtrack.workpiece"}


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        package = importlib.import_module(_SUBPACKAGES[name])
        globals()[name] = package
        return package
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'seamtrack' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBPACKAGES))
