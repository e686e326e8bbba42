"""Bad inputs for units, files and values that would complete a wrong run (issue 43, items 16,
18-20): entries of the catalogue in :mod:`seamtrack.bench.failure_inputs`, with the files they
need (a seam in metres, a ragged CSV, real-profile sets in metres, with labels that are no
numbers, of no profile or no measured point, and a 0.5 MB npz that would load into 1.2 GB).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.bench.failure_kit import Entry, naming_key, run_set, set_args

#: paper-verification's seam (Eq. 15-17, 400 mm) written in metres.
_t = np.linspace(0.0, 0.4, 201).tolist()
_METRES = "x_mm,y_mm,z_mm\n" + "".join(f"{x!r},{0.01 * math.sin(10 * x)!r},0.0\n" for x in _t)

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {
    "seam_in_metres.csv": _METRES.encode(),
    "ragged.csv": b"x_mm,y_mm,z_mm\n0,0,0\n10,0\n20,0,0\n",
}


def _real_set(
    folder: Path,
    z_mm: np.ndarray,
    labels: str | None = None,
    joint: str = "v-groove",
    y_mm: np.ndarray | None = None,
) -> None:
    """A real-profile set in the bench's layout (docs/extractors.md, 'Real data')."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "set.json").write_text(json.dumps({"joint": joint}))
    width = z_mm.shape[1] if z_mm.ndim == 2 else 0
    y = np.linspace(-10.0, 10.0, width) if y_mm is None else y_mm
    np.savez_compressed(folder / "profiles.npz", y_mm=y, z_mm=z_mm)
    if labels is not None:
        (folder / "labels.csv").write_text("index,y_mm,z_mm\n" + labels)


def _v(n: int = 3, scale: float = 1.0) -> np.ndarray:
    """``n`` profiles of a 90 deg V, 100 mm from the emitter, in mm (scale 1e-3: in metres)."""
    y = np.linspace(-10.0, 10.0, 201)
    return np.tile(scale * (100.0 + 10.0 - np.minimum(np.abs(y), 10.0)), (n, 1))


def _labels(rows: list[str]) -> str:
    return "".join(f"{i},{row}\n" for i, row in enumerate(rows))


GOOD = _labels(["0.0,110.0"] * 3)

#: Files made when the workspace is (name -> maker of that folder).
GENERATED: dict[str, Any] = {
    "real_in_metres": lambda p: _real_set(
        p, _v(scale=1e-3), _labels(["0.0,0.11"] * 3), y_mm=1e-3 * np.linspace(-10, 10, 201)
    ),
    "real_labels_in_metres": lambda p: _real_set(p, _v(), _labels(["0.0,0.11"] * 3)),
    "real_text_label": lambda p: _real_set(p, _v(), _labels(["0.0,110.0", "seam,here", "0,110"])),
    "real_nan_label": lambda p: _real_set(p, _v(), _labels(["0.0,110.0", "nan,nan", "0,110"])),
    "real_inf_label": lambda p: _real_set(p, _v(), _labels(["0.0,110.0", "0,inf", "0,110"])),
    "real_all_nan": lambda p: _real_set(p, np.full((3, 201), np.nan), GOOD),
    "real_no_profile": lambda p: _real_set(p, np.zeros((0, 201)), "", joint="none"),
    # 0.5 MB of NaN that numpy would load into 330 MB and the profiles into 1.2 GB.
    "real_npz_bomb": lambda p: _real_set(p, np.full((20_000, 2048), np.nan), joint="none"),
}


def _real(folder: str) -> tuple[str, ...]:
    return ("extractors", "bench", "--real", folder, "--out", "OUT")


ENTRIES: tuple[Entry, ...] = (
    # --- item 16: units and labels
    naming_key("seam CSV in metres",
               run_set('seam.source="csv"', 'seam.file="seam_in_metres.csv"')),
    naming_key("seam points in metres",
               run_set('seam.source="points"', "seam.points_mm=[[0,0,0],[0.2,0,0],[0.4,0.01,0]]")),
    Entry("real-profile set in metres", _real("real_in_metres"), field="--real"),
    Entry("real-profile labels in metres", _real("real_labels_in_metres"), field="--real"),
    Entry("real-profile label that is text", _real("real_text_label"), field="--real"),
    Entry("real-profile label NaN", _real("real_nan_label"), field="--real"),
    Entry("real-profile label inf", _real("real_inf_label"), field="--real"),
    Entry("real-profile set all NaN", _real("real_all_nan"), field="--real"),
    Entry("real-profile set of no profile", _real("real_no_profile"), field="--real"),
    Entry("real-profile npz of 4e7 NaN in 0.5 MB", _real("real_npz_bomb"), field="--real"),
    # --- item 18: sweeps
    Entry("sweep --scheduler 'not a url'",
          ("sweep", "paper-corner", "--param", "tracker.radius_mm", "--values", "1",
           "--scheduler", "not a url", "--out", "OUT"),
          field="--scheduler"),
    Entry("sweep --scheduler on port 99999",
          ("sweep", "paper-corner", "--param", "tracker.radius_mm", "--values", "1",
           "--scheduler", "tcp://127.0.0.1:99999", "--out", "OUT"),
          field="--scheduler"),
    # --- item 19: values that complete a wrong run
    naming_key("mesh tolerance 1e308 mm on pipe-on-plate",
               ("run", "pipe-on-plate", *set_args("workpiece.tolerance_mm=1e308"), "--out", "OUT")),
    naming_key("seam rotation 1e308 deg", run_set("seam.rotation_deg=[1e308,0,0]")),
    naming_key("weld at 1e6 mm/s with the axis limits raised",
               run_set("robot.velocity_max_mm_s=[1e4,1e4,1e4]",
                       "simulation.welding_speed_mm_s=1e6")),
    naming_key("axis speed limit 1e7 mm/s", run_set("robot.velocity_max_mm_s=[1e7,10,10]")),
    naming_key("sensor that never sees the seam",
               ("check", "paper-verification", *set_args("sensor.range_mm=300"))),
    # --- item 20: messages that blamed the wrong field
    naming_key("welding speed 1e-300 mm/s", run_set("simulation.welding_speed_mm_s=1e-300")),
    naming_key("frame rate 1e308 Hz", run_set("sensor.frame_rate_hz=1e308")),
    naming_key("ragged seam CSV row", run_set('seam.source="csv"', 'seam.file="ragged.csv"')),
)  # fmt: skip
