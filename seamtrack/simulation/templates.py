"""The built-in scenes (``seamtrack init --list``): their names and one-line descriptions, read
from the TOML files shipped in :mod:`seamtrack.scenes` without importing the simulation, so that
listing them stays instant."""

from __future__ import annotations

import tomllib
from importlib import resources


def builtin_scenes() -> dict[str, str]:
    """Built-in scene names and their one-line descriptions."""
    out = {}
    for entry in sorted(resources.files("seamtrack.scenes").iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            data = tomllib.loads(entry.read_text())
            out[entry.name[:-5]] = str(data.get("description", ""))
    return out
