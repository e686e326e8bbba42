"""A scene models only what it needs: a seam-mode run imports no CAD, ray casting or 3D view."""

from __future__ import annotations

import subprocess
import sys


def test_seam_mode_run_imports_no_heavy_dependency() -> None:
    code = (
        "import sys, seamtrack as st\n"
        "r = st.simulate(st.load_scene('paper-verification', {'seam.length_mm': 20}))\n"
        "assert r.status == 'completed', r.summary\n"
        "heavy = [m for m in ('cadquery', 'OCP', 'embreex', 'pyvista', 'vtk', 'trimesh',"
        " 'matplotlib') if m in sys.modules]\n"
        "print(','.join(heavy))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == ""


def test_import_seamtrack_is_light() -> None:
    code = "import sys, seamtrack; print(len([m for m in sys.modules if 'numpy' in m]))"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.stdout.strip() == "0"


def test_help_and_the_scene_list_import_nothing_heavy() -> None:
    """`seamtrack --help` and `seamtrack init --list` answer at once: they load neither numpy,
    numba, SciPy nor pydantic (what made `init --list` take 3-4 s). The time itself is the
    bench's to measure; this checks its cause."""
    code = (
        "import sys, contextlib, io\n"
        "from seamtrack.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
        "    assert main(['init', '--list']) == 0\n"
        "    try:\n"
        "        main(['--help'])\n"
        "    except SystemExit as stop:\n"
        "        assert stop.code == 0\n"
        "assert 'paper-verification' in out.getvalue() and 'usage:' in out.getvalue()\n"
        "print(','.join(m for m in ('numpy', 'numba', 'scipy', 'pydantic') if m in sys.modules))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == ""
