"""The ``seamtrack`` command.

Every command takes ``--set KEY=VALUE`` overrides (repeatable). Bad input prints one line per
problem, ``seamtrack: error: <field>: <what>; fix: <how>``, and exits with code 2.
"""

from __future__ import annotations

import argparse
import errno
import functools
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from seamtrack._version import __version__
from seamtrack.cli import heat as heat_command
from seamtrack.cli import jobs
from seamtrack.cli import seams as seams_command
from seamtrack.cli import serve as serve_command
from seamtrack.cli import warm as warm_command
from seamtrack.cli.dataset import add_dataset_parser
from seamtrack.cli.parsing import (
    QUIET_HELP,
    SCENE_HELP,
    add_at_argument,
    add_command,
    add_workers_arguments,
)
from seamtrack.cli.recording import (
    EXTRACTORS_ACTIONS,
    add_record_argument,
    add_recording_arguments,
    record_epoch_ns,
)
from seamtrack.cli.tables import print_table
from seamtrack.errors import OutputError, PluginRuntimeError, SceneError, SeamtrackError
from seamtrack.simulation.compiling import announce_compiling, announce_wanted

EXIT_USAGE = 2


def _overrides(args: argparse.Namespace) -> list[str]:
    return list(getattr(args, "set", None) or [])


_progress_wanted = jobs.progress_wanted


# --------------------------------------------------------------------------- commands
def _run_pictures(result: Any, parts: Any, stage: Path) -> None:
    """error.png, and with ``[distortion]`` distortion.png (the seam moving through the run)."""
    from seamtrack.viz.plots import plot_run

    plot_run(result, stage / "error.png")
    if parts.moving is not None:
        from seamtrack.viz.distortion import plot_seam_motion

        seam = parts.moving.seam
        end_s = float(result.summary["sim_time_s"])
        plot_seam_motion(parts.moving.motion, seam.length_mm, end_s, stage / "distortion.png")


def cmd_run(args: argparse.Namespace) -> int:
    from seamtrack.cli.signals import stop_on_signals

    with stop_on_signals() as stop:  # SIGINT, SIGTERM: stop between frames (cli/signals.py)
        return _run(args, stop)


def _run(args: argparse.Namespace, stop: Any) -> int:
    from seamtrack.cli.signals import exit_code
    from seamtrack.io.output import check_fresh, write_run
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    scene = load_scene(args.scene, _overrides(args))
    out = Path(args.out) if args.out else Path("runs") / scene.name
    # fail before the run, not after it (and create nothing yet); never mix two runs. The
    # default runs/<scene> is seamtrack's own: an earlier run there is replaced whole.
    replace = check_fresh(out, args.force or not args.out)
    epoch_ns = record_epoch_ns(args.record_epoch, args.record)
    if scene.config.passes is not None:
        return jobs.run_job_command(args, scene, out, stop, replace)
    if args.weldx:
        from seamtrack.io.weldx_file import check_weldx_target, write_weldx

        check_weldx_target(args.weldx)
    if args.record:  # the ros extra, imported only for a recording
        from seamtrack.cli.recording import check_record, recorded_run

        check_record(args.record, args.force)
    parts = build_parts(scene)
    if stop.requested:  # before the loop began: nothing was simulated, nothing is written
        print(f"seamtrack: {stop.reason} before the run began; nothing written", file=sys.stderr)
        return exit_code(stop)
    if args.record:
        result = recorded_run(args.record, scene, parts, _progress_wanted(args), stop, epoch_ns)
    else:
        result = run(parts, progress=_progress_wanted(args), stop=stop)
    write_run(
        result,
        out,
        scene.to_toml(),
        scene.config.simulation.trace_period_s,
        extra=None if args.no_plot else lambda stage: _run_pictures(result, parts, stage),
        replace=replace,
    )
    if args.weldx:
        write_weldx(result, scene, parts, args.weldx, scene.config.simulation.trace_period_s)
    if stop.requested:  # one line, whatever --quiet says; no render of a stopped run
        when = f"stopped at t = {result.summary['sim_time_s']:.2f} s"
        print(
            f"seamtrack: {stop.reason}; "
            + (when if result.status == "interrupted" else "after the run ended")
            + f" (status {result.status}); wrote {out}"
            + (f" and {args.record}" if args.record else "")
            + (f" and {args.weldx}" if args.weldx else ""),
            file=sys.stderr,
        )
        return exit_code(stop)
    if not args.quiet:
        print_table(list(result.summary.items()), f"seamtrack run {scene.name}")
        print(
            f"wrote {out}/summary.json, trace.csv, frames.csv, scene.toml"
            + ("" if args.no_plot else ", error.png")
            + ("" if args.no_plot or parts.moving is None else ", distortion.png")
            + (f"; and {args.weldx}" if args.weldx else "")
            + (f"; and {args.record}" if args.record else "")
        )
    if args.render:
        from seamtrack.viz.run import render_run

        paths = render_run(scene, result, out, progress=_progress_wanted(args))
        if not args.quiet:
            print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    from seamtrack.viz.run import view_command

    path = view_command(args.scene, args.at, args.out, overrides=_overrides(args))
    print(f"wrote {path}")
    return 0


def cmd_extractors(args: argparse.Namespace) -> int:
    if args.action == "list":
        from seamtrack.features.extractors import available_extractors

        for name in available_extractors():
            print(name)
        return 0
    from seamtrack.bench.extractors import bench_extractors
    from seamtrack.io.output import new_dir

    if args.real is not None or args.action == "import":  # real scans: sets or recordings
        from seamtrack.cli.recording import extractors_real

        return extractors_real(args, _progress_wanted(args))
    with new_dir(args.out) as out:
        bench_extractors(out, quick=args.quick, progress=_progress_wanted(args))
    print((out / "extractors.md").read_text(), end="")
    print("\nv-groove against its included angle (real-sensor artefacts):")
    print((out / "extractors_angles.md").read_text(), end="")
    print(
        f"wrote {out}/extractors.csv, .md, .json, extractors_angles.md, "
        "extractors_error_vs_noise.png"
    )
    return 0


def cmd_cache(args: argparse.Namespace) -> int:
    from seamtrack.workpiece.loader import cache_dir, clear_cache

    if args.action == "clear":
        print(f"removed {clear_cache()} cache entries from {cache_dir()}")
    else:
        print(cache_dir())
    return 0


def cmd_init(args: argparse.Namespace) -> int:
    from seamtrack.simulation.templates import builtin_scenes

    scenes = builtin_scenes()
    if args.list:
        width = max(len(n) for n in scenes)
        for name, description in scenes.items():
            print(f"{name:<{width}}  {description}")
        return 0
    from seamtrack.simulation.scene import scene_text

    name = args.template or "paper-verification"
    text, _ = scene_text(name) if name in scenes else (None, None)
    if text is None:
        raise SceneError(
            f"no template {name!r}",
            field="TEMPLATE",
            fix=f"use one of {', '.join(scenes)} (seamtrack init --list)",
        )
    target = Path(args.output or f"{name}.toml")
    if target.exists() and not args.force:
        raise OutputError(
            f"{str(target)!r} exists",
            field="-o",
            fix="choose another name or pass --force to overwrite",
        )
    from seamtrack.simulation.scene import load_scene
    from seamtrack.simulation.scene_help import commented_scene

    lines = text.splitlines()
    opening = next((i for i, line in enumerate(lines) if not line.startswith("#")), len(lines))
    header = "\n".join(lines[:opening])  # the template's opening comment
    # every key of the resolved scene, each commented (the overrides validated before writing)
    text = commented_scene(load_scene(name, _overrides(args)), header)
    try:
        target.write_text(text)
    except OSError as exc:
        raise OutputError(
            f"cannot write {str(target)!r}: {exc.strerror}",
            field="-o",
            fix="choose a writable path",
        ) from None
    print(f"wrote {target} (edit it, then: seamtrack check {target})")
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    from seamtrack.geometry.frames import make as make_pose
    from seamtrack.simulation.assemble import build_parts, planned_tcp_poses
    from seamtrack.simulation.checks import check_seam_in_view
    from seamtrack.simulation.countermeasures import describe as describe_countermeasures
    from seamtrack.simulation.robots import is_arm
    from seamtrack.simulation.scene import load_scene

    scene = load_scene(args.scene, _overrides(args))
    parts = build_parts(scene)
    c = scene.config
    settings = parts.settings
    seam = parts.seam
    robot = parts.robot
    start_joints = parts.start_joints  # an arm's, planned; a gantry's are its axis positions
    if start_joints is None:
        start_joints = robot.joints_for_tool(make_pose(translation=parts.tcp_start_world))
    start_pose = robot.T_world_sensor(start_joints)
    first = parts.sense(start_pose, 0.0)
    path = planned_tcp_poses(seam.length_mm, parts.tool_program, robot, is_arm(c))
    assert parts.sensor is not None
    in_view = check_seam_in_view(path @ robot.T_tcp_sensor, parts.sensor, seam)
    rows: list[tuple[str, Any]] = [
        ("scene", scene.name),
        ("mode", c.sensor.mode),
        ("seam points", len(seam.points)),
        ("seam length (mm)", seam.length_mm),
        ("tracker", c.tracker.name),
        ("welding speed (mm/s)", settings.welding_speed_mm_s),
        ("nominal weld time (s)", seam.length_mm / settings.welding_speed_mm_s),
        ("frame period (s)", settings.frame_period_s),
        ("travel per frame (mm)", settings.welding_speed_mm_s * settings.frame_period_s),
        ("control period (s)", parts.robot.control_period_s),
        ("end tolerance (mm)", settings.end_tolerance_mm),
        ("time limit (s)", settings.time_limit_s),
        ("seam seen at start", bool(first) or first.reason),
        ("seam in view along the path", f"from {in_view} of {len(path)} poses 5 mm apart"),
        ("sensor mount", _mount_text(c, parts.mount)),
        ("extractor", parts.extractor_name if c.sensor.mode == "mesh" else "none (seam mode)"),
        ("sensor resolution (mm)", parts.sensor_resolution_mm),
        ("countermeasures", describe_countermeasures(c)),
    ]
    if c.passes is not None:
        rows += jobs.check_rows(c, parts)
    print_table(rows, f"{scene.name}: valid")
    return 0


def _mount_text(c: Any, mount: Any) -> str:
    """Where the sensor sits, for ``check``: the seam's own mount as the mount says it, else the
    values the scene gives (not the keys' names)."""
    if mount is not None and mount.from_seam:
        return str(mount.describe())
    tool = c.robot.tool
    if tool.sensor_xyz_mm is not None or tool.sensor_rpy_deg is not None:
        return (
            f"robot.tool: sensor_xyz_mm {tool.sensor_xyz_mm}, sensor_rpy_deg {tool.sensor_rpy_deg}"
        )
    rotation = c.sensor.mount_rotation_deg or (0.0, 0.0, 0.0)
    return f"turned {[float(a) for a in rotation]} deg (sensor.mount_rotation_deg)"


def cmd_sensor(args: argparse.Namespace) -> int:
    from seamtrack.cli.sensors import sensor_command

    return sensor_command(args.preset, list_all=args.list, as_json=args.json,
                          overrides=_overrides(args))  # fmt: skip


def cmd_sweep(args: argparse.Namespace) -> int:
    from seamtrack.batch.sweep import (
        markdown_table,
        parse_values,
        run_sweep,
        seam_labels,
        summarize,
        write_sweep,
    )

    values = parse_values(args.values)
    if args.seeds < 0:
        raise SceneError(f"{args.seeds} seeds", field="--seeds", fix="give 0 (no seeds) or more")
    seeds = list(range(args.seeds)) if args.seeds else None
    from seamtrack.simulation.scene import parse_override

    overrides = dict(parse_override(o) for o in _overrides(args))
    _say_workers(args.workers, len(values) * max(1, args.seeds))
    rows = run_sweep(
        args.scene,
        args.param,
        values,
        overrides=overrides,
        seeds=seeds,
        workers=args.workers,
        scheduler=args.scheduler,
        out_dir=args.out,
        progress=_progress_wanted(args),
    )
    table = summarize(rows)
    if args.param == "workpiece.seam":  # name each found seam: id, joint type, bodies
        try:
            labels = seam_labels(args.scene, overrides)
        except SeamtrackError:  # no weldment: seams named by a joint script
            labels = {}
        for row in table:
            row["label"] = labels.get(row["value"])
    print(markdown_table(table, args.param), end="")
    if args.out:
        write_sweep(table, args.param, args.out, rows=rows)
        print(f"wrote {args.out}/results.jsonl, sweep.md, sweep.json, sweep.csv, sweep.png")
    return 0


def _say_workers(requested: Any, cases: int) -> None:
    """One line on stderr when the sweep starts fewer workers than ``--workers`` asks."""
    from seamtrack.batch.sweep import usable_workers

    if isinstance(requested, int) and requested > 1:
        _, note = usable_workers(requested, cases)
        if note:
            print(f"seamtrack: {note}", file=sys.stderr)


def cmd_compare(args: argparse.Namespace) -> int:
    """Each tracker on the same scene: a sweep over the whole ``[tracker]`` table, so the
    scene's own tracker keeps its parameters and the others run with their defaults."""
    from seamtrack.batch.sweep import markdown_table, run_sweep, summarize, write_sweep
    from seamtrack.control.registry import ALIASES
    from seamtrack.simulation.scene import load_scene, parse_override

    trackers = [t.strip() for t in args.trackers.split(",") if t.strip()]
    overrides = dict(parse_override(o) for o in _overrides(args))
    own = load_scene(args.scene, overrides).config.tracker
    own_name = ALIASES.get(own.name, own.name)
    values = [
        own.model_dump(exclude_none=True) if ALIASES.get(name, name) == own_name else {"name": name}
        for name in trackers
    ]
    _say_workers(args.workers, len(values))
    rows = run_sweep(
        args.scene,
        "tracker",
        values,
        overrides=overrides,
        workers=args.workers,
        out_dir=args.out,
        progress=_progress_wanted(args),
    )
    table = summarize(rows)
    for row, given in zip(table, dict.fromkeys(trackers), strict=False):
        row["label"] = given  # as the user named it ("I", "my.mod:Class"), not resolved
    print(markdown_table(table, "tracker"), end="")
    if args.out:
        write_sweep(table, "tracker", args.out, plot=False, rows=rows)
    return 0


def cmd_scan(args: argparse.Namespace) -> int:
    """One stripe profile at arc length S along the seam, with its seam point."""
    import numpy as np

    from seamtrack.io.output import check_writable, new_dir
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.robots import sensor_pose_at
    from seamtrack.simulation.scene import load_scene

    scene = load_scene(args.scene, _overrides(args))
    parts = build_parts(scene)
    seam = parts.seam
    if not 0.0 <= args.at <= seam.length_mm:
        raise SceneError(
            f"{args.at} mm is not on the seam (0..{seam.length_mm:.3f} mm)",
            field="--at",
            fix="give an arc length along the seam in mm",
        )
    T_world_sensor, _ = sensor_pose_at(parts.robot, parts.tool_program, args.at)
    out = Path(args.out) if args.out else Path("runs") / f"scan-{scene.name}-{args.at:g}mm.csv"
    folder = out.parent if str(out.parent) else Path(".")
    check_writable(folder)
    mesh_mode = scene.config.sensor.mode == "mesh"
    if mesh_mode:
        from seamtrack.io.profiles import write_profile_csv
        from seamtrack.viz.plots import plot_profile_png

        assert parts.scan is not None
        profile, feature = parts.scan(T_world_sensor, 0.0)
    else:
        feature = parts.sense(T_world_sensor, 0.0)
    with new_dir(folder):
        if mesh_mode:
            write_profile_csv(profile, out)
            plot_profile_png(profile, out.with_suffix(".png"), feature=feature)
        else:
            point = feature.point_world if feature else np.full(3, np.nan)
            np.savetxt(
                out,
                np.concatenate([feature.point_laser if feature else [np.nan] * 2, point])[None],
                delimiter=",",
                comments="",
                header="y_L_mm,z_L_mm,x_mm,y_mm,z_mm",
                fmt="%.6f",
            )
    if mesh_mode:
        assert profile.valid is not None  # filled in by Profile itself
        print(f"profile: {len(profile)} rays, {int(np.count_nonzero(profile.valid))} valid points")
    if feature:
        true = seam.closest(feature.point_world)
        print(
            f"seam point: laser (y, z) = {np.round(feature.point_laser, 4).tolist()} mm, "
            f"world {np.round(feature.point_world, 4).tolist()} mm, "
            f"{true.distance_mm[0]:.4f} mm from the true seam"
        )
    else:
        print(f"no seam point: {feature.reason}")
    print(
        f"wrote {out}"
        + (f" and {out.with_suffix('.png')}" if scene.config.sensor.mode == "mesh" else "")
    )
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    from seamtrack.viz.images import render_command

    for line in render_command(args.scene, args.at, args.out, overrides=_overrides(args)):
        print(line)
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from seamtrack.bench.runner import run_benches

    run_benches(args.which, Path(args.out), quick=args.quick)
    return 0


# --------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="seamtrack",
        description="Simulate robotic weld seam tracking with a laser vision sensor.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    parser.add_argument("--version", action="version", version=f"seamtrack {__version__}")
    parser.add_argument(
        "--debug",
        action="store_true",
        help="on an error in a plugin, show seamtrack's own frames too",
    )
    add = functools.partial(add_command, sub)
    _add_scene_commands(add)
    _add_batch_commands(add)
    _add_scan_command(add)
    seams_command.add_parser(sub)
    serve_command.add_parser(sub)
    heat_command.add_parser(sub)
    warm_command.add_parser(sub)
    _add_picture_commands(add)
    _add_extractors_command(add)
    add_dataset_parser(add)
    _add_upkeep_commands(add)
    return parser


def _add_scene_commands(add: Callable[..., argparse.ArgumentParser]) -> None:
    """run, init, check, sensor: a scene run, written, checked; the sensor's geometry."""
    p = add("run", cmd_run, "run a scene and write summary.json, trace.csv, error.png")
    p.add_argument(
        "scene",
        nargs="?",
        default="paper-verification",
        help="built-in scene name or .toml file (default: paper-verification)",
    )
    p.add_argument("--out", help="output folder (default: runs/<scene name>)")
    p.add_argument(
        "--force",
        action="store_true",
        help="replace an earlier run's folder (--out) whole, and an earlier --record file",
    )
    p.add_argument("--no-plot", action="store_true", help="skip error.png")
    p.add_argument("--weldx", metavar="FILE", help="also write the run as a weldx file (.wx)")
    add_record_argument(p)
    p.add_argument(
        "--render", action="store_true", help="also write scene.png and run.gif (3D views, PyVista)"
    )
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)

    p = add("init", cmd_init, "write a complete, commented scene file from a template")
    p.add_argument("template", nargs="?", help="template name (see --list)")
    p.add_argument("-o", "--output", help="file to write (default: TEMPLATE.toml)")
    p.add_argument("--list", action="store_true", help="list the templates")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")

    p = add("check", cmd_check, "validate a scene and print derived values")
    p.add_argument("scene", help=SCENE_HELP)

    p = add("sensor", cmd_sensor, "sensor geometry and specs, both ways (Eq. 4-8)")
    p.add_argument("--preset", default="paper", help="sensor preset (see --list; default paper)")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--list", action="store_true", help="list the presets")


def _add_batch_commands(add: Callable[..., argparse.ArgumentParser]) -> None:
    """sweep, compare: a scene run many times, over values of a key or over trackers."""
    p = add("sweep", cmd_sweep, "run a scene over values of one key")
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--param", required=True, help="dotted scene key, e.g. tracker.radius_mm")
    p.add_argument(
        "--values",
        required=True,
        help="comma-separated values (with --param workpiece.seam, 'all': every seam found)",
    )
    p.add_argument(
        "--seeds",
        type=int,
        default=0,
        help="Monte Carlo: run each value with "
        "seeds 0..N-1 and report means with 95%% confidence intervals",
    )
    add_workers_arguments(p)
    p.add_argument("--out", help="folder for results.jsonl (resumable), sweep.md/json/csv/png")
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)

    p = add("compare", cmd_compare, "compare trackers on one scene")
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument(
        "--trackers",
        default="I,II,trajectory",
        help="comma-separated tracker names (I, II, trajectory, or module:Class)",
    )
    add_workers_arguments(p, scheduler=False)
    p.add_argument("--out", help="folder for results.jsonl, sweep.md/json/csv")
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)


def _add_scan_command(add: Callable[..., argparse.ArgumentParser]) -> None:
    """scan: one stripe profile and its seam point."""
    p = add("scan", cmd_scan, "one stripe profile and its seam point at an arc length")
    p.add_argument("scene", help=SCENE_HELP)
    add_at_argument(p, 0.0, "arc length along the seam, mm (default 0)")
    p.add_argument(
        "--out",
        help="CSV file (default: runs/scan-<scene>-<S>mm.csv; in mesh mode a PNG plot beside it)",
    )


def _add_picture_commands(add: Callable[..., argparse.ArgumentParser]) -> None:
    """render, view: the camera's image at an arc length; the scene in 3D."""
    p = add(
        "render",
        cmd_render,
        "the camera image at an arc length, and the profile measured from its pixels",
    )
    p.add_argument("scene", help=SCENE_HELP)
    add_at_argument(p, 0.0, "arc length along the seam, mm (default 0)")
    p.add_argument("--out", help="PNG to write (default: runs/render-<scene>-<S>mm.png)")

    p = add(
        "view",
        cmd_view,
        "render a scene (part, seam, sensor, laser fan, field of view, stripe) to a PNG",
    )
    p.add_argument("scene", help=SCENE_HELP)
    add_at_argument(p, None, "torch position along the seam, mm (default: mid-seam)")
    p.add_argument("--out", help="PNG to write (default: runs/<scene>-view.png)")


def _add_extractors_command(add: Callable[..., argparse.ArgumentParser]) -> None:
    """extractors: list, bench or import the feature extractors' profiles."""
    p = add(
        "extractors",
        cmd_extractors,
        "feature extractors: list them, or score them on synthetic profiles (bench)",
        scene=False,
    )
    p.add_argument("action", choices=["bench", "list", "import"], help=EXTRACTORS_ACTIONS)
    p.add_argument(
        "--out",
        default="bench-results/extractors",
        help="folder for the bench's CSV, table and plot (default bench-results/extractors)",
    )
    p.add_argument("--quick", action="store_true", help="fewer profiles (a smoke run)")
    p.add_argument(
        "--real",
        metavar="DIR",
        help="bench on real profiles instead: a set folder (set.json, profiles.npz, "
        "labels.csv) or a folder of them, or a recording (MCAP, ROS bag); docs/extractors.md",
    )
    add_recording_arguments(p)
    p.add_argument(
        "--force", action="store_true", help="import: replace a set imported before into --out"
    )
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)


def _add_upkeep_commands(add: Callable[..., argparse.ArgumentParser]) -> None:
    """cache, bench: the mesh cache; the benchmarks."""
    p = add("cache", cmd_cache, "the workpiece mesh cache: where it is, or clear it", scene=False)
    p.add_argument(
        "action",
        choices=["dir", "clear"],
        nargs="?",
        default="dir",
        help="dir: print the folder (default); clear: empty it",
    )

    p = add(
        "bench",
        cmd_bench,
        "benchmarks; results go to a JSON and a markdown table",
        scene=False,
    )
    p.add_argument(
        "which",
        nargs="?",
        default="all",
        help="raycast, extractors, mesh, loop, tradeoff, sweep, scaling, failures, camera, "
        "dataset, multipass, gym, bridge, trackers, paper, firstrun, weldments, stability, "
        "arc, distortion, beads, or all",
    )
    p.add_argument("--out", default="bench-results", help="folder for the results")
    p.add_argument("--quick", action="store_true", help="fewer repeats (a smoke run)")


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if announce_wanted(args.command, bool(getattr(args, "quiet", False))):
            with announce_compiling():
                return int(args.fn(args))
        return int(args.fn(args))
    except SeamtrackError as exc:
        for line in str(exc).splitlines():
            print(f"seamtrack: error: {line}", file=sys.stderr)
        if isinstance(exc, PluginRuntimeError):
            print(exc.user_frames(all_frames=args.debug), end="", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("seamtrack: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:
        if exc.errno not in _DISK_FULL:
            raise
        where = f" writing {exc.filename}" if exc.filename else ""
        print(
            f"seamtrack: error: --out: the disk is full{where} ({exc.strerror}); nothing "
            "half-written is kept; fix: free some space on that disk, or give --out on another "
            "(seamtrack dataset keeps its finished chunks and resumes from them)",
            file=sys.stderr,
        )
        return EXIT_USAGE


#: The errors of a disk (or a quota) with no room left.
_DISK_FULL = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG}


if __name__ == "__main__":
    sys.exit(main())
