"""``seamtrack warm`` compiles a scene's kernels ahead of its run: the run that follows, in a
fresh process, compiles nothing (numba's compile notice, printed at the first cache miss, is
absent), while the same run on an empty cache says it compiles."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from seamtrack.cli.main import main
from seamtrack.simulation.compiling import MESSAGE


def _seamtrack(
    args: list[str], cache: Path, cwd: Path | None = None
) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    env.pop("SEAMTRACK_COMPILE_NOTICE", None)  # the suite turns the notice off
    return subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", *args],
        capture_output=True, text=True, env=env, timeout=600, cwd=cwd,
    )  # fmt: skip


def test_after_warm_the_run_compiles_nothing(tmp_path: Path) -> None:
    run = ["run", "paper-verification", "--set", "seam.length_mm=20", "--no-plot"]
    cold = _seamtrack([*run, "--out", str(tmp_path / "cold")], tmp_path / "cold-cache")
    assert cold.returncode == 0, cold.stderr
    assert MESSAGE in cold.stderr  # the oracle can fail: an empty cache compiles

    cache = tmp_path / "numba"
    here = tmp_path / "here"
    here.mkdir()
    warmed = _seamtrack(["warm", "paper-verification"], cache, cwd=here)
    assert warmed.returncode == 0, warmed.stderr
    assert "warmed 1 scene in" in warmed.stdout
    assert not list(here.iterdir())  # it writes no run
    after = _seamtrack([*run, "--out", str(tmp_path / "after")], cache)
    assert after.returncode == 0, after.stderr
    assert MESSAGE not in after.stderr


@pytest.mark.parametrize(
    ("argv", "field"),
    [(["warm", "no-such-scene"], "SCENE"), (["warm", "--jobs", "0"], "--jobs")],
)
def test_bad_warm_arguments_get_one_line_and_exit_2(argv, field, capsys) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"seamtrack: error: {field}") and "fix:" in err[0]


def test_a_built_in_scene_whose_extra_is_missing_is_skipped_unless_named(
    monkeypatch, capsys
) -> None:
    """Every built-in scene (no names): one whose extra is not installed is skipped and said
    so, the others warm; named, the same scene is an error of one line, exit 2."""
    import seamtrack.cli.warm as warm
    from seamtrack.errors import SeamtrackError
    from seamtrack.simulation.templates import builtin_scenes

    def fake(name: str) -> float:
        if name == "pipe-on-plate":
            raise SeamtrackError("pin is not installed", field="robot.model",
                                 fix="pip install 'seamtrack[arms]'")  # fmt: skip
        return 0.0

    monkeypatch.setattr(warm, "warm_scene", fake)
    assert main(["warm"]) == 0
    out = capsys.readouterr().out
    assert f"warmed {len(builtin_scenes()) - 1} scenes in" in out
    skipped = [line for line in out.splitlines() if "skipped:" in line]
    assert len(skipped) == 1 and skipped[0].startswith("pipe-on-plate")
    assert main(["warm", "pipe-on-plate"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(err) == 1 and "seamtrack[arms]" in err[0]
