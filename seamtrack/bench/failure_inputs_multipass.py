"""Bad inputs for multi-pass jobs (``[process]``, ``[passes]``, ``[planner]``): entries of the
catalogue in :mod:`seamtrack.bench.failure_inputs`, with the planner plugins they need.

The job is ``multipass-v-groove`` cut to a 20 mm seam; a planner's failure shows after the
scan-only pass (a few seconds), the scene's before anything runs; none writes a thing.
"""

from __future__ import annotations

from typing import Any

from seamtrack.bench.failure_kit import Entry, naming_key, run_args, set_args

_PLANNERS = '''\
"""Planners that fail, for the bad-input catalogue."""


class PlansNothing:
    def plan(self, groove, pass_index, state):
        return None


class Raises:
    def plan(self, groove, pass_index, state):
        raise ValueError("planner bug")


class ReturnsGarbage:
    def plan(self, groove, pass_index, state):
        return {"reference": "left"}


class NoPlan:
    pass


class NeverReturns:
    def plan(self, groove, pass_index, state):
        import threading

        threading.Event().wait()  # blocks for good, without using the CPU


class TooFast:
    def plan(self, groove, pass_index, state):
        from seamtrack.control.planner import PassPlan

        return PassPlan(reference="centre", offset_mm=0.0, work_angle_rad=0.0,
                        travel_speed_mm_s=1000.0, wire_feed_mm_s=state.process.wire_feed_mm_s,
                        layer=pass_index, bead_in_layer=0)
'''

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {"bad_planners.py": _PLANNERS.encode()}

#: Files made when the workspace is (none here).
GENERATED: dict[str, Any] = {}

JOB = ("multipass-v-groove", *set_args("workpiece.params.seam_length_mm=20.0"))


def _job(*pairs: str) -> tuple[str, ...]:
    return run_args(*JOB, *set_args(*pairs))


ENTRIES: tuple[Entry, ...] = (
    naming_key("multipass wire feed 0", _job("process.wire_feed_m_min=0")),
    naming_key("multipass wire feed -2", _job("process.wire_feed_m_min=-2.0")),
    Entry("multipass bead larger than the groove",
          _job("process.wire_feed_m_min=30.0", "process.wire_diameter_mm=3.2",
               "workpiece.params.plate_thickness_mm=6.0"),
          field="process.wire_feed_m_min", quick=False),
    # issue 43 item 8: tiny process values, named (not an overflow blamed on a plugin)
    naming_key("multipass wire feed 1e-300 m/min", _job("process.wire_feed_m_min=1e-300")),
    naming_key("multipass wire diameter 1e-300 mm", _job("process.wire_diameter_mm=1e-300")),
    naming_key("multipass wire diameter 5 mm (no GMAW wire)", _job("process.wire_diameter_mm=5.0")),
    Entry("multipass override wire feed 1e-300",
          _job("passes.overrides=[{number = 1, wire_feed_m_min = 1e-300}]"),
          field="passes.overrides.0.wire_feed_m_min"),
    # item 9: plans that cannot fill the groove, refused before the run
    naming_key("multipass wire feed 0.01 m/min", _job("process.wire_feed_m_min=0.01")),
    Entry("multipass auto plan of 400 passes",
          _job("process.wire_feed_m_min=1.0", "process.wire_diameter_mm=0.5"),
          field="process.wire_feed_m_min", quick=False),
    naming_key("multipass 3 passes for a 20 mm V", _job("passes.count=3"), quick=False),
    # item 17: overrides checked like the scene, and the planner's time
    Entry("multipass override at 1000 mm/s",
          _job("passes.overrides=[{number = 1, travel_speed_mm_s = 1000.0}]"),
          field="passes.overrides.0.travel_speed_mm_s"),
    Entry("multipass override beyond the axes' reach",
          _job("process.travel_speed_max_mm_s=2000.0",
               "passes.overrides=[{number = 1, travel_speed_mm_s = 1500.0}]"),
          field="passes.overrides.0.travel_speed_mm_s"),
    Entry("multipass override of pass 99 of 16",
          _job("passes.overrides=[{number = 99, offset_mm = 0.0}]"),
          field="passes.overrides.0.number", quick=False),
    Entry("multipass override of pass 99 of 2",
          _job("passes.count=2", "passes.overrides=[{number = 99, offset_mm = 0.0}]"),
          field="passes.overrides.0.number"),
    Entry("multipass planner never returns",
          _job('planner.name="bad_planners:NeverReturns"', "passes.scan_first=false",
               "simulation.wall_time_limit_s=1.0"),
          field="planner.name", quick=False),
    Entry("multipass planner at 1000 mm/s",
          _job('planner.name="bad_planners:TooFast"', "passes.scan_first=false"),
          field="planner.name", quick=False),
    naming_key("multipass zero passes", _job("passes.count=0")),
    naming_key("multipass unknown planner", _job('planner.name="nope"')),
    naming_key("multipass planner without plan()", _job('planner.name="bad_planners:NoPlan"')),
    naming_key("multipass planner plans no bead",
               _job('planner.name="bad_planners:PlansNothing"'), quick=False),
    naming_key("multipass planner raises", _job('planner.name="bad_planners:Raises"'), quick=False),
    naming_key("multipass planner returns garbage",
               _job('planner.name="bad_planners:ReturnsGarbage"'), quick=False),
    naming_key("multipass bead offset outside the groove",
               _job("passes.overrides=[{number = 1, offset_mm = 40.0}]"), quick=False),
    Entry("multipass work angle on the gantry",
          _job("passes.overrides=[{number = 1, work_angle_deg = 10.0}]"),
          field="passes.overrides.0.work_angle_deg"),
    Entry("multipass speed window upside down",
          _job("process.travel_speed_min_mm_s=20.0", "process.travel_speed_max_mm_s=10.0"),
          field="process.travel_speed_min_mm_s"),
    naming_key("multipass wetting angle on a parabola",
               _job("process.bead.wetting_angle_deg=60.0")),
)  # fmt: skip
