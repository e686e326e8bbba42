"""What the arm scenes give, and what the gantry gives on the same seams (part of ``seamtrack
bench loop``): docs/arms.md's table of runs.

Each run of :data:`OUTCOME_RUNS` once, as a user runs it: its status and how far it got, the
max error, an arm's work and travel angle errors and joint-space figures (scoring), or the one
line a refused scene answers. No time is measured here.
"""

from __future__ import annotations

from typing import Any

#: (scene, overrides, the run as docs/arms.md names it).
OUTCOME_RUNS: tuple[tuple[str, dict[str, Any], str], ...] = (
    ("pipe-saddle", {}, "`pipe-saddle`, UR10e, 10 mm/s, mesh mode"),
    (
        "pipe-saddle",
        {
            "robot.model": "cartesian",
            "robot.base_origin_mm": [-100.0, -75.0, 0.0],
            "robot.base_rotation_deg": [0.0, 0.0, 0.0],
        },
        "`pipe-saddle` on the gantry",
    ),
    ("pipe-on-plate", {}, "`pipe-on-plate`, UR10e, girth (closed seam)"),
    ("v-groove-corner-arm", {}, "`v-groove-corner-arm`, KR 16, 80 deg corner"),
    (
        "v-groove-corner",
        {"workpiece.params.corner_angle_deg": 80.0},
        "`v-groove-corner` at 80 deg on the gantry (`--set workpiece.params.corner_angle_deg=80`)",
    ),
)
#: Summary keys kept per run (those a run has).
KEYS = (
    "status",
    "completed_fraction",
    "max_error_mm",
    "max_work_angle_error_deg",
    "rms_work_angle_error_deg",
    "p95_work_angle_error_deg",
    "max_travel_angle_error_deg",
    "rms_travel_angle_error_deg",
    "p95_travel_angle_error_deg",
    "max_joint_speed_deg_s",
    "max_joint_speed_fraction",
    "max_joint_speed_joint",
    "min_joint_limit_margin_deg",
    "min_wrist_angle_deg",
    "joint_travel_deg",
    "joint_limited_ticks",
)


def arm_outcomes(quick: bool = False) -> list[dict[str, Any]]:
    """One row per run (``quick``: the first 2 simulated seconds of each, a smoke test)."""
    from seamtrack.errors import SeamtrackError
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    rows = []
    for scene, overrides, label in OUTCOME_RUNS:
        given = {**overrides, **({"simulation.time_limit_s": 2.0} if quick else {})}
        row: dict[str, Any] = {"run": label, "scene": scene, "overrides": overrides}
        try:
            summary = run(build_parts(load_scene(scene, given))).summary
        except SeamtrackError as exc:
            row.update(status="refused", field=exc.field, error=exc.message.splitlines()[0])
        else:
            row.update({k: summary[k] for k in KEYS if k in summary})
        rows.append(row)
    return rows


def _angles(r: dict[str, Any]) -> str:
    if "max_work_angle_error_deg" not in r:
        return ""
    text = (
        f"{r['max_work_angle_error_deg']:.2f} / {r['max_travel_angle_error_deg']:.1f} (RMS "
        f"{r['rms_work_angle_error_deg']:.3f} / {r['rms_travel_angle_error_deg']:.2f}, p95 "
        f"{r['p95_work_angle_error_deg']:.3f} / {r['p95_travel_angle_error_deg']:.2f})"
    )
    return text


def _joints(r: dict[str, Any]) -> str:
    if "max_joint_speed_deg_s" not in r:
        return ""
    travel = r["joint_travel_deg"]
    return (
        f"max {r['max_joint_speed_deg_s']:.0f} deg/s ({100 * r['max_joint_speed_fraction']:.0f} "
        f"% of joint {r['max_joint_speed_joint']}'s limit), wrist >= "
        f"{r['min_wrist_angle_deg']:.1f} deg, limits >= {r['min_joint_limit_margin_deg']:.0f} "
        f"deg away, joint-limited on {r['joint_limited_ticks']} ticks; joint 1 turns "
        f"{travel[0]:.0f} deg, joint 6 {travel[-1]:.0f} deg"
    )


def _status(r: dict[str, Any]) -> str:
    if r["status"] == "refused":
        return f"refused (`{r['field']}`): {r['error']}"
    return f"{r['status']} ({100 * r['completed_fraction']:.1f} %)"


def arm_outcomes_table(result: dict[str, Any]) -> str:
    """docs/arms.md's table of runs, from a ``loop.json``."""
    lines = [
        "| run | status (completed) | max error mm | work / travel angle error, max deg | joints |",
        "|---|---|---|---|---|",
    ]
    for r in result.get("arm_outcomes", []):
        error = f"{r['max_error_mm']:.3f}" if "max_error_mm" in r else ""
        lines.append(f"| {r['run']} | {_status(r)} | {error} | {_angles(r)} | {_joints(r)} |")
    return "\n".join(lines) + "\n"
