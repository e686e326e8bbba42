"""Two outputs never share a folder (issue 43, item 15): a run refuses a folder that holds an
earlier output unless ``--force``, and then replaces it whole (no old error.png, no old
pass_* folder beside the new files); a folder of the user's own files is never written into;
the default ``runs/<scene>`` is seamtrack's own, so running a scene twice just works. The
refusals themselves are catalogue entries (``seamtrack bench failures``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from seamtrack.cli.main import main
from seamtrack.errors import OutputError
from seamtrack.io.output import check_fresh, prepare_file, staged

SHORT = ["--set", "seam.length_mm=20", "-q"]


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_a_run_into_an_earlier_runs_folder_needs_force(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["run", *SHORT, "--out", str(out)]) == 0
    first = _files(out)
    assert "error.png" in first
    # the same folder again: refused, untouched
    assert main(["run", *SHORT, "--no-plot", "--out", str(out)]) == 2
    assert _files(out) == first
    # with --force: replaced whole; the earlier error.png does not stay beside the new run
    assert main(["run", *SHORT, "--no-plot", "--out", str(out), "--force"]) == 0
    second = _files(out)
    assert sorted(second) == ["frames.csv", "scene.toml", "summary.json", "trace.csv"]
    assert second["trace.csv"] == first["trace.csv"]  # the same run, written again


def test_a_folder_of_ones_own_files_is_never_written_into(tmp_path: Path) -> None:
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("hand-written\n")
    for force in ([], ["--force"]):
        assert main(["run", *SHORT, "--out", str(mine), *force]) == 2
        assert _files(mine) == {"notes.txt": b"hand-written\n"}
    empty = tmp_path / "empty"
    empty.mkdir()
    assert check_fresh(empty) is False  # an empty folder is as good as a new one


def test_the_default_folder_is_replaced_whole(tmp_path: Path, monkeypatch) -> None:
    """``seamtrack run`` twice (the README's tour) into runs/<scene>: the second run replaces
    the first, with no file of the first left."""
    monkeypatch.chdir(tmp_path)
    assert main(["run", *SHORT]) == 0
    out = tmp_path / "runs" / "paper-verification"
    assert (out / "error.png").exists()
    assert main(["run", *SHORT, "--no-plot"]) == 0
    assert not (out / "error.png").exists()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_a_job_folder_replaced_keeps_none_of_the_earlier_passes(tmp_path: Path) -> None:
    """The staging a job is written through: with ``replace`` an earlier job's pass_07 goes,
    without it the folder is refused before anything is written."""
    out = tmp_path / "job"
    (out / "pass_07").mkdir(parents=True)
    (out / "pass_07" / "summary.json").write_text("{}\n")
    (out / "job.json").write_text("{}\n")
    (out / "scene.toml").write_text("\n")
    with pytest.raises(OutputError, match="--force"):
        check_fresh(out)
    assert check_fresh(out, force=True) is True
    with staged(out, replace=True) as stage:
        (stage / "pass_01").mkdir()
        (stage / "pass_01" / "summary.json").write_text('{"status": "completed"}\n')
        (stage / "job.json").write_text('{"status": "completed"}\n')
    assert sorted(_files(out)) == ["job.json", "pass_01/summary.json"]


def test_a_file_writer_makes_its_folder_and_refuses_one_a_file_blocks(tmp_path: Path) -> None:
    """``prepare_file``: the folders of a new file are made; a file where a folder must be is
    an OutputError naming the field, before anything is written."""
    target = prepare_file(tmp_path / "a" / "b" / "plot.png", field="path")
    assert target.parent.is_dir() and not target.exists()
    (tmp_path / "blocker").write_text("mine")
    with pytest.raises(OutputError) as err:
        prepare_file(tmp_path / "blocker" / "plot.png", field="path")
    assert err.value.field == "path"
    assert (tmp_path / "blocker").read_text() == "mine"
