"""The CLI's ROS 2 parts: ``run --record run.mcap``, and real scans from a recording
(``extractors bench --real run.mcap``, ``extractors import``). The ``ros`` extra's libraries are
imported only when one of these is asked for."""

from __future__ import annotations

import argparse
import decimal
import sys
import time
from pathlib import Path
from typing import Any

from seamtrack.errors import SeamtrackError

EXTRACTORS_ACTIONS = "list them, run the bench, or import a recording's profiles (--real) to --out"


def add_record_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--record",
        metavar="FILE",
        help="also record every frame as ROS 2 messages in an MCAP file (Foxglove opens it; "
        "needs pip install 'seamtrack[ros]')",
    )
    p.add_argument(
        "--record-epoch",
        metavar="SECONDS",
        help="the recording's clock at the run's start: Unix time in seconds, or 'now' "
        "(default 0, 1970)",
    )


def record_epoch_ns(text: str | None, record: str | None) -> int:
    """``--record-epoch`` as integer nanoseconds (0 when not given), or a one-line error."""
    if text is None:
        return 0
    if not record:
        raise SeamtrackError(
            "--record-epoch without --record", field="--record-epoch",
            fix="add --record FILE.mcap, or drop --record-epoch",
        )  # fmt: skip
    if text.strip().lower() == "now":
        return time.time_ns()
    from seamtrack.bridge.record import MAX_EPOCH_S

    try:
        value = decimal.Decimal(text.strip())
    except decimal.InvalidOperation:
        value = decimal.Decimal("NaN")
    if not value.is_finite() or not 0 <= value <= MAX_EPOCH_S:
        raise SeamtrackError(
            f"{text!r} is not a start time", field="--record-epoch",
            fix=f"give Unix seconds from 0 to {MAX_EPOCH_S} (e.g. 1767225600 for "
            "2026-01-01), or 'now'",
        )  # fmt: skip
    return int(value * 1_000_000_000)


def add_recording_arguments(p: argparse.ArgumentParser) -> None:
    """``extractors``' options for a recording given as ``--real``."""
    p.add_argument("--topic", help="a recording's PointCloud2 profile topic (default: the one)")
    p.add_argument(
        "--labels",
        metavar="TOPIC",
        help="a recording's PointStamped label topic (default /seamtrack/seam_truth, or the "
        "only one)",
    )
    p.add_argument(
        "--joint",
        help="the joint family of a recording's profiles (default: the recording's extractor)",
    )


def check_record(path: str, force: bool = False) -> None:
    """Refuse, before the run, a missing extra or a bad target (nothing is written): an
    existing file too, unless ``force`` and it is an MCAP file (never another kind of file)."""
    from seamtrack.bridge.extra import require_ros

    require_ros("--record")
    from seamtrack.bridge.record import check_record_target

    check_record_target(path, force=force)


def recorded_run(
    path: str, scene: Any, parts: Any, progress: bool, stop: Any = None, epoch_ns: int = 0
) -> Any:
    """Run ``parts`` recording every frame into ``path`` (an MCAP file): whole when the run
    ends (any status, ``interrupted`` by ``stop`` too: up to the stop, with its error series),
    without the error series on a ``KeyboardInterrupt``, nothing when the run fails."""
    from seamtrack.bridge.frames import observe
    from seamtrack.bridge.record import Recorder
    from seamtrack.simulation.loop import run

    recorder = Recorder(path, parts, scene, epoch_ns=epoch_ns)
    try:
        result = run(observe(parts, recorder), progress=progress, stop=stop)
    except KeyboardInterrupt:
        recorder.finish(None)
        print(f"seamtrack: stopped; wrote {path} up to the stop", file=sys.stderr)
        raise
    except BaseException:
        recorder.discard()
        raise
    recorder.finish(result, scene.config.simulation.trace_period_s)
    return result


def extractors_real(args: argparse.Namespace, progress: bool) -> int:
    """``extractors bench --real SETS_OR_RECORDING`` and ``extractors import --real RECORDING
    --out DIR`` (a recording's profiles in the real-data layout)."""
    from seamtrack.bench.extractors import bench_real, load_real_sets
    from seamtrack.io.output import check_fresh, check_writable, new_dir

    recording = {"topic": args.topic, "labels": args.labels, "joint": args.joint}
    if args.real is None:
        raise SeamtrackError(
            "import needs a recording", field="--real", fix="give --real run.mcap (or a bag)"
        )
    if args.action == "import":
        from seamtrack.bridge.extra import is_recording

        if not is_recording(args.real):
            raise SeamtrackError(
                f"{args.real!r} is not a recording", field="--real",
                fix="give an .mcap file or a ROS bag (a set folder needs no import)",
            )  # fmt: skip
        out = check_writable(args.out)
        replace = check_fresh(out, args.force)
        (found,) = load_real_sets(args.real, **recording)  # refused before anything is written
        from seamtrack.bridge.importer import read_scans, write_real_set

        scans = read_scans(args.real, args.topic, args.labels, joint=found.joint)
        before = _stamps(Path(out))
        write_real_set(scans, out, joint=found.joint, replace=replace)
        labelled = "with labels" if found.labels is not None else "without labels"
        print(
            f"wrote {Path(out)}/{_written(Path(out), before)}: {len(found.profiles)} profiles, "
            f"{labelled}"
        )
        return 0
    load_real_sets(args.real, **recording)  # a bad input is refused before any writing
    with new_dir(args.out) as out:
        bench_real(args.real, out, progress=progress, **recording)
    print((out / "extractors_real.md").read_text(), end="")
    print(f"wrote {out}/{_written(out, {})}")
    return 0


def _stamps(folder: Path) -> dict[str, tuple[int, int]]:
    """Each file in ``folder`` (not below) by name -> (mtime in ns, size): what was there."""
    if not folder.is_dir():
        return {}
    return {
        f.name: (f.stat().st_mtime_ns, f.stat().st_size) for f in folder.iterdir() if f.is_file()
    }


def _written(folder: Path, before: dict[str, tuple[int, int]]) -> str:
    """The files of ``folder`` new or changed since ``before`` (:func:`_stamps`), by name."""
    now = _stamps(folder)
    return ", ".join(sorted(name for name, stamp in now.items() if before.get(name) != stamp))
