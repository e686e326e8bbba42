"""Bad inputs for articulated arms (render and scan, arm parameters, URDF files): entries of the
catalogue in :mod:`seamtrack.bench.failure_inputs`, with the files they need."""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import Entry

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {}
#: Files made when the workspace is (name -> a function of the path).
GENERATED: dict[str, Any] = {}

ENTRIES: tuple[Entry, ...] = ()
