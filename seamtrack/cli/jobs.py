"""``seamtrack run`` and ``seamtrack check`` of a multi-pass job (a scene with ``[passes]``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from seamtrack.cli.tables import print_table
from seamtrack.errors import SceneError


def progress_wanted(args: argparse.Namespace) -> bool:
    """Progress bars unless ``--quiet``, and only on a terminal."""
    return not getattr(args, "quiet", False) and sys.stderr.isatty()


def run_job_command(
    args: argparse.Namespace, scene: Any, out: Path, stop: Any = None, replace: bool = False
) -> int:
    """``seamtrack run`` of a scene with ``[passes]``: the multi-pass job (``stop``: a
    signal's request; the job writes its passes up to the stop; ``replace``: ``out`` holds an
    earlier output that ``--force`` replaces whole)."""
    from seamtrack.cli.signals import exit_code
    from seamtrack.io.output import write_job
    from seamtrack.multipass.job import run_job
    from seamtrack.viz.job import write_job_pictures
    from seamtrack.viz.plots import plot_run

    exports = (("--weldx", args.weldx), ("--render", args.render), ("--record", args.record))
    for flag, given in exports:
        if given:
            raise SceneError(
                "a multi-pass job writes one folder a pass; it has no single run to export",
                field=flag,
                fix=f"drop {flag}, or run one pass's scene.toml from the job's folder",
            )
    job = run_job(scene, progress=progress_wanted(args), stop=stop)
    pictures: list[str] = []
    stopped = stop is not None and stop.requested  # then the job's pictures are not drawn
    write_job(
        job,
        out,
        scene.to_toml(),
        scene.config.simulation.trace_period_s,
        extra=None
        if args.no_plot
        else lambda record, folder: plot_run(
            record.result, folder / "error.png", title=pass_title(scene.name, record)
        ),
        finish=None
        if args.no_plot or stopped
        else lambda folder: pictures.extend(
            path.name for path in write_job_pictures(job, scene, folder)
        ),
        replace=replace,
    )
    if stop is not None and stop.requested:  # one line, whatever --quiet says
        print(
            f"seamtrack: {stop.reason}; the job stopped in {job.passes[-1].name} (status "
            f"{job.status}); wrote {out}/job.json, scene.toml and {len(job.passes)} pass "
            "folders up to the stop",
            file=sys.stderr,
        )
        return exit_code(stop)
    if not args.quiet:
        rows = [
            (k, v) for k, v in job.summary.items() if k not in ("per_pass", "fusion_flagged_s_mm")
        ]
        print_table(rows, f"seamtrack run {scene.name} (multi-pass job)")
        drawn = "".join(f", {name}" for name in pictures)
        print(f"wrote {out}/job.json, scene.toml{drawn} and {len(job.passes)} pass folders")
    return 0


def pass_title(scene_name: str, record: Any) -> str:
    """A pass's error.png title: which pass of the job it shows, and its status."""
    plan = record.plan
    if plan is None:
        what = "the scan-only pass (arc off)"
    else:
        layer = f"layer {plan.layer + 1}{' (cap)' if plan.cap else ''}"
        bead = f"bead {plan.bead_in_layer + 1} of {plan.beads_in_layer}"
        what = f"{layer}, {bead} (from {plan.reference})"
    return f"{scene_name} {record.name}: {what}; status: {record.result.status}"


def check_rows(c: Any, parts: Any = None) -> list[tuple[str, Any]]:
    """``seamtrack check``'s rows for a multi-pass job: the process and the plan's frame, and
    with the scene's ``parts`` the passes the plan lays on the CAD groove (a plan that cannot
    fill the groove is refused here, as before a run)."""
    from seamtrack.simulation.process import heat_input_kj_mm, process_of

    p = process_of(c)
    v = c.simulation.welding_speed_mm_s
    assert c.passes is not None
    rows: list[tuple[str, Any]] = [("passes", c.passes.count)]
    if parts is not None:
        rows.append(("passes the plan lays (CAD groove)", planned_passes(c, parts)))
        level, warning = planned_level(c, parts)
        rows.append(("ISO 5817 level of the plan, perfectly tracked", level))
        if warning:
            print(f"warning: {warning}", file=sys.stderr)
    return rows + [
        ("planner", c.planner.name if c.planner is not None else "adaptive"),
        ("scan-only pass first", c.passes.scan_first),
        ("wire feed (mm/s)", p.wire_feed_mm_s),
        ("bead area at the nominal speed (mm^2)", float(p.bead_area_mm2(v))),
        ("bead shape", f"{p.bead_model}, w/h {p.width_to_height:.3g}"),
        ("travel speed window (mm/s)", f"{p.speed_min_mm_s:g} .. {p.speed_max_mm_s:g}"),
        ("heat input at the nominal speed (kJ/mm)", heat_input_kj_mm(c, v)),
    ]


def planned_level(c: Any, parts: Any) -> tuple[str, str]:
    """The ISO 5817 level the plan meets laid with perfect tracking on the CAD groove (the
    dry run: :func:`seamtrack.multipass.job.dry_run`, every speed within the process's
    window), and a warning (empty: none) when a requested ``passes.count`` does not meet
    level B: the beads the process lays at its limits, that many, leave the groove under
    the plates' line or the crown over the limit."""
    import numpy as np

    from seamtrack.control.planner import JobState, is_builtin, planner
    from seamtrack.multipass.job import bead_shape, dry_run
    from seamtrack.multipass.paths import STATION_SPACING_MM
    from seamtrack.simulation.process import process_of
    from seamtrack.workpiece.beads import BeadShape
    from seamtrack.workpiece.fill import FillState
    from seamtrack.workpiece.inspection import MIN_THICKNESS_MM, inspect_weld

    assert c.passes is not None
    name = c.planner.name if c.planner is not None else "adaptive"
    if not is_builtin(name):
        return "decided by the plugin as it runs", ""
    params = dict(c.planner.params) if c.planner is not None else {}
    count = c.passes.count if isinstance(c.passes.count, int) else None
    empty = FillState.from_mesh(parts.mesh, parts.seam, spacing_mm=STATION_SPACING_MM)
    state = JobState(process_of(c), count=count, reinforcement_mm=c.passes.reinforcement_mm)
    fill, _ = dry_run(empty, planner(name, **params), state, bead_shape(c, BeadShape))
    r = np.asarray(fill.reinforcement_mm())
    corners = np.asarray(fill.top_corners)
    t = c.workpiece.params.get("plate_thickness_mm") if c.workpiece is not None else None
    thickness = float(t) if t is not None else float(np.max(corners[:, :, 1].min(axis=1)
                                                         - empty.base_z.min(axis=1)))  # fmt: skip
    if thickness <= MIN_THICKNESS_MM:
        return "not judged (plate of 3 mm or less)", ""
    weld = inspect_weld(fill.s_mm, thickness_mm=thickness,
                        width_mm=np.abs(corners[:, 1, 0] - corners[:, 0, 0]),
                        excess_mm=r[:, 1], underfill_mm=-r[:, 0])  # fmt: skip
    level = weld.level or "none"
    text = (f"{level} (reinforcement {r[:, 0].min():.2f} to {r[:, 1].max():.2f} mm, "
            f"{int(np.count_nonzero(r[:, 0] < 0))} stations under the plates' line)")  # fmt: skip
    if count is None or level == "B":
        return text, ""
    return text, (
        f"passes.count = {count}: the plan laid with perfect tracking on the CAD groove meets "
        f"ISO 5817 level {level}, not B ({text.split('(', 1)[1][:-1]}): {count} beads within "
        "the process's travel speed window do not fill this groove cleanly; fix: give "
        'another passes.count, or count = "auto"'
    )


def planned_passes(c: Any, parts: Any) -> str:
    """The plan on the CAD groove, as a row of ``check``: the passes, the layers, the cap."""
    from seamtrack.multipass.job import planned_layout
    from seamtrack.multipass.paths import STATION_SPACING_MM
    from seamtrack.workpiece.fill import FillState

    fill = FillState.from_mesh(parts.mesh, parts.seam, spacing_mm=STATION_SPACING_MM)
    plan = planned_layout(fill, c)
    if plan is None:
        return "decided by the plugin as it runs"
    *fill_layers, cap = plan.beads_per_layer
    layers = ", ".join(str(n) for n in fill_layers) or "none"
    return f"{plan.passes} (fill layers of {layers} beads; a cap of {cap})"
