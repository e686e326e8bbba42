"""``seamtrack bench trackers``: the paper's algorithms against the trajectory tracker on real
geometry, the comparison table of docs/trackers.md.

The same runs as ``seamtrack compare paper-v-groove --trackers I,II,trajectory --set
simulation.welding_speed_mm_s=V`` for V = 5 and 20 mm/s: a sweep over the whole ``[tracker]``
table, the scene's own tracker with its parameters and the others with their defaults. Writes
``trackers.json`` (``machine``, ``command``, ``columns`` and one row per speed and tracker) and
``trackers.md``, the table :func:`trackers_table` renders from the JSON (docs/figures.py
renders the docs' copy from the committed JSON with the same function, and a test holds the
two equal).

Then the seam's end (``end_of_part``): each run of :data:`END_RUNS` once with the trajectory
tracker's end handling off (``tracker.params.end_zone_mm = 0``, ``end_of_part = false``: the
torch bridges on past the part's end) and once as the scene has it; its ``overrun_mm`` and
``stop_cause`` each time, the table :func:`end_of_part_table` renders.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info, markdown_table

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
#: The seam's end: (scene, overrides, the command a user runs).
END_RUNS: tuple[tuple[str, dict[str, Any], str], ...] = (
    (
        "paper-v-groove",
        {"workpiece.params.seam_length_mm": 60.0},
        "`seamtrack run paper-v-groove --set workpiece.params.seam_length_mm=60` (`make demo`)",
    ),
    ("v-groove-corner-arm", {}, "`seamtrack run v-groove-corner-arm` (KR 16)"),
    ("tacks-and-clamp", {}, "`seamtrack run tacks-and-clamp`"),
)
#: The tracker's end handling off: it bridges past the part's end as it would across a gap.
END_OFF: dict[str, Any] = {"tracker.params.end_zone_mm": 0.0, "tracker.params.end_of_part": False}
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
        "end_of_part": end_of_part_rows(END_RUNS[:1] if quick else END_RUNS),
        "command": f"seamtrack compare {SCENE} --trackers {','.join(TRACKERS)} "
        "--set simulation.welding_speed_mm_s=V",
        "quick": quick,
        "columns": list(COLUMNS),
        "rows": rows,
    }
    (out / "trackers.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "trackers.md").write_text(trackers_table(result) + "\n" + end_of_part_table(result))
    return result


def end_of_part_rows(runs: tuple[tuple[str, dict[str, Any], str], ...]) -> list[dict[str, Any]]:
    """Each run with the tracker's end handling off (``before``) and as the scene has it."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    rows = []
    for scene, overrides, command in runs:
        row: dict[str, Any] = {"scene": scene, "overrides": overrides, "command": command}
        for label, extra in (("before", END_OFF), ("after", {})):
            summary = run(build_parts(load_scene(scene, {**overrides, **extra}))).summary
            for key in ("status", "stop_cause", "overrun_mm"):
                row[f"{key}_{label}"] = summary.get(key)
        rows.append(row)
    return rows


def end_of_part_table(result: dict[str, Any]) -> str:
    """The seam's end: overrun with the tracker's end handling off and on (docs/trackers.md)."""
    lines = [
        "| run | overrun_mm before | after | stop_cause after | status after |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['command']} | {r['overrun_mm_before']:.2f} | {r['overrun_mm_after']:.3f} | "
        f"`{r['stop_cause_after']}` | {r['status_after']} |"
        for r in result.get("end_of_part", [])
    ]
    return "\n".join(lines) + "\n"


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
    body = ([_cell(r.get(c)) for c in columns] for r in result["rows"])
    return "\n".join(markdown_table(columns, body)) + "\n"
