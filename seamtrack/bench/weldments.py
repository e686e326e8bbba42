"""``seamtrack bench weldments``: every seam of the bracket weldment tracked, and ``seamtrack
seams`` on public STEP files (:mod:`seamtrack.bench.weldments_public`): docs/weldments.md's
tables.

The same runs as ``seamtrack sweep weldment-bracket --param workpiece.seam --values all
--workers 2`` (mesh mode, 1024 rays, 100 frames/s, 10 mm/s, the trajectory tracker). Writes
``weldments.json`` (``machine``, ``quick``, the command, its wall time and the 1-minute load
before it, one row per seam as the sweep summarises it) and ``weldments.md``, the table
:func:`weldments_table` renders from the JSON (docs/figures.py renders the docs' copy from the
committed JSON with the same function).
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info
from seamtrack.bench.weldments_public import public_rows, public_table

SCENE = "weldment-bracket"
PARAM = "workpiece.seam"
WORKERS = 2
#: ``--quick``: two seams (a smoke run, not the docs' figures).
QUICK_SEAMS = ("s1", "s7")


def bench_weldments(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """Track every seam and write ``weldments.json`` and ``weldments.md`` into ``out_dir``."""
    from seamtrack.batch.sweep import run_sweep, seam_labels, summarize

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    values = list(QUICK_SEAMS) if quick else ["all"]
    load = os.getloadavg()[0]
    start = time.perf_counter()
    cases = run_sweep(SCENE, PARAM, values, workers=WORKERS)
    wall = time.perf_counter() - start
    labels = seam_labels(SCENE, {})
    public = public_rows(quick)
    rows = summarize(cases)
    for row in rows:
        row["label"] = labels.get(row["value"], str(row["value"]))
    result = {
        "machine": machine_info(),
        "quick": quick,
        "command": f"seamtrack sweep {SCENE} --param {PARAM} --values "
        f"{','.join(values)} --workers {WORKERS}",
        "wall_s": wall,
        "load_average_before": load,
        "rows": rows,
        "public": public,
    }
    (out / "weldments.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "weldments.md").write_text(weldments_table(result) + "\n" + public_table(result))
    return result


def weldments_table(result: dict[str, Any]) -> str:
    """The sweep's table, as ``seamtrack sweep`` prints it."""
    from seamtrack.batch.sweep import markdown_table

    return markdown_table(result["rows"], PARAM)
