"""The first run's minute of compiling is announced on stderr, once, when stdout is not a
terminal (a log or a pipe would otherwise get a minute of silence)."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import numba

from seamtrack.simulation.compiling import MESSAGE, announce_compiling, announce_wanted


def test_a_compilation_is_announced_once_and_a_compiled_call_not_at_all() -> None:
    @numba.njit(cache=False)
    def twice(x: float) -> float:
        return 2.0 * x

    @numba.njit(cache=False)
    def thrice(x: float) -> float:
        return 3.0 * x

    stream = io.StringIO()
    with announce_compiling(stream):
        assert twice(2.0) == 4.0  # compiles
        assert thrice(2.0) == 6.0  # compiles: no second line
        assert twice(3.0) == 6.0  # compiled already
    assert stream.getvalue() == MESSAGE + "\n"
    stream = io.StringIO()
    with announce_compiling(stream):
        assert twice(5.0) == 10.0  # nothing compiles: nothing said
    assert stream.getvalue() == ""


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_notice_is_wanted_off_a_terminal_unless_quiet(monkeypatch) -> None:
    monkeypatch.delenv("SEAMTRACK_COMPILE_NOTICE", raising=False)
    assert announce_wanted("run", quiet=False, stdout=io.StringIO())
    assert not announce_wanted("run", quiet=False, stdout=_Tty())  # the bars show progress
    assert not announce_wanted("run", quiet=True, stdout=io.StringIO())
    assert not announce_wanted("init", quiet=False, stdout=io.StringIO())
    monkeypatch.setenv("SEAMTRACK_COMPILE_NOTICE", "0")
    assert not announce_wanted("run", quiet=False, stdout=io.StringIO())


def test_a_cold_run_into_a_pipe_says_it_compiles(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}  # an empty cache
    env.pop("SEAMTRACK_COMPILE_NOTICE", None)  # the suite turns it off
    res = subprocess.run(
        [sys.executable, "-m", "seamtrack.cli", "run", "paper-verification",
         "--set", "seam.length_mm=20", "--out", str(tmp_path / "run"), "--no-plot"],
        capture_output=True, text=True, env=env, timeout=600,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert res.stderr.splitlines().count(MESSAGE) == 1
    assert MESSAGE not in res.stdout
