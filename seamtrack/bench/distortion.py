"""``seamtrack bench distortion`` (issue 39 item 5): the distortion models against published
measurements, the gantry loop's speed with distortion on and off, and the tracked and taught
errors of ``butt-distortion``. Writes ``distortion.json`` and ``distortion.md``.

``cases``: one row per published measurement (``source`` with its DOI, ``kind``, ``measured``,
``simulated``, ``unit``). A row's ``measured`` is the value read in the source; where the
source's text could not be read here its ``measured`` is ``null`` with the reason in ``note``
(no number is made up or read off a model), and ``within`` says whether the model meets the
issue's bar (20 %, or the scatter the source reports) only where both numbers are there.

``loop``: ``butt-distortion`` run twice on the gantry, with its ``[distortion]`` and without;
``loop_x_real_time`` is simulated seconds per CPU second of this process (the loop's own
clock, which other jobs on a shared machine inflate far less than the wall clock, written
beside it with the 1-minute load).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info, markdown_table

#: Issue 39: the gantry loop runs at least this many times real time with distortion on.
TARGET_X_REAL_TIME = 25.0
#: Issue 39: every published case within 20 % (or the scatter its source reports).
TARGET_RELATIVE = 0.20
#: butt-distortion's must-show figures (issue 39): the seam moves and the taught path errs by
#: at least 1 mm; the default closed loop stays within 0.3 mm.
TARGET_SHIFT_MM = 1.0
TARGET_TRACKED_MM = 0.3


@dataclasses.dataclass(frozen=True)
class PublishedCase:
    """One published measurement. ``measured`` is ``None`` when its value was not read (say
    why in ``note``); ``scatter`` is the relative scatter the source reports (``None``: the
    issue's 20 % applies); ``bound`` is ``"lower"`` when the source gives only a floor and
    ``"range"`` when it gives a range (``measured`` its middle, ``scatter`` its half-width over
    that). ``simulate`` runs the model on the source's conditions (``None``: they were not
    read, so the model cannot be run on them)."""

    source: str
    doi: str
    kind: str
    unit: str
    measured: float | None = None
    scatter: float | None = None
    bound: str = ""
    note: str = ""
    simulate: Callable[[], float] | None = None


def v_groove_area_mm2(
    thickness_mm: float, groove_angle_deg: float, root_gap_mm: float, root_face_mm: float
) -> float:
    """The cross-section of a single-V butt joint's groove, mm^2: the root gap over the whole
    thickness and the two bevels over the thickness less the root face."""
    bevel = thickness_mm - root_face_mm
    return root_gap_mm * thickness_mm + bevel**2 * math.tan(math.radians(groove_angle_deg) / 2)


def _twi_v_groove_shrinkage_mm() -> float:
    """Spraragen and Ettinger's transverse shrinkage
    (:func:`seamtrack.heat.distortion.spraragen_ettinger_shrinkage_mm`) of the shipped
    ``multipass-v-groove`` joint, a 60 degree V: the weld's area is the groove's."""
    from seamtrack.heat.distortion import spraragen_ettinger_shrinkage_mm
    from seamtrack.simulation.scene import load_scene

    workpiece = load_scene("multipass-v-groove").config.workpiece
    assert workpiece is not None  # the shipped job scene is a CAD part
    p = workpiece.params
    t, gap = float(p["plate_thickness_mm"]), float(p["root_gap_mm"])
    area = v_groove_area_mm2(t, float(p["groove_angle_deg"]), gap, float(p["root_face_mm"]))
    return spraragen_ettinger_shrinkage_mm(area, thickness_mm=t, root_opening_mm=gap)


#: The published measurements the model is held to (issue 39: single-pass angular distortion at
#: more than one heat input and thickness, transverse shrinkage, the per-pass angular
#: distortion of a multi-pass joint). The values stay ``None`` until read in the paper itself:
#: the stored copies reachable when this was written hold only each paper's first page, and a
#: second search (2026-12-06) found no copy of any results section either (docs/heat.md).
PUBLISHED: tuple[PublishedCase, ...] = (
    PublishedCase(
        "Seong, Park and Lee, 'Analytical model for angular distortion in multilayer welding "
        "under constraints', Applied Sciences 10 (2020) 1848",
        "10.3390/app10051848",
        "multi-pass V-groove butt under constraint: angular distortion after each pass",
        "deg",
        note="value not read: the stored copies (scribd page 1 of 17, doaj.org, mdpi.com "
        "mirrors) hold the title, abstract and introduction only",
    ),
    PublishedCase(
        "Seong, 'Prediction and characteristics of angular distortion in multi-layer butt "
        "welding', Materials 12 (2019) 1435",
        "10.3390/ma12091435",
        "multi-pass V-groove butt, free: angular distortion after each pass",
        "deg",
        note="value not read: the stored copies (mdpi.com, readkong.com) hold the abstract "
        "and introduction only",
    ),
    PublishedCase(
        "Seong, Materials 12 (2019) 1435 (bead-on-plate database)",
        "10.3390/ma12091435",
        "single-pass bead-on-plate angular distortion, low Q/h^2 (thick plate)",
        "deg",
        note="value not read: the database's table is in none of the stored copies (abstract "
        "and introduction only)",
    ),
    PublishedCase(
        "Seong, Materials 12 (2019) 1435 (bead-on-plate database)",
        "10.3390/ma12091435",
        "single-pass bead-on-plate angular distortion, near the Q/h^2 peak (thin plate)",
        "deg",
        note="value not read: the database's table is in none of the stored copies (abstract "
        "and introduction only)",
    ),
    PublishedCase(
        "Huang et al., 'Finite element analysis and in-situ measurement of out-of-plane "
        "distortion in thin plate TIG welding', Materials 12 (2019) 141",
        "10.3390/ma12010141",
        "thin-plate TIG: largest transient out-of-plane distortion during welding (DIC)",
        "mm",
        measured=4.0,
        bound="lower",
        note="read in the abstract (mdpi.com/1996-1944/12/1/141, osti.gov/pages/biblio/"
        "1489600): 'larger than 4 mm' during welding; the plate and the arc are not in it, so "
        "the model is not run on it (its elastic transient angle is hundredths of a degree)",
    ),
    PublishedCase(
        "Velikanov, 'Determination of shrinkage of weld' (EDP Sciences, 2018)",
        "",
        "transverse shrinkage of a butt weld",
        "mm",
        note="value and DOI not read: the stored copy (scribd) holds the introduction only",
    ),
    PublishedCase(
        "TWI, 'How much shall I allow for weld shrinkage?' (FAQ, twi-global.com/technical-"
        "knowledge/faqs/faq-how-much-shall-i-allow-for-weld-shrinkage)",
        "",
        "transverse shrinkage of a 60 deg V butt weld in steel, whole joint (the shipped "
        "multipass-v-groove joint: 20 mm, 2 mm gap, 1 mm root face)",
        "mm",
        measured=2.25,
        scatter=0.75 / 2.25,
        bound="range",
        note="TWI's allowance from experience: '1.5 to 3mm per weld for 60 deg V joint'; the "
        "range is the scatter. Simulated: Spraragen and Ettinger's relation on the groove's area",
        simulate=_twi_v_groove_shrinkage_mm,
    ),
)


def simulate_case(case: PublishedCase) -> float | None:
    """The model's value for ``case``: ``None`` while the source's conditions (plate, arc,
    joint) are not read, as the model cannot be run without them."""
    return None if case.simulate is None else float(case.simulate())


def case_rows(cases: tuple[PublishedCase, ...] = PUBLISHED) -> list[dict[str, Any]]:
    """The ``cases`` rows: the published value, the model's (``None`` where the source's
    conditions were not read, so the model cannot be run on them) and the verdict."""
    rows = []
    for c in cases:
        simulated = simulate_case(c)
        within: bool | None = None
        if c.measured is not None and simulated is not None:
            if c.bound == "lower":
                within = simulated >= c.measured * (1 - (c.scatter or TARGET_RELATIVE))
            else:
                within = abs(simulated - c.measured) <= (c.scatter or TARGET_RELATIVE) * abs(
                    c.measured
                )
        rows.append({
            "source": c.source, "doi": c.doi, "kind": c.kind, "measured": c.measured,
            "simulated": simulated, "unit": c.unit, "bound": c.bound, "scatter": c.scatter,
            "within": within, "note": c.note,
        })  # fmt: skip
    return rows


def _loop_run(distortion: bool, seam_length_mm: float | None) -> dict[str, Any]:
    """butt-distortion on the gantry, with its ``[distortion]`` or without: the summary's
    figures and simulated seconds per CPU second (after an untimed warm-up run)."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run
    from seamtrack.simulation.scene import load_scene

    overrides: dict[str, Any] = {}
    if seam_length_mm is not None:  # the scene's three tacks moved onto the shorter seam
        tacks = [{"position_mm": f * seam_length_mm} for f in (0.05, 0.5, 0.95)]
        overrides = {"workpiece.params.seam_length_mm": seam_length_mm, "distortion.tacks": tacks}
    scene = load_scene("butt-distortion", overrides)
    if not distortion:
        config = scene.config.model_copy(update={"distortion": None})
        scene = dataclasses.replace(scene, config=config)
    parts = build_parts(scene)
    warm = dataclasses.replace(parts.settings, time_limit_s=2.0)
    run(dataclasses.replace(parts, settings=warm))
    load = os.getloadavg()[0]
    start = time.perf_counter()
    result = run(parts, clock=time.process_time)
    wall_clock = time.perf_counter() - start
    s = result.summary
    cpu = float(s["wall_time_s"])
    simulated = float(s["sim_time_s"])
    row = {
        "distortion": distortion,
        "status": s["status"],
        "simulated_s": simulated,
        "cpu_s": cpu,
        "wall_clock_s": wall_clock,
        "loop_x_real_time": simulated / cpu,
        "loop_x_real_time_wall": simulated / wall_clock,
        "load_1min": round(load, 2),
        "tracked_max_error_mm": float(s["max_error_mm"]),
    }
    for key in ("untracked_max_error_mm", "max_seam_shift_mm", "tacks_broken"):
        if key in s:
            row[key] = float(s[key])
    return row


#: The multi-pass job the bench runs quick: the scene on a 12 mm plate and a 40 mm seam.
MULTIPASS_QUICK: dict[str, Any] = {
    "workpiece.params.seam_length_mm": 40.0,
    "workpiece.params.plate_thickness_mm": 12.0,
    "distortion.thickness_mm": 12.0,
    "process.wire_feed_m_min": 6.0,
}


def _multipass_run(quick: bool) -> dict[str, Any]:
    """``multipass-v-groove-distortion`` (the 40 mm, 12 mm quick case when ``quick``): the
    angle after each pass and after the job, each pass's worst error against its true path
    where that path is, and how far the seam had sunk where the pass started."""
    from seamtrack.multipass.job import run_job
    from seamtrack.simulation.scene import load_scene

    load = os.getloadavg()[0]
    start = time.perf_counter()
    job = run_job(load_scene("multipass-v-groove-distortion", MULTIPASS_QUICK if quick else {}))
    wall = time.perf_counter() - start
    s = job.summary
    welded = [r for r in job.passes if r.plan is not None]
    total = 0.0
    rows = []
    for r, angle in zip(welded, s["angular_distortion_per_pass_deg"], strict=True):
        total += angle
        assert r.plan is not None
        rows.append({
            "pass": r.name, "reference": r.plan.reference, "cap": bool(r.plan.cap),
            "angle_deg": angle, "accumulated_deg": total,
            "max_error_mm": float(r.result.summary["max_error_mm"]),
            "seam_shift_at_start_mm": float(r.result.trace.seam_shift_mm[0]),
        })  # fmt: skip
    return {
        "scene": "multipass-v-groove-distortion",
        "overrides": MULTIPASS_QUICK if quick else {},
        "status": s["status"],
        "passes": s["passes"],
        "underfilled_stations": s["underfilled_stations"],
        "angular_distortion_deg": s["angular_distortion_deg"],
        "worst_pass_error_mm": max(row["max_error_mm"] for row in rows),
        "rows": rows,
        "wall_s": wall,
        "load_1min": round(load, 2),
    }


def _or_dash(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def multipass_table(data: dict[str, Any]) -> str:
    """The multi-pass job with distortion: one row per pass."""
    m = data["multipass"]
    header = ["pass", "aimed at", "its angle (deg)", "accumulated (deg)",
              "seam sunk where it starts (mm)", "max error (mm)"]  # fmt: skip
    rows = (
        [str(r["pass"]), r["reference"] + (" (cap)" if r["cap"] else ""),
         f"{r['angle_deg']:.2f}", f"{r['accumulated_deg']:.2f}",
         f"{r['seam_shift_at_start_mm']:.2f}", f"{r['max_error_mm']:.3f}"]
        for r in m["rows"]
    )  # fmt: skip
    lines = markdown_table(header, rows)
    lines.append(
        f"\n{m['status']}, {m['passes']} passes, {m['underfilled_stations']} stations "
        f"underfilled; the plates turned {m['angular_distortion_deg']:.2f} deg; worst pass "
        f"{m['worst_pass_error_mm']:.3f} mm ({m['wall_s']:.0f} s wall at a 1-minute load of "
        f"{m['load_1min']:.2f})."
    )
    return "\n".join(lines) + "\n"


def cases_table(data: dict[str, Any]) -> str:
    """The published cases: one row each, the model's value beside the source's."""

    def measured(r: dict[str, Any]) -> str:
        value = r["measured"]
        if value is None:
            return "not read"
        if r["bound"] == "range":
            half = r["scatter"] * value
            return f"{value - half:.2f}-{value + half:.2f}"
        return (">= " if r["bound"] == "lower" else "") + f"{value:.2f}"

    header = ["source", "DOI", "what was measured", "measured", "simulated", "unit", "within"]
    rows = (
        [r["source"], r["doi"] or "-", r["kind"], measured(r),
         _or_dash(r["simulated"]), r["unit"], {None: "-", True: "yes", False: "no"}[r["within"]]]
        for r in data["cases"]
    )  # fmt: skip
    lines = markdown_table(header, rows)
    return "\n".join(lines) + "\n"


def loop_table(data: dict[str, Any]) -> str:
    """butt-distortion with distortion on and off: speed, errors, the load."""
    header = ["butt-distortion", "loop x real time (CPU)", "x real time (wall)",
              "tracked max error (mm)", "taught path max error (mm)", "max seam shift (mm)",
              "1-min load"]  # fmt: skip
    rows = (
        [f"distortion {'on' if r['distortion'] else 'off'}", f"{r['loop_x_real_time']:.1f}",
         f"{r['loop_x_real_time_wall']:.1f}", f"{r['tracked_max_error_mm']:.3f}",
         _or_dash(r.get("untracked_max_error_mm")), _or_dash(r.get("max_seam_shift_mm")),
         f"{r['load_1min']:.2f}"]
        for r in data["loop"]
    )  # fmt: skip
    lines = markdown_table(header, rows)
    return "\n".join(lines) + "\n"


def bench_distortion(out_dir: str | Path, quick: bool = False) -> dict[str, Any]:
    """The cases, the loop on and off, butt-distortion's errors; ``quick`` cuts the seam to
    40 mm (a smoke test, not a measurement)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    length = 40.0 if quick else None
    on = _loop_run(True, length)
    print(f"  distortion on: {on['loop_x_real_time']:.1f}x real time", flush=True)
    off = _loop_run(False, length)
    print(f"  distortion off: {off['loop_x_real_time']:.1f}x real time", flush=True)
    multipass = _multipass_run(quick)
    print(f"  multi-pass job: {multipass['angular_distortion_deg']:.2f} deg", flush=True)
    result: dict[str, Any] = {
        "cases": case_rows(),
        "loop_x_real_time": {"on": on["loop_x_real_time"], "off": off["loop_x_real_time"]},
        "tracked_max_error_mm": on["tracked_max_error_mm"],
        "untracked_max_error_mm": on.get("untracked_max_error_mm"),
        "max_seam_shift_mm": on.get("max_seam_shift_mm"),
        "loop": [on, off],
        "multipass": multipass,
        "quick": quick,
        "targets": {
            "loop_x_real_time_on": TARGET_X_REAL_TIME,
            "relative": TARGET_RELATIVE,
            "max_seam_shift_mm": TARGET_SHIFT_MM,
            "untracked_max_error_mm": TARGET_SHIFT_MM,
            "tracked_max_error_mm": TARGET_TRACKED_MM,
        },
        "machine": machine_info(),
    }
    (out / "distortion.json").write_text(json.dumps(result, indent=2) + "\n")
    tables = [cases_table(result), loop_table(result), multipass_table(result)]
    (out / "distortion.md").write_text("\n".join(tables))
    return result
