"""Running the command line in a fresh interpreter, for tests."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``python -m seamtrack.cli ARGS`` in a fresh interpreter."""
    return subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )
