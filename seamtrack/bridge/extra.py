"""Whether the ``ros`` extra is installed, and whether a path is a recording: asked without
importing seamtrack's ROS modules (or any ROS library)."""

from __future__ import annotations

import importlib
from pathlib import Path

from seamtrack.errors import SeamtrackError

#: The modules of the ``ros`` extra a recording or an import needs (the lockstep bridge adds its
#: transports).
RECORD_MODULES = ("rosbags", "mcap", "mcap_ros2")


def require_ros(field: str, modules: tuple[str, ...] = RECORD_MODULES) -> None:
    """Import ``modules`` or raise a :class:`SeamtrackError` naming ``pip install
    'seamtrack[ros]'`` (field ``field``, e.g. ``--record``)."""
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            raise SeamtrackError(
                f"{name} (the ROS 2 libraries) is not installed",
                field=field,
                fix="pip install 'seamtrack[ros]'",
            ) from None


def is_recording(path: str | Path) -> bool:
    """Whether ``path`` is an MCAP file, a ROS 2 bag (a folder with ``metadata.yaml``, or a
    ``.db3``) or a ROS 1 ``.bag``: what :mod:`seamtrack.bridge.importer` reads."""
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file()
    return p.suffix.lower() in (".mcap", ".db3", ".bag")
