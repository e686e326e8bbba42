"""Bad inputs for the heat of the weld (issue 39): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. The heat input is ``thermal_efficiency * U * I`` from
``[process]``; an efficiency above 1 would put more heat into the plate than the arc makes.
The job is ``multipass-v-groove`` cut to a 20 mm seam; the scene is refused before anything
runs. ``seamtrack heat`` asked at a zero or negative speed, at the source itself (where the field
is infinite), or with an efficiency above 1, says so naming the option.
"""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import Entry, naming_key, run_args

#: Files written into the workspace (none here).
FILES: dict[str, bytes] = {}

#: Files made when the workspace is (none here).
GENERATED: dict[str, Any] = {}

JOB = ("multipass-v-groove", "--set", "workpiece.params.seam_length_mm=20.0")
#: The distorting butt joint cut to a 20 mm seam with one tack at its middle: refused before it
#: runs (the travel speed, the tacks and clamps along the seam, the arc's efficiency).
BUTT = ("butt-distortion", "--set", "workpiece.params.seam_length_mm=20.0",
        "--set", "distortion.tacks=[{position_mm = 10.0}]")  # fmt: skip


def _job(pair: str) -> tuple[str, ...]:
    return run_args(*JOB, "--set", pair)


def _butt(pair: str) -> tuple[str, ...]:
    return run_args(*BUTT, "--set", pair)


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
    naming_key("heat thermal efficiency above 1", _job("process.thermal_efficiency=1.2")),
    naming_key("heat thermal efficiency 0", _job("process.thermal_efficiency=0.0")),
    naming_key("distortion run at zero speed", _butt("simulation.welding_speed_mm_s=0.0")),
    naming_key("distortion run at a negative speed", _butt("simulation.welding_speed_mm_s=-3.0")),
    Entry("distortion tack outside the seam", _butt("distortion.tacks=[{position_mm = 25.0}]"),
          field="distortion.tacks[0].position_mm"),
    Entry("distortion tack before the seam", _butt("distortion.tacks=[{position_mm = -1.0}]"),
          field="distortion.tacks[0].position_mm"),
    Entry("distortion clamp outside the seam", _butt("distortion.clamps=[{position_mm = 40.0}]"),
          field="distortion.clamps[0].position_mm"),
    naming_key("distortion efficiency above 1", _butt("process.thermal_efficiency=1.2")),
)  # fmt: skip
