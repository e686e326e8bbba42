"""Bad inputs for the arc in profile mode (issue 38): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`. Each is ``v-groove-arc-profile`` with one key changed,
refused before anything runs: a negative current, a look-ahead that puts the laser line under
the torch's nozzle, the image model on a sensor that forms no image, the arc in seam mode.
"""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import Entry, naming_key, run_args

#: Files written into the workspace (none here).
FILES: dict[str, bytes] = {}

#: Files made when the workspace is (none here).
GENERATED: dict[str, Any] = {}


def _run(pair: str) -> tuple[str, ...]:
    return run_args("v-groove-arc-profile", "--set", pair)


ENTRIES: tuple[Entry, ...] = (
    naming_key("arc profile model, negative current", _run("arc.current_a=-250.0")),
    naming_key("arc profile model, stripe under the torch", _run("sensor.look_ahead_mm=5.0")),
    naming_key("arc image model without an image", _run('arc.model="image"')),
    Entry("arc in seam mode", _run('sensor.mode="seam"'), field="arc.model"),
)
