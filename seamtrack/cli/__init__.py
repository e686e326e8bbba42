"""The ``seamtrack`` command."""

from seamtrack.cli.main import main

__all__ = ["main"]
