"""Bad inputs for the heat of the weld (issue 39): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. The heat input is ``thermal_efficiency * U * I`` from
``[process]``; an efficiency above 1 would put more heat into the plate than the arc makes.
The job is ``multipass-v-groove`` cut to a 20 mm seam; the scene is refused before anything
runs. ``seamtrack heat`` asked at a zero or negative speed, at the source itself (where the field
is infinite), or with an efficiency above 1, says so naming the option.
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


#: ``seamtrack heat``: the field asked at a point, 5 mm beside the arc unless said.
FIELD = ("heat", "--at", "0,5,0", "--speed-mm-s", "5")

ENTRIES: tuple[Entry, ...] = (
    Entry("heat field at zero speed", ("heat", "--at", "0,5,0", "--speed-mm-s", "0"),
          field="--speed-mm-s"),
    Entry("heat field at a negative speed", ("heat", "--at", "0,5,0", "--speed-mm-s=-4"),
          field="--speed-mm-s"),
    Entry("heat field at the point source", ("heat", "--at", "0,0,0", "--speed-mm-s", "5"),
          field="--at"),
    Entry("heat field on the line source's axis",
          ("heat", "--at", "0,0,1.5", "--speed-mm-s", "5", "--thickness-mm", "3"), field="--at"),
    Entry("heat field efficiency above 1", (*FIELD, "--thermal-efficiency", "1.2"),
          field="--thermal-efficiency"),
    Entry("heat field zero thickness", (*FIELD, "--thickness-mm", "0"), field="--thickness-mm"),
    Entry("heat field unknown material", (*FIELD, "--material", "copper"), field="--material"),
    Entry("heat thermal efficiency above 1",
          _job("process.thermal_efficiency=1.2"),
          field="process.thermal_efficiency"),
    Entry("heat thermal efficiency 0",
          _job("process.thermal_efficiency=0.0"),
          field="process.thermal_efficiency"),
)  # fmt: skip
