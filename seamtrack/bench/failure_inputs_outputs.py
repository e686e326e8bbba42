"""Bad inputs for where a command writes (issue 43, item 15): never two outputs mixed in one
folder, never a user's own file replaced. Entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`, with the folders they need."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import SHORT, Entry

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {
    # an earlier run's folder, as `seamtrack run` writes it
    "earlier_run/summary.json": b'{"status": "completed"}\n',
    "earlier_run/scene.toml": b"# an earlier run's scene\n",
    "earlier_run/error.png": b"not really a PNG, but the earlier run's\n",
    # an earlier job's folder, with a pass the next job may not lay
    "earlier_job/job.json": b'{"status": "completed"}\n',
    "earlier_job/scene.toml": b"# an earlier job's scene\n",
    "earlier_job/pass_07/summary.json": b'{"status": "completed"}\n',
    # a folder of the user's own labels: not seamtrack's
    "my_labels/labels.csv": b"index,y_mm,z_mm\n0,0.5,80.0\n",
    "my_labels/notes.txt": b"hand-labelled on Tuesday\n",
}

GENERATED: dict[str, Callable[[Path], None]] = {}


def _run_into(folder: str, *extra: str) -> tuple[str, ...]:
    return ("run", *SHORT, "--out", folder, *extra)


#: A short multi-pass job's scene keys (refused before anything is built).
_JOB = ("multipass-v-groove", "--set", "workpiece.params.seam_length_mm=20")

ENTRIES: tuple[Entry, ...] = (
    Entry("run into an earlier run's folder", _run_into("earlier_run"), field="--out"),
    Entry("run into a folder of one's own files", _run_into("my_labels"), field="--out"),
    Entry(
        "run with --force into a folder of one's own files",
        _run_into("my_labels", "--force"),
        field="--out",
    ),
    Entry(
        "job into an earlier job's folder", ("run", *_JOB, "--out", "earlier_job"), field="--out"
    ),
    Entry(
        "import onto a folder of one's own labels",
        ("extractors", "import", "--real", "one_cloud.mcap", "--out", "my_labels", "--force"),
        field="--out",
    ),
)
