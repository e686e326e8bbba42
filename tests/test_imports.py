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
