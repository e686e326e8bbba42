"""``seamtrack bench trackers``: the paper's algorithms against the trajectory tracker on real
geometry, the comparison table of docs/trackers.md.

The same runs as ``seamtrack compare paper-v-groove --trackers I,II,trajectory --set
simulation.welding_speed_mm_s=V`` for V = 5 and 20 mm/s: a sweep over the whole ``[tracker]``
table, the scene's own tracker with its parameters and the others with their defaults. Writes
``trackers.json`` (``machine``, ``command``, ``columns`` and one row per speed and tracker) and
``trackers.md``, the table :func:`trackers_table` renders from the JSON (docs/figures.py
renders the docs' copy from the committed JSON with the same function, and a test holds the
two equal).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info

SCENE = "paper-v-groove"
SPEEDS_MM_S = (5.0, 20.0)
TRACKERS = ("I", "II", "trajectory")
COLUMNS = (
    "speed_mm_s",
    "tracker",
    "status",
    "stop_cause",
    "max_error_mm",
    "min_error_mm",
    "rms_error_mm",
    "mean_speed_mm_s",
    "completed_fraction",
)
#: ``--quick``: the part cut to 60 mm (a smoke run, not the docs' figures).
QUICK_OVERRIDES: dict[str, Any] = {"workpiece.params.seam_length_mm": 60.0}


def tracker_values(scene: str, overrides: dict[str, Any], names: tuple[str, ...]) -> list[dict]:
    """The ``[tracker]`` tables compared: the scene's own tracker keeps its parameters."""
    from seamtrack.control.registry import ALIASES
    from seamtrack.simulation.scene import load_scene

    own = load_scene(scene, overrides).config.tracker
    own_name = ALIASES.get(own.name, own.name)
    return [
        own.model_dump(exclude_none=True) if ALIASES.get(name, name) == own_name else {"name": name}
        for name in names
    ]


def bench_trackers(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """Run the comparison and write ``trackers.json`` and ``trackers.md`` into ``out_dir``."""
    from seamtrack.batch.sweep import run_sweep

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    base = dict(QUICK_OVERRIDES) if quick else {}
    rows = []
    for speed in SPEEDS_MM_S:
        overrides = {**base, "simulation.welding_speed_mm_s": speed}
        values = tracker_values(SCENE, overrides, TRACKERS)
        for name, case in zip(
            TRACKERS, run_sweep(SCENE, "tracker", values, overrides=overrides), strict=True
        ):
            summary = case.get("summary") or {}
            row: dict[str, Any] = {"speed_mm_s": speed, "tracker": name}
            row.update({k: summary.get(k) for k in COLUMNS[2:]})
            if "error" in case:
                row["status"] = f"error: {case['error']}"
            rows.append(row)
    result = {
        "machine": machine_info(),
        "command": f"seamtrack compare {SCENE} --trackers {','.join(TRACKERS)} "
        "--set simulation.welding_speed_mm_s=V",
        "quick": quick,
        "columns": list(COLUMNS),
        "rows": rows,
    }
    (out / "trackers.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "trackers.md").write_text(trackers_table(result))
    return result


def _cell(value: Any) -> str:
    """A table cell: 4 significant digits, as ``seamtrack compare`` prints them."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def trackers_table(result: dict[str, Any]) -> str:
    """The markdown table of a ``trackers.json``."""
    columns = result["columns"]
    head = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    body = ["| " + " | ".join(_cell(r.get(c)) for c in columns) + " |" for r in result["rows"]]
    return "\n".join(head + body) + "\n"
