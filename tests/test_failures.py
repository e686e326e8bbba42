"""Every failure a clear answer: the bad-input catalogue (seamtrack.bench.failures) through the
real command line, in-process, plus what a user plugin's error shows and the CLI's own manners.

Each catalogue entry must exit 2 with exactly one ``seamtrack: error:`` line naming its field,
print no traceback and leave no output folder (``seamtrack bench failures`` runs the same
catalogue in fresh processes and also measures memory).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
from pathlib import Path

import pytest

from seamtrack._version import __version__
from seamtrack.bench.failures import CATALOGUE, Entry, Outcome, workspace
from seamtrack.cli.main import build_parser, main


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return workspace(tmp_path_factory.mktemp("catalogue"))


def _run_in_process(
    args: list[str], root: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> tuple[int, str]:
    monkeypatch.chdir(root)
    monkeypatch.syspath_prepend(str(root))
    code = main(args)
    return code, capsys.readouterr().err


def _tree(root: Path) -> dict[str, tuple[int, str]]:
    """Every folder and file under ``root``: its size and content digest (folders: -1)."""
    found: dict[str, tuple[int, str]] = {}
    for folder, dirs, files in os.walk(root):
        for name in dirs:
            found[os.path.relpath(os.path.join(folder, name), root)] = (-1, "")
        for name in files:
            path = Path(folder) / name
            data = path.read_bytes()
            found[os.path.relpath(path, root)] = (len(data), hashlib.sha256(data).hexdigest())
    return found


#: A user plugin's error line is followed by the plugin's own frames (indented lines), no more.
PLUGIN_FRAMES = "its own frames follow"


@pytest.mark.parametrize(
    "entry",
    [e if e.quick else pytest.param(e, marks=pytest.mark.slow) for e in CATALOGUE],
    ids=lambda e: e.name,
)
def test_bad_input_gets_one_line_exit_2_and_leaves_nothing(
    entry: Entry, root: Path, capfd: pytest.CaptureFixture[str], monkeypatch
) -> None:
    """The promises checked on their own terms (not with the bench's grader): exit code 2;
    on stderr one line, naming the field, with what is wrong and the fix (after a user
    plugin's error line, only that plugin's own frames), no traceback; and the workspace (the
    entry's files and output path) byte for byte as before: no output folder, no half-written
    file. capfd, not capsys: a library that prints on the C stderr (urdfdom did) is caught."""
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # Python's caches are not our writes
    out = root / f"out-{abs(hash(entry.name))}"
    args = [str(out) if a == "OUT" else a.replace("OUT/", f"{out}/") for a in entry.args]
    before = _tree(root)
    code, err = _run_in_process(args, root, capfd, monkeypatch)
    assert code == 2, err
    first, *more = err.splitlines()
    # One line: ``seamtrack: error: [<file>: ]<field>: <what is wrong>; fix: <what to do>``.
    assert first.startswith("seamtrack: error: "), err
    head, sep, fix = first.removeprefix("seamtrack: error: ").partition("; fix: ")
    assert sep and fix.strip(), first
    where = head.split(": ")  # [<file>,] <field>, <what is wrong> (which may hold ': ' too)
    assert len(where) >= 2 and any(entry.field in part for part in where[:2]), first
    if PLUGIN_FRAMES in fix:
        assert all(line.startswith(" ") for line in more), err
    else:
        assert more == [], err
    assert "Traceback" not in err
    assert _tree(root) == before
    # The bench's grader, which `seamtrack bench failures` uses, agrees.
    assert Outcome(entry.name, code, err, out.exists(), 0.0, 0.0).problems(entry.field) == []


def test_the_catalogue_covers_every_item_of_the_issue() -> None:
    """The inputs the issue lists are all in the catalogue (names are the check)."""
    names = {e.name for e in CATALOGUE}
    for needed in (
        "tracker RaisesInUpdate",
        "tracker RaisesInReset",
        "tracker ReturnsString",
        "tracker ReturnsShortTarget",
        "tracker ReturnsNaNTarget",
        "tracker ReturnsNegativeSpeed",
        "extractor RaisingExtractor",
        "extractor NaNExtractor",
        "stripe_noise range_sigma_mm=-1",
        "stripe_noise dropout_rate=2",
        "stripe_noise secondary_probability=1e9",
        "stripe_noise range_sigma_mm=inf",
        "stripe_noise speckle_correlation_rays=inf",
        "tracker.params gain_1_s=[1,2]",
        'tracker.params gain_1_s="x"',
        "binary scene file",
        "control period 1e-8 s",
        "seam step 1e-6 mm",
        "seam length 1e9 mm",
        "1e8 rays",
        "'yes' for a boolean",
        "false for a number",
        "empty scene file",
        "sweep --workers 0",
        "sweep --seeds -1",
        "compare with an unknown tracker",
        "seams of a STEP without solids",
        "seams of solids that never touch",
        "weldment scene, STEP without solids",
        "weldment scene, solids that never touch",
        "workpiece.seam naming no seam",
        "groove weldx does not define",
        "groove missing parameters",
    ):
        assert needed in names


def test_the_catalogue_covers_the_bad_inputs_of_the_heat_issue() -> None:
    """Issue 39's bad inputs (a zero or negative speed, a tack outside the seam, an efficiency
    above 1, a point inside the source's singularity), each on the command line that takes it:
    the field, the distorting run and the multi-pass job."""
    names = {e.name for e in CATALOGUE}
    for needed in (
        "heat field at zero speed",
        "heat field at a negative speed",
        "heat field at the point source",
        "heat field on the line source's axis",
        "heat field efficiency above 1",
        "heat thermal efficiency above 1",
        "distortion run at zero speed",
        "distortion run at a negative speed",
        "distortion tack outside the seam",
        "distortion tack before the seam",
        "distortion clamp outside the seam",
        "distortion efficiency above 1",
    ):
        assert needed in names


def test_a_plugin_error_shows_the_users_frames_and_debug_shows_all(
    root: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    args = [
        "run",
        "--set",
        "seam.length_mm=20",
        "--set",
        'tracker.name="bad_plugins:RaisesInUpdate"',
    ]
    code, err = _run_in_process([*args, "--out", str(root / "u1")], root, capsys, monkeypatch)
    assert code == 2
    first, *frames = err.splitlines()
    assert first.startswith("seamtrack: error: tracker.name: 'bad_plugins:RaisesInUpdate' update()")
    assert "ZeroDivisionError" in first and "t = " in first
    assert any("bad_plugins.py" in f for f in frames)
    assert not any(f"seamtrack{os.sep}simulation" in f for f in frames)
    assert not (root / "u1").exists()
    code, err = _run_in_process(
        ["--debug", *args, "--out", str(root / "u2")], root, capsys, monkeypatch
    )
    assert code == 2
    assert any(f"seamtrack{os.sep}simulation{os.sep}loop.py" in f for f in err.splitlines())


def _options(parser: argparse.ArgumentParser) -> list[tuple[str, argparse.Action]]:
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += [(f"{name} {a}", b) for a, b in _options(sub)]
        elif not isinstance(action, argparse._HelpAction):
            found.append((action.dest, action))
    return found


def test_every_cli_option_has_help_text() -> None:
    missing = [name for name, action in _options(build_parser()) if not action.help]
    assert missing == []


def test_set_is_offered_only_where_a_scene_is_read() -> None:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    with_set = {name for name, p in sub.choices.items() if any(a.dest == "set" for a in p._actions)}
    assert {"run", "check", "sweep", "compare", "scan", "view", "init"} <= with_set
    assert not with_set & {"bench", "cache", "extractors"}


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"seamtrack {__version__}"


def test_compare_labels_trackers_as_given(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        [
            "compare",
            "paper-corner",
            "--trackers",
            "I,convergence-radius",
            "--set",
            "seam.points_mm=[[0, 0, 0], [12, 0, 0], [20, 8, 0]]",
            "-q",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    rows = [line.split("|")[1].strip() for line in out.splitlines()[2:]]
    assert rows == ["I", "convergence-radius"]


def test_the_catalogue_holds_every_reproducer_of_the_robustness_issue(tmp_path) -> None:
    """Issue 23's reproducers are in the catalogue: found by what an entry runs (its command
    line and the files it reads), not by its name."""
    from seamtrack.bench.failure_inputs import workspace

    root = workspace(tmp_path)
    files = {
        str(p.relative_to(root)): p.read_bytes().decode("utf-8", "replace")
        for p in root.rglob("*")
        if p.is_file() and p.stat().st_size < 1_000_000
    }

    def runs(*needles: str) -> bool:
        """Some entry's command line, with the text of the files it names, holds every needle."""
        for entry in CATALOGUE:
            text = " ".join(entry.args)
            text += " ".join(body for name, body in files.items() if name in text)
            if all(n in text for n in needles):
                return True
        return False

    camera = (
        "f_number=1e9",
        "focal_length_mm=1e-9",
        "exposure=1e300",
        "full_well_e=1e300",
        "ambient=1e300",
        "full_well_e=1e-300",
        "read_noise_e=1e300",
        "f_number=1e4",
    )
    for value in camera:
        assert runs(f"sensor.camera.{value}"), value
    assert runs("render", "v-groove-camera", "sensor.camera.f_number=1e9")
    assert runs("dataset", "--images")
    assert runs("rows=20000", "columns=20000")
    assert runs("rows=4096", "columns=8192", "supersample=8")
    assert runs("joint_acceleration_max_deg_s2=[1,2]", 'robot.model="ur10e"')
    assert runs("joint_acceleration_max_deg_s2=[]")
    assert runs("robot.tool.sensor_xyz_mm=[1e300,0,0]")
    assert runs('robot.urdf="/dev/zero"')
    assert runs("robot.urdf", 'name="chain300"') and runs("robot.urdf", 'name="chain600"')
    for urdf in ('axis xyz="nan 0 1"', 'link name="stray"'):
        assert runs("robot.urdf", urdf), urdf
    assert runs('workpiece.params.plate_width_mm="abc"')
    assert runs("workpiece.params.plate_width_mm=true")
    assert runs("DVGroove", "alpha_1_deg=-30")
    assert runs("alpha_deg=1e300")
    assert runs("UGroove", "R_mm=50", "t_mm=10")
    assert runs("c_mm=12", "t_mm=10")
    assert runs("alpha_deg=180")
    assert runs("standoff_offset_mm = [-1000.0, 1000.0]", "lateral_offset_mm = [-1000.0, 1000.0]")
    for step in ("inside.step", "coincident.step", "tiny_pair.step"):
        assert runs("seams", step), step
