"""What the ``seamtrack`` commands' parsers share: a command with its ``--set`` overrides, the
arc length ``--at``, the processes a batch runs on."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

SCENE_HELP = "built-in scene name (seamtrack init --list) or a .toml file"
QUIET_HELP = "print nothing but errors"


def add_command(
    sub: Any,
    name: str,
    fn: Callable[[argparse.Namespace], int],
    help_: str,
    scene: bool = True,
    set_example: str = "tracker.radius_mm=0.5",
) -> argparse.ArgumentParser:
    """A command on the ``seamtrack`` subparsers ``sub``, run by ``fn``; with ``--set`` where it
    reads a scene."""
    p: argparse.ArgumentParser = sub.add_parser(name, help=help_, description=help_)
    p.set_defaults(fn=fn)
    if scene:  # --set only where a scene is read
        p.add_argument(
            "--set",
            action="append",
            metavar="KEY=VALUE",
            help=f"override a scene key, e.g. --set {set_example} (repeatable)",
        )
    return p


def add_at_argument(p: argparse.ArgumentParser, default: float | None, help_: str) -> None:
    """``--at S_MM``: an arc length along the seam, mm."""
    p.add_argument("--at", type=float, default=default, metavar="S_MM", help=help_)


def add_workers_arguments(p: argparse.ArgumentParser, scheduler: bool = True) -> None:
    """``--workers`` (local processes) and, with ``scheduler``, ``--scheduler`` (Dask)."""
    p.add_argument("--workers", type=int, default=1, help="local processes (default 1)")
    if scheduler:
        p.add_argument("--scheduler", help="Dask scheduler address (tcp://host:port)")
