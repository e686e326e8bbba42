"""Bad inputs for ROS 2 recordings and imports (``run --record``, ``extractors bench --real``
on an MCAP file, ``extractors import``): entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`, with the files they need."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import SHORT, Entry, run_args

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {
    "garbage.mcap": b"\x89MCAP0\r\nthis is not an MCAP file\n",
    "notes.mcap": b"a user's notes, named .mcap by mistake\n",
}


def _folder(path: Path) -> None:
    path.mkdir(parents=True, exist_ok=True)


def _recording(topics: tuple[str, ...], clouds: int) -> Callable[[Path], None]:
    """An MCAP file with ``clouds`` profiles on each PointCloud2 topic of ``topics`` and a
    clock (garbage where the ``ros`` extra is missing: its entries then name the extra)."""

    def write(path: Path) -> None:
        try:
            from seamtrack.bridge import messages as m
            from seamtrack.bridge.record import McapOut
        except ImportError:
            path.write_bytes(b"no ros extra here\n")
            return
        import numpy as np

        from seamtrack.sensing.profiles import Profile

        out = McapOut(path)
        for i in range(clouds):
            t = 0.01 * i
            profile = Profile(np.column_stack([np.linspace(-5, 5, 9), np.full(9, 100.0)]))
            out.write("/clock", m.clock(t), t)
            for topic in topics:
                out.write(topic, m.profile_cloud(profile, t), t)
        out.close()

    return write


def _truncated(path: Path) -> None:
    """A recording cut short in its middle (a copy that stopped)."""
    _recording(("/scanner/cloud",), 40)(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


#: Files made when the workspace is (name -> a function of the path).
GENERATED: dict[str, Callable[[Path], None]] = {
    "a_folder.mcap": _folder,
    "clock_only.mcap": _recording((), 3),
    "two_clouds.mcap": _recording(("/left/cloud", "/right/cloud"), 2),
    "one_cloud.mcap": _recording(("/scanner/cloud",), 2),
    "truncated.mcap": _truncated,
}


def _bench(recording: str, *extra: str) -> tuple[str, ...]:
    return ("extractors", "bench", "--real", recording, *extra, "--out", "OUT")


ENTRIES: tuple[Entry, ...] = (
    Entry("record to a .txt name", run_args(*SHORT, "--record", "run.txt"), field="--record"),
    Entry("record onto a folder", run_args(*SHORT, "--record", "a_folder.mcap"), field="--record"),
    Entry("record under a file", run_args(*SHORT, "--record", "a_file/run.mcap"), field="--record"),
    Entry(
        "record onto an earlier recording",
        run_args(*SHORT, "--record", "one_cloud.mcap"),
        field="--record",
    ),
    Entry(
        "record with --force onto a file that is not MCAP",
        run_args(*SHORT, "--record", "notes.mcap", "--force"),
        field="--record",
    ),
    Entry(
        "record epoch not a number",
        run_args(*SHORT, "--record", "new.mcap", "--record-epoch", "yesterday"),
        field="--record-epoch",
    ),
    Entry(
        "record epoch past 2038",
        run_args(*SHORT, "--record", "new.mcap", "--record-epoch", "3e9"),
        field="--record-epoch",
    ),
    Entry(
        "record epoch without --record",
        run_args(*SHORT, "--record-epoch", "0"),
        field="--record-epoch",
    ),
    Entry("bench a recording that is not MCAP", _bench("garbage.mcap"), field="--real"),
    Entry("bench a recording without profiles", _bench("clock_only.mcap"), field="--real"),
    Entry("bench a recording of two profile topics", _bench("two_clouds.mcap"), field="--real"),
    Entry(
        "bench a recording's missing topic",
        _bench("one_cloud.mcap", "--topic", "/nope"),
        field="--topic",
    ),
    Entry(
        "bench a recording's missing labels",
        _bench("one_cloud.mcap", "--labels", "/nope"),
        field="--labels",
    ),
    Entry(
        "bench a recording of joint 'weld'",
        _bench("one_cloud.mcap", "--joint", "weld"),
        field="--joint",
    ),
    Entry("bench a missing recording", _bench("nowhere.mcap"), field="--real"),
    Entry("bench a recording cut short", _bench("truncated.mcap"), field="--real"),
    Entry(
        "import a folder that is no recording",
        ("extractors", "import", "--real", "a_folder.mcap", "--out", "OUT"),
        field="--real",
    ),
    Entry("import without a recording", ("extractors", "import", "--out", "OUT"), field="--real"),
)
