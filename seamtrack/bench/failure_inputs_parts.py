"""Bad inputs for weldments (seams between bodies) and weldx grooves: entries of the catalogue in
:mod:`seamtrack.bench.failure_inputs`, with the files they need.

Weldments: STEP assemblies made with CadQuery when the workspace is (a box inside another, two
coincident boxes, cubes too small for the shortest seam, two plates facing each other across a
rod), each refused by ``seamtrack seams`` with what is really wrong. Blocks in a row, which once
gave seams through the middle block, are valid parts: ``tests/test_weldment_sight.py`` checks
their seams. Grooves: every ISO 9692-1 type's fields out of the range the standard means, and
the groove part's own parameters, on ``seamtrack run weldx-v-groove``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from seamtrack.bench.failure_kit import Entry, naming_key, run_args, seams_of, set_args

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {}


def _assembly(path: Path, boxes: Mapping[str, tuple[float, ...]], rod: bool = False) -> None:
    """A STEP assembly of named boxes (x, y, z, dx, dy, dz); ``rod``: and a 1 mm rod along y
    at x = 1.5, z = 0.5, 4 mm long."""
    import cadquery as cq

    assembly = cq.Assembly(name=path.stem)
    for name, (x, y, z, dx, dy, dz) in boxes.items():
        assembly.add(cq.Solid.makeBox(dx, dy, dz, cq.Vector(x, y, z)), name=name)
    if rod:
        axis = cq.Vector(0, 1, 0)
        assembly.add(cq.Solid.makeCylinder(0.5, 4, cq.Vector(1.5, 0, 0.5), axis), name="rod")
    assembly.export(str(path), exportType="STEP")


def _row(size: float, n: int) -> Any:
    boxes = {f"c{i}": (i * size, 0.0, 0.0, size, size, size) for i in range(n)}
    return lambda path: _assembly(path, boxes)


#: Files made when the workspace is (CadQuery imported then, not with this module).
GENERATED: dict[str, Any] = {
    "inside.step": lambda p: _assembly(
        p, {"outer": (0, 0, 0, 10, 10, 10), "inner": (4, 4, 4, 2, 2, 2)}
    ),
    "corner_inside.step": lambda p: _assembly(
        p, {"outer": (0, 0, 0, 10, 10, 10), "corner": (0, 0, 0, 2, 2, 2)}
    ),
    "coincident.step": lambda p: _assembly(
        p, {"a": (0, 0, 0, 10, 10, 10), "b": (0, 0, 0, 10, 10, 10)}
    ),
    "overlap.step": lambda p: _assembly(
        p, {"a": (0, 0, 0, 10, 10, 10), "b": (5, 0, 0, 10, 10, 10)}
    ),
    "tiny_pair.step": _row(0.01, 2),
    "tiny_row.step": _row(0.1, 3),
    "rod_in_gap.step": lambda p: _assembly(
        p, {"a": (0, 0, 0, 1, 4, 1), "b": (2, 0, 0, 1, 4, 1)}, rod=True
    ),
}

#: weldx-v-groove cut to 20 mm.
_GROOVE = ("weldx-v-groove", "--set", "workpiece.params.seam_length_mm=20")


def _groove(field: str, *pairs: str, name: str = "") -> Entry:
    """A groove run with the given ``--set`` pairs, its error naming ``field``."""
    return Entry(
        name or f"groove {' '.join(pairs)}", run_args(*_GROOVE, *set_args(*pairs)), field=field
    )


def _table(groove: str, field: str, name: str) -> Entry:
    return _groove(f"workpiece.groove.{field}", f"workpiece.groove={{{groove}}}", name=name)


WELDMENTS: tuple[Entry, ...] = (
    seams_of("seams, a box inside another", "inside.step"),
    seams_of("seams, a box inside another at its corner", "corner_inside.step"),
    seams_of("seams, two coincident boxes", "coincident.step"),
    seams_of("seams, two boxes overlapping by half", "overlap.step"),
    seams_of("seams, 0.01 mm cubes face to face", "tiny_pair.step"),
    seams_of("seams, three 0.1 mm cubes in a row", "tiny_row.step"),
    seams_of("seams, plates facing across a rod", "rod_in_gap.step"),
    naming_key(
        "weldment scene, two coincident boxes",
        run_args("weld.toml", *set_args('workpiece.step="coincident.step"')),
    ),
    Entry(
        "seams --min-length-mm 0",
        ("seams", "tiny_pair.step", "--min-length-mm", "0"),
        field="--min-length-mm",
    ),
    Entry(
        "seams --min-length-mm nan",
        ("seams", "tiny_pair.step", "--min-length-mm", "nan"),
        field="--min-length-mm",
    ),
)

_P = "workpiece.params"
PLATES: tuple[Entry, ...] = (
    _groove(f"{_P}.plate_width_mm", f'{_P}.plate_width_mm="abc"'),
    _groove(f"{_P}.plate_width_mm", f"{_P}.plate_width_mm=true"),
    _groove(f"{_P}.plate_width_mm", f"{_P}.plate_width_mm=1e300"),
    _groove(f"{_P}.plate_width_mm", f"{_P}.plate_width_mm=-5"),
    _groove(f"{_P}.plate_width_mm", f"{_P}.plate_width_mm=[40]"),
    _groove(f"{_P}.seam_length_mm", f'{_P}.seam_length_mm="abc"'),
    _groove(f"{_P}.seam_length_mm", f"{_P}.seam_length_mm=true"),
    _groove(f"{_P}.seam_length_mm", f"{_P}.seam_length_mm=1e300"),
    _groove(f"{_P}.arc_radius_mm", f'{_P}.path="arc"', f"{_P}.arc_radius_mm=false"),
    _groove(f"{_P}.path", f"{_P}.path=3"),
)

_V = 'type="VGroove", t_mm=10, alpha_deg=60, b_mm=1, c_mm=1'
_DV = 'type="DVGroove", t_mm=20, alpha_1_deg=60, alpha_2_deg=60, c_mm=2'
_DU = 'type="DUGroove", t_mm=40, beta_1_deg=8, beta_2_deg=8, R_mm=6, R2_mm=6'
_DHV = 'type="DHVGroove", t_mm=20, beta_1_deg=45, beta_2_deg=45, c_mm=2'
_DHU = 'type="DHUGroove", t_mm=40, beta_1_deg=8, beta_2_deg=8, R_mm=6, R2_mm=6'
_U = 'type="UGroove", t_mm=15, beta_deg=9, R_mm=6, c_mm=3'
_HU = 'type="HUGroove", t_mm=15, beta_deg=9, R_mm=6, c_mm=3'
_HV = 'type="HVGroove", t_mm=10, beta_deg=45, c_mm=1'
_UV = 'type="UVGroove", t_mm=20, alpha_deg=60, beta_deg=10, R_mm=6, h_mm=4'
_VV = 'type="VVGroove", t_mm=20, alpha_deg=70, beta_deg=10, h_mm=5, c_mm=1'
_I = 'type="IGroove", t_mm=4, b_mm=1'

GROOVES: tuple[Entry, ...] = (
    # the reproducers
    _table(
        f"{_DV}, alpha_1_deg=-30".replace("alpha_1_deg=60, ", ""),
        "alpha_1_deg",
        "DVGroove alpha_1_deg=-30",
    ),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=1e300"),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=180"),
    _table('type="UGroove", t_mm=10, beta_deg=9, R_mm=50', "R_mm", "UGroove R_mm=50 in t_mm=10"),
    _groove("workpiece.groove.c_mm", "workpiece.groove.c_mm=12"),
    # their neighbours: other values, other types
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=-60"),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=0"),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=170"),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=true"),
    _groove("workpiece.groove.alpha_deg", 'workpiece.groove.alpha_deg="60"'),
    _groove("workpiece.groove.alpha_deg", "workpiece.groove.alpha_deg=nan"),
    _groove("workpiece.groove.c_mm", "workpiece.groove.c_mm=10"),
    _groove("workpiece.groove.c_mm", "workpiece.groove.c_mm=-1"),
    _groove("workpiece.groove.b_mm", "workpiece.groove.b_mm=-1"),
    _groove("workpiece.groove.b_mm", "workpiece.groove.b_mm=1e6"),
    _groove("workpiece.groove.t_mm", "workpiece.groove.t_mm=0"),
    _groove("workpiece.groove.t_mm", "workpiece.groove.t_mm=1e6"),
    _groove("workpiece.groove.t_mm", "workpiece.groove.t_mm=true"),
    _table(
        f"{_DV}, alpha_2_deg=0".replace("alpha_2_deg=60, ", ""),
        "alpha_2_deg",
        "DVGroove alpha_2_deg=0",
    ),
    _table(f"{_DV}, h1_mm=10, h2_mm=10", "h1_mm", "DVGroove depths and root face over t"),
    _table(f"{_DHV}, h1_mm=15", "h1_mm", "DHVGroove h1_mm=15 (and h2) in t_mm=20"),
    _table(
        f"{_DHV}, beta_2_deg=-10".replace("beta_2_deg=45, ", ""),
        "beta_2_deg",
        "DHVGroove beta_2_deg=-10",
    ),
    _table(
        f"{_DU}, R2_mm=30".replace("R2_mm=6, ", ""), "R2_mm", "DUGroove R2_mm=30 deeper than its U"
    ),
    _table(
        _DU.replace("t_mm=40", "t_mm=2").replace("R_mm=6, R2_mm=6", "R_mm=0.5, R2_mm=0.5"),
        "c_mm",
        "DUGroove default c_mm=3 in t_mm=2",
    ),
    _table(f"{_DHU}, c_mm=50", "c_mm", "DHUGroove c_mm=50 in t_mm=40"),
    _table(
        f"{_DHU}, beta_1_deg=90".replace("beta_1_deg=8, ", ""),
        "beta_1_deg",
        "DHUGroove beta_1_deg=90",
    ),
    _table(_U.replace("R_mm=6", "R_mm=12"), "R_mm", "UGroove c_mm + R_mm over t_mm"),
    _table(_U.replace("beta_deg=9", "beta_deg=1e300"), "beta_deg", "UGroove beta_deg=1e300"),
    _table(_HU.replace("R_mm=6", "R_mm=0"), "R_mm", "HUGroove R_mm=0"),
    _table(_HU.replace("R_mm=6", "R_mm=50"), "R_mm", "HUGroove R_mm=50 in t_mm=15"),
    _table(_HV.replace("beta_deg=45", "beta_deg=90"), "beta_deg", "HVGroove beta_deg=90"),
    _table(_HV.replace("c_mm=1", "c_mm=12"), "c_mm", "HVGroove c_mm=12 in t_mm=10"),
    _table(_UV.replace("R_mm=6", "R_mm=1"), "R_mm", "UVGroove R_mm too small to meet its V"),
    _table(_UV.replace("h_mm=4", "h_mm=25"), "h_mm", "UVGroove h_mm=25 in t_mm=20"),
    _table(_UV.replace("alpha_deg=60", "alpha_deg=-60"), "alpha_deg", "UVGroove alpha_deg=-60"),
    _table(_VV.replace("h_mm=5", "h_mm=19"), "h_mm", "VVGroove h_mm + c_mm over t_mm"),
    _table(_VV.replace("h_mm=5", "h_mm=1"), "h_mm", "VVGroove h_mm not above c_mm"),
    _table(_VV.replace("beta_deg=10", "beta_deg=0"), "beta_deg", "VVGroove beta_deg=0"),
    _table(_I.replace("b_mm=1", "b_mm=50"), "b_mm", "IGroove b_mm=50 in t_mm=4"),
    _table(_I.replace("t_mm=4", "t_mm=-4"), "t_mm", "IGroove t_mm=-4"),
    _table(f"{_V}, h_mm=2", "h_mm", "VGroove takes no h_mm"),
    _table('type="FFGroove", t_mm=2', "type", "FFGroove (weldx's frame groove)"),
)

ENTRIES: tuple[Entry, ...] = (*WELDMENTS, *PLATES, *GROOVES)
