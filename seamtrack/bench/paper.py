"""``seamtrack bench paper``: the paper's Table 3 through Eq. 4-8 and its Table 4 re-run, the
tables of docs/paper.md.

Algorithm II on ``paper-corner`` over the radius of convergence, as ``seamtrack sweep
paper-corner --param tracker.radius_mm --values 6,5,1,0.1,0.05,0.04,0.02,0.01``: once with the
scene's ideal axes, once with the position servo on (``robot.servo_gain_1_s = 20``,
``robot.interpolation_period_s = 0.004``). Before them, the ``paper`` sensor preset solved
from Table 3's specs and its specs derived back through Eq. 4-8 (``table3``). Writes
``paper.json`` (``machine``, ``quick``, ``table3``, the radii and one list of rows per axis
model) and ``paper.md``, the tables :func:`table3_table`, :func:`table4_table` and
:func:`servo_table` render from the JSON (docs/figures.py renders the docs' copies from the
committed JSON with the same functions).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from seamtrack.batch.sweep import TABLE_KEYS
from seamtrack.bench.common import machine_info

SCENE = "paper-corner"
RADII_MM = (6.0, 5.0, 1.0, 0.1, 0.05, 0.04, 0.02, 0.01)
#: ``--quick``: two radii (a smoke run, not the docs' figures).
QUICK_RADII_MM = (6.0, 0.1)
SERVO: dict[str, Any] = {"robot.servo_gain_1_s": 20.0, "robot.interpolation_period_s": 0.004}
#: The sweep table's columns (a row of Table 4 is a case of ``seamtrack sweep``).
COLUMNS = TABLE_KEYS
#: The paper's own Table 4 (MaxError, MinError in mm at RADII_MM), quoted for comparison:
#: /work/shared/paper/seam-tracking-simulation.md, "Table 4 Seam tracking algorithm II
#: simulation result".
PAPER_MAX_ERROR_MM = (0.63, 0.497, 0.288, 0.288, 0.288, 0.288, 0.288, 0.288)
PAPER_MIN_ERROR_MM = (0.158, 0.123, 0.027, 0.0168, 0.0154, 0.0151, 0.0149, 0.0418)


def _rows(radii: tuple[float, ...], overrides: dict[str, Any]) -> list[dict[str, Any]]:
    from seamtrack.batch.sweep import run_sweep

    rows = []
    for radius, case in zip(
        radii, run_sweep(SCENE, "tracker.radius_mm", list(radii), overrides=overrides), strict=True
    ):
        summary = case.get("summary") or {}
        row: dict[str, Any] = {"radius_mm": radius, **{k: summary.get(k) for k in COLUMNS}}
        if "error" in case:
            row["status"] = f"error: {case['error']}"
        rows.append(row)
    return rows


def _table3() -> dict[str, Any]:
    """Table 3's specs, the geometry ``preset("paper")`` solves from them, and the specs that
    geometry gives back through Eq. 4-8."""
    from seamtrack.sensing.sensor import PRESET_SPECS, preset

    sensor = preset("paper")
    return {
        "table3": dict(PRESET_SPECS["paper"]),
        "geometry": sensor.geometry(),
        "eq4_8": sensor.specs(),
    }


def table3_table(result: dict[str, Any]) -> str:
    """Table 3's specs beside the same specs derived from the solved geometry (Eq. 4-8)."""
    t = result["table3"]
    paper, geometry, eq = t["table3"], t["geometry"], t["eq4_8"]
    rows = [
        ("depth of field D", f"{paper['depth_of_field_mm']:g} mm",
         f"{eq['depth_of_field_mm']:.3f} mm (Eq. 4)"),
        ("F_min, F_max", f"{paper['fov_near_mm']:g}, {paper['fov_far_mm']:g} mm",
         f"{eq['fov_near_mm']:.3f}, {eq['fov_far_mm']:.3f} mm (Eq. 6, 5)"),
        ("R_D, R_L (average)",
         f"{paper['depth_resolution_mm']:g}, {paper['lateral_resolution_mm']:g} mm",
         f"{eq['depth_resolution_mm']:.3g} (Eq. 7, N_H = {geometry['pixels_h']:.0f}), "
         f"{eq['lateral_resolution_mm']:.3g} mm (Eq. 8 bounds "
         f"{eq['lateral_resolution_near_mm']:.4f}-{eq['lateral_resolution_far_mm']:.4f}, "
         f"N_V = {geometry['pixels_v']:.0f})"),
        ("laser angle", f"{paper['angle_deg']:g} deg", f"{eq['angle_deg']:.2f} deg"),
        ("solved geometry", "",
         f"b = {geometry['baseline_mm']:.2f} mm, range {eq['range_near_mm']:.2f}-"
         f"{eq['range_far_mm']:.2f} mm, optical axis crossing at {eq['range_center_mm']:.2f} mm"),
    ]  # fmt: skip
    lines = ["| | Table 3 | Eq. 4-8 from the solved geometry |", "|---|---|---|"]
    lines += [f"| {name} |{f' {a}' if a else ''} | {b} |" for name, a, b in rows]
    return "\n".join(lines) + "\n"


def bench_paper(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """Run both sweeps and write ``paper.json`` and ``paper.md`` into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    radii = QUICK_RADII_MM if quick else RADII_MM
    result = {
        "machine": machine_info(),
        "quick": quick,
        "scene": SCENE,
        "table3": _table3(),
        "radii_mm": list(radii),
        "servo_overrides": SERVO,
        "ideal_axes": _rows(radii, {}),
        "servo_on": _rows(radii, SERVO),
    }
    (out / "paper.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "paper.md").write_text(
        table3_table(result) + "\n" + table4_table(result) + "\n" + servo_table(result)
    )
    return result


def _cell(value: Any, spec: str = ".4g") -> str:
    """A table cell: 4 significant digits, as ``seamtrack sweep`` prints them."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if isinstance(value, float):
        return format(value, spec)
    return str(value)


def table4_table(result: dict[str, Any]) -> str:
    """The sweep with ideal axes, as ``seamtrack sweep`` prints it."""
    head = [
        "| tracker.radius_mm | " + " | ".join(COLUMNS) + " |",
        "|" + "---|" * (len(COLUMNS) + 1),
    ]
    body = [
        f"| {r['radius_mm']:g} | " + " | ".join(_cell(r.get(c)) for c in COLUMNS) + " |"
        for r in result["ideal_axes"]
    ]
    return "\n".join(head + body) + "\n"


def servo_table(result: dict[str, Any]) -> str:
    """Per radius: the max error with the servo on and with ideal axes, the min error with the
    servo on, and the paper's own figures."""
    radii = result["radii_mm"]
    pairs = zip(PAPER_MAX_ERROR_MM, PAPER_MIN_ERROR_MM, strict=True)
    paper = dict(zip(RADII_MM, pairs, strict=True))
    servo, ideal = result["servo_on"], result["ideal_axes"]
    rows = [
        ("max_error_mm, servo on", [_cell(r["max_error_mm"], ".3f") for r in servo]),
        ("max_error_mm, ideal axes", [_cell(r["max_error_mm"], ".3f") for r in ideal]),
        ("min_error_mm, servo on", [_cell(r["min_error_mm"], ".1e") for r in servo]),
        ("paper MaxError (mm)", [f"{paper[x][0]:g}" if x in paper else "" for x in radii]),
        ("paper MinError (mm)", [f"{paper[x][1]:g}" if x in paper else "" for x in radii]),
    ]
    lines = [
        "| tracker.radius_mm | " + " | ".join(f"{x:g}" for x in radii) + " |",
        "|" + "---|" * (len(radii) + 1),
    ]
    lines += [f"| {name} | " + " | ".join(cells) + " |" for name, cells in rows]
    return "\n".join(lines) + "\n"
