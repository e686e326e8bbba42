"""Bad inputs for the heat of the weld (issue 39): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. The heat input is ``thermal_efficiency * U * I`` from
``[process]``; an efficiency above 1 would put more heat into the plate than the arc makes.
The job is ``multipass-v-groove`` cut to a 20 mm seam; the scene is refused before anything
runs.
"""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import Entry

#: Files written into the workspace (none here).
FILES: dict[str, bytes] = {}

#: Files made when the workspace is (none here).
GENERATED: dict[str, Any] = {}

JOB = ("multipass-v-groove", "--set", "workpiece.params.seam_length_mm=20.0")


def _job(pair: str) -> tuple[str, ...]:
    return ("run", *JOB, "--set", pair, "--out", "OUT")

ENTRIES: tuple[Entry, ...] = (
    Entry("heat thermal efficiency above 1",
          _job("process.thermal_efficiency=1.2"),
          field="process.thermal_efficiency"),
    Entry("heat thermal efficiency 0",
          _job("process.thermal_efficiency=0.0"),
          field="process.thermal_efficiency"),
)  # fmt: skip
