"""Trackers by name: the built-ins (the paper's algorithms I and II and a look-ahead
``trajectory`` tracker), a user's class named ``package.module:Class``, or a class registered
under the entry-point group ``seamtrack.trackers``.
"""

from __future__ import annotations

import importlib
import inspect
import os
import sys
from importlib.metadata import entry_points
from typing import Any

from seamtrack.control.trackers import ConvergenceRadius, PointToPoint
from seamtrack.control.tracking import Tracker
from seamtrack.control.trajectory import TrajectoryTracker
from seamtrack.errors import PluginError


def _builtin() -> dict[str, type]:
    return {
        "point-to-point": PointToPoint,
        "convergence-radius": ConvergenceRadius,
        "trajectory": TrajectoryTracker,
    }


#: Short names the CLI and the paper use.
ALIASES = {
    "I": "point-to-point",
    "II": "convergence-radius",
    "1": "point-to-point",
    "2": "convergence-radius",
}

_PROTOCOL_METHODS = ("reset", "update", "command")


def load_class(name: str, field: str) -> Any:
    """The object ``package.module:Class`` names (a user's plugin), or a one-line error naming
    ``field``."""
    module_name, _, attr = name.partition(":")
    try:
        module = _import_from_here(module_name)
    except Exception as exc:  # the user's module may fail in any way on import
        raise PluginError(
            f"cannot import {module_name!r}: {exc}",
            field=field,
            fix="check the module is on PYTHONPATH (or installed) and imports",
        ) from None
    cls = getattr(module, attr, None)
    if cls is None:
        raise PluginError(
            f"module {module_name!r} has no {attr!r}",
            field=field,
            fix="name the class as package.module:Class",
        )
    return cls


def _import_from_here(module_name: str) -> Any:
    """``module_name`` imported, looked for in the current directory too when it is on no
    path (as uvicorn and gunicorn load ``module:app``: the ``seamtrack`` command, unlike
    ``python -m``, does not put the current directory on ``sys.path``)."""
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        here = os.getcwd()
        top = module_name.partition(".")[0]
        if exc.name != top or here in sys.path or not _is_module_in(here, top):
            raise
    sys.path.insert(0, here)
    return importlib.import_module(module_name)


def _is_module_in(folder: str, top: str) -> bool:
    return os.path.isfile(os.path.join(folder, top + ".py")) or os.path.isdir(
        os.path.join(folder, top)
    )


def tracker_class(name: str) -> type:
    """The class behind a tracker name: a built-in, ``package.module:Class``, or an entry
    point in the group ``seamtrack.trackers``."""
    name = ALIASES.get(name, name)
    builtin = _builtin()
    if name in builtin:
        return builtin[name]
    if ":" in name:
        cls = load_class(name, "tracker.name")
    else:
        found = [ep for ep in entry_points(group="seamtrack.trackers") if ep.name == name]
        if not found:
            known = ", ".join(sorted(builtin) + sorted(ALIASES))
            raise PluginError(
                f"unknown tracker {name!r}",
                field="tracker.name",
                fix=f"use one of {known}, or package.module:Class",
            )
        try:
            cls = found[0].load()
        except Exception as exc:
            raise PluginError(
                f"entry point {name!r} failed to load: {exc}",
                field="tracker.name",
                fix="repair or uninstall that plugin",
            ) from None
    missing = [m for m in _PROTOCOL_METHODS if not callable(getattr(cls, m, None))]
    if missing:
        raise PluginError(
            f"{name!r} lacks the tracker method(s) {', '.join(missing)}",
            field="tracker.name",
            fix="implement reset(context), update(measurement) and "
            "command(t_s, tcp_world, tcp_velocity_world)",
        )
    return cls


def tracker_parameters(name: str) -> set[str]:
    """Keyword parameters a tracker class takes (all names when it takes ``**kwargs``)."""
    cls = tracker_class(name)
    try:
        parameters = inspect.signature(cls).parameters
    except (TypeError, ValueError):
        return set()
    if any(p.kind is p.VAR_KEYWORD for p in parameters.values()):
        return {"radius_mm", "tolerance_mm"}
    return {k for k in parameters if k != "self"}


def tracker(name: str, **params: Any) -> Tracker:
    """Build a tracker by name with its parameters (unknown parameters are an error)."""
    cls = tracker_class(name)
    try:
        signature = inspect.signature(cls)
    except (TypeError, ValueError):
        signature = None
    if signature is not None:
        accepts_any = any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values())
        unknown = [k for k in params if k not in signature.parameters and not accepts_any]
        if unknown:
            allowed = ", ".join(k for k in signature.parameters if k != "self") or "none"
            raise PluginError(
                f"{name!r} takes no parameter {unknown[0]!r}",
                field=f"tracker.{unknown[0]}",
                fix=f"parameters of this tracker: {allowed}",
            )
    try:
        instance = cls(**params)
    except PluginError:
        raise
    except Exception as exc:
        raise PluginError(
            f"{name!r} could not be created: {exc}",
            field="tracker.name",
            fix="check the tracker's parameters",
        ) from None
    return instance
