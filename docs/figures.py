"""The measured figures, rendered from the benches' JSON (``docs/bench/<name>/*.json``).

No figure is copied by hand: the README's headline table and the documentation's "Measured
figures" page are both made here from what the benches wrote.

    python docs/figures.py            # print the headline table
    python docs/figures.py --write    # put it into README.md, between its two markers, and
                                      # every page's bench tables (below) into their pages
    python docs/figures.py --check    # exit 1 if a table is not what the JSON says

A figure table inside a page is written between two markers naming the bench output it comes
from: a bench JSON, rendered by the bench's own table function (:data:`RENDERERS`); a bench's
markdown (written by the bench from the same measurement as its JSON), whole; or the N-th
table of one (``bench/<name>/<file>.md#N``, from 0)::

    <!-- table: bench/trackers/trackers.json -->
    | ... the rendered table ... |
    <!-- end table -->

The site's build calls :func:`figures_page` through ``docs/hooks.py``.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "docs" / "bench"
README = ROOT / "README.md"
BEGIN = "<!-- figures:begin (python docs/figures.py --write) -->"
END = "<!-- figures:end -->"

#: The benches, in the order of the figures page: name -> (JSON files, the command that writes
#: them, what it measures).
BENCHES: dict[str, tuple[tuple[str, ...], str, str]] = {
    "scaling": (
        ("scaling.json",),
        "seamtrack bench scaling",
        "the paper's verification run, the CAD cache, a 1e5-point seam, the wall-clock guard",
    ),
    "loop": (("loop.json",), "seamtrack bench loop", "the closed loop on `paper-v-groove`"),
    "raycast": (
        ("raycast.json",),
        "seamtrack bench raycast",
        "stripe profiles by ray casting, and their precision against exact hits",
    ),
    "extractors": (
        ("extractors.json", "extractors_real.json"),
        "seamtrack extractors bench (--real DIR for the real sets)",
        "the joint-feature extractors on synthetic profiles with ground truth, and on real scans",
    ),
    "mesh": (("mesh.json",), "seamtrack bench mesh", "meshing CAD parts at a tolerance"),
    "camera": (("camera.json",), "seamtrack bench camera", "image mode: camera images"),
    "tradeoff": (("tradeoff.json",), "seamtrack bench tradeoff", "speed against accuracy"),
    "sweep": (("sweep.json",), "seamtrack bench sweep", "a sweep on 1 and 2 workers"),
    "dataset": (("dataset.json",), "seamtrack bench dataset", "labelled profiles and images"),
    "failures": (
        ("failures.json",),
        "seamtrack bench failures",
        "every bad input of the catalogue through the command line",
    ),
    "multipass": (("multipass.json",), "seamtrack bench multipass", "multi-pass jobs"),
    "gym": (("gym.json",), "seamtrack bench gym", "the Gymnasium environment's steps"),
    "bridge": (("bridge.json",), "seamtrack bench bridge", "the lockstep bridge's cost"),
    "trackers": (
        ("trackers.json",),
        "seamtrack bench trackers",
        "the paper's algorithms against the trajectory tracker on `paper-v-groove`, and the "
        "tracker's stop at the part's end",
    ),
    "paper": (
        ("paper.json",),
        "seamtrack bench paper",
        "the paper's Table 3 through Eq. 4-8, and its Table 4: algorithm II on `paper-corner` "
        "over the radius of convergence",
    ),
    "firstrun": (
        ("firstrun.json",),
        "seamtrack bench firstrun",
        "the demo's first mesh-mode run with an empty numba cache, then the same run again",
    ),
    "distortion": (
        ("distortion.json",),
        "seamtrack bench distortion",
        "the distortion models against published measurements; `butt-distortion` on and off",
    ),
    "weldments": (
        ("weldments.json",),
        "seamtrack bench weldments",
        "every seam of the bracket weldment tracked, one sweep on 2 workers; `seamtrack seams` "
        "on the public STEP files",
    ),
    "stability": (
        ("stability.json",),
        "seamtrack bench stability",
        "what the extremes of a scene's inputs do (seam mode)",
    ),
    "arc": (
        ("arc.json",),
        "seamtrack bench arc",
        "the arc in image and profile mode: current, look-ahead, seam-point errors, cost",
    ),
    "beads": (
        ("beads.json",),
        "seamtrack bench beads",
        "the bead model's width and height against a published bead-on-plate table",
    ),
}


#: A page's bench table: its markers and what lies between them.
TABLE = re.compile(
    r"^<!-- table: (?P<source>bench/[\w/.-]+\.(json(#\w+)?|md(#\d+)?)) -->\n(?P<body>.*?)"
    r"^<!-- end table -->$",
    re.S | re.M,
)


def _trackers_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.trackers import trackers_table

    return trackers_table(data)


def _end_of_part_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.trackers import end_of_part_table

    return end_of_part_table(data)


def _precision_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.raycast_precision import precision_table

    return precision_table(data)


def _weldments_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.weldments import weldments_table

    return weldments_table(data)


def _arm_outcomes_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.loop_arms import arm_outcomes_table

    return arm_outcomes_table(data)


def _stability_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.stability import stability_table

    return stability_table(data)


def _public_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.weldments_public import public_table

    return public_table(data)


def _groove_fill_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.groove_fill import groove_fill_table

    return groove_fill_table(data)


def _scans_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.extractors_scans import scans_table

    return scans_table(data)


def _firstrun_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.firstrun import firstrun_table

    return firstrun_table(data)


def _distortion_cases_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.distortion import cases_table

    return cases_table(data)


def _distortion_loop_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.distortion import loop_table

    return loop_table(data)


def _distortion_multipass_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.distortion import multipass_table

    return multipass_table(data)


def _speckle_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.camera_speckle import speckle_summary_table

    return speckle_summary_table(data)


def _must_show_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.camera_summary import must_show_table

    return must_show_table(data)


def _table3_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.paper import table3_table

    return table3_table(data)


def _table4_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.paper import table4_table

    return table4_table(data)


def _servo_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.paper import servo_table

    return servo_table(data)


def _presets_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.tradeoff import presets_table

    return presets_table(data)


def _arc_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.arc import arc_table

    return arc_table(data)


def _beads_table(data: dict[str, Any]) -> str:
    from seamtrack.bench.published_beads import beads_table

    return beads_table(data)


#: The bench JSON files a page may quote (``file.json``, or ``file.json#name`` for one of a
#: file's several tables) -> the bench's own function that renders the table.
RENDERERS: dict[str, Callable[[dict[str, Any]], str]] = {
    "trackers.json": _trackers_table,
    "trackers.json#end_of_part": _end_of_part_table,
    "tradeoff.json": _presets_table,
    "camera.json#speckle": _speckle_table,
    "camera.json#must_show": _must_show_table,
    "paper.json#table3": _table3_table,
    "paper.json#table4": _table4_table,
    "paper.json#servo": _servo_table,
    "firstrun.json": _firstrun_table,
    "distortion.json#cases": _distortion_cases_table,
    "distortion.json#loop": _distortion_loop_table,
    "distortion.json#multipass": _distortion_multipass_table,
    "raycast.json#precision": _precision_table,
    "weldments.json": _weldments_table,
    "weldments.json#public": _public_table,
    "loop.json#arm_outcomes": _arm_outcomes_table,
    "stability.json": _stability_table,
    "groove_fill.json": _groove_fill_table,
    "extractors_scans.json": _scans_table,
    "arc.json": _arc_table,
    "beads.json": _beads_table,
}


def md_tables(text: str) -> list[str]:
    """The tables of a markdown text, in order, each with a final newline."""
    found, current = [], []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            current.append(line)
        elif current:
            found.append("\n".join(current) + "\n")
            current = []
    return found


def render_table(source: str) -> str:
    """What a page's markers name (``bench/<name>/<file>.json``, ``.md`` or ``.md#N``,
    relative to docs/), rendered from the bench's output."""
    file, _, index = source.partition("#")
    path = BENCH.parent / file
    if path.suffix == ".json":
        name = f"{path.name}#{index}" if index else path.name
        return RENDERERS[name](json.loads(path.read_text()))
    text = path.read_text()
    return md_tables(text)[int(index)] if index else text.rstrip("\n") + "\n"


def page_tables(text: str) -> list[tuple[str, str, str]]:
    """A page's bench tables: (source, the table in the page, the table its JSON renders)."""
    return [(m["source"], m["body"], render_table(m["source"])) for m in TABLE.finditer(text)]


def render_pages(text: str) -> str:
    """A page with every bench table rendered again from its JSON."""
    return TABLE.sub(
        lambda m: f"<!-- table: {m['source']} -->\n{render_table(m['source'])}<!-- end table -->",
        text,
    )


def pages() -> list[Path]:
    """The pages that may hold bench tables: README.md and docs/*.md."""
    return [README, *sorted((ROOT / "docs").glob("*.md"))]


def load(name: str, file: str | None = None) -> dict[str, Any]:
    """One bench's JSON (its first file unless ``file`` names another)."""
    files = BENCHES[name][0]
    return json.loads((BENCH / name / (file or files[0])).read_text())


# --------------------------------------------------------------------------- headline table
def _row(name: str, what: str, measured: Callable[[], str], command: str) -> str:
    try:
        text = measured()
    except (OSError, KeyError, IndexError, TypeError, ValueError) as exc:  # a bench re-shaped
        text = f"(no figure: {type(exc).__name__} {exc} reading docs/bench/{name})"
    return f"| {what} | {text} | `{command}` |"


def _scaling() -> str:
    r = load("scaling")["row"]
    return (
        f"{r['coarse_status']}, max error {r['coarse_max_error_mm']:.3f} mm (the paper asks "
        f"0.5), RMS {r['coarse_rms_error_mm']:.3f} mm, {r['coarse_wall_s']:.2f} s wall"
    )


def _loop() -> str:
    r = load("loop")["rows"][0]
    return (
        f"{r['sim_s_per_cpu_s']:.1f} simulated s per CPU s, max error {r['max_error_mm']:.3f} "
        f"mm; per frame {r['scan_ms_per_frame']:.2f} ms ray casting, "
        f"{r['extract_ms_per_frame']:.2f} ms extraction"
    )


def _raycast() -> str:
    case = load("raycast")["cases"][0]
    rates = case["profiles_per_s"]
    section = rates["scan_mesh (Profile), plane-section fan"]
    embree = rates["scan_mesh (Profile), Embree fan, float64 refinement"]
    ratios = case["ratios"]
    return (
        f"{section:,.0f} profiles/s per core with the plane-section fan, {embree:,.0f} with "
        f"Embree's, on {case['triangles']:,} triangles; "
        f"{ratios['scan_mesh (plane-section) / bare embreex']:.2f}x bare embreex, "
        f"{ratios['scan_mesh (plane-section) / trimesh']:.2f}x trimesh"
    )


def _extractors() -> str:
    data = load("extractors")
    rows = [
        r
        for r in data["rows"]
        if r["level"] == "outliers+reflection" and r["extractor"] == r["joint"]
    ]
    detect = [r["detection_rate"] for r in rows]
    p95 = [r["p95_error_mm"] for r in rows if r["p95_error_mm"] is not None]
    median_us = [t["median_us"] for k, t in data["timing"].items() if k != "generic"]
    return (
        f"{len(rows)} families with 5 % outliers and a false reflection: detected "
        f"{100 * min(detect):.1f}-{100 * max(detect):.1f} %, p95 error <= {max(p95):.3f} mm; "
        f"{min(median_us):.0f}-{max(median_us):.0f} us per profile (median)"
    )


def _mesh() -> str:
    rows = load("mesh")["rows"]
    held = sum(r["deviation_mm"] <= r["tolerance_mm"] for r in rows)
    finest = max(rows, key=lambda r: r["triangles"])
    paper = [r for r in rows if r["path"] == "paper" and r["tolerance_mm"] <= 0.01]
    worst = max(r["peak_bytes_per_triangle"] for r in paper)
    return (
        f"deviation within the tolerance in {held} of {len(rows)} meshes (1 to 0.001 mm); "
        f"{finest['triangles']:,} triangles in {finest['meshing_time_s']:.0f} s at the finest; "
        f"meshing peaks at <= {worst:.0f} bytes a triangle on the paper part at 0.01 and 0.001 mm"
    )


def _camera() -> str:
    data = load("camera")
    worst = max(r["rms_px"] for r in data["plane"])
    ratios = [r["centroid_ratio"] for r in data["speckle"]]
    ideal = data["throughput"]["ideal"]["images_per_s"]
    return (
        f"detectors within {worst:.3f} px RMS of the analytic plane; speckle noise "
        f"{min(ratios):.2f}-{max(ratios):.2f}x Dorsch et al.'s; {ideal:.0f} ideal images/s"
    )


def _angles() -> str:
    rows = load("extractors").get("angle_sweep") or []
    inside = [r for r in rows if 40 <= r["angle_deg"] <= 145]
    return (
        f"V-grooves of 30-150 deg on real-sensor artefact profiles, range units 0.01-0.05 mm: "
        f"claimed 40-145 deg, detected >= {100 * min(r['detection_rate'] for r in inside):.1f} "
        f"%, p95 <= {max(r['p95_error_mm'] for r in inside):.2f} mm there"
    )


def _exposure() -> str:
    rows = load("camera").get("exposure") or []
    if not rows:
        return "not measured yet (seamtrack bench camera)"
    tilt = max(r["tilt_deg"] for r in rows)
    found = min(r["found"] for r in rows)
    saturated = max(r["saturated"] for r in rows)
    old = min(r["fixed_found_old_threshold"] for r in rows)
    return (
        f"default camera and detector, steel and aluminium tilted 0-{tilt:.0f} deg: "
        f"{100 * found:.0f} % of the stripe's columns found at worst, at most "
        f"{100 * saturated:.1f} % saturated (a fixed exposure and absolute threshold: "
        f"{100 * old:.0f} % at worst)"
    )


def _speckle() -> str:
    rows = load("camera").get("speckle_sweep") or []
    if not rows:
        return "not measured yet (seamtrack bench camera)"
    line = [r["vs_line_formula"] for r in rows]
    spot = [r["spot_ratio"] for r in rows]
    within = sum(0.7 <= x <= 1.3 for x in spot)
    widths = sorted({r["line_thickness_mm"] for r in rows})
    return (
        f"{len(rows)} cases, lines {widths[0]:g}-{widths[-1]:g} mm, f/2-f/16, 3 pixel pitches: "
        f"a column's speckle noise {min(line):.2f}-{max(line):.2f}x the line's own formula; "
        f"a patch {within} of {len(rows)} within 30 % of Dorsch's spot (the rest: docs/camera.md)"
    )


def _tradeoff() -> str:
    rows = {r["label"]: r for r in load("tradeoff")["rows"]}
    parts = [
        f"{label} {rows[label]['total_s']:.2f} s, RMS {rows[label]['rms_error_mm']:.4f} mm"
        for label in ("fast preview", "default", "reference")
        if label in rows
    ]
    return "; ".join(parts)


def _sweep() -> str:
    data = load("sweep")
    two = next(r for r in data["runs"] if r["workers"] == 2)
    same = "identical numbers" if data["same_numbers"] else "numbers DIFFER"
    ratio = two["ratio_to_1_worker"]
    return f"{data['cases']} cases: 2 workers take {ratio:.2f}x the wall time of 1; {same}"


def _dataset() -> str:
    rates = load("dataset")["rates"]
    geometry = [r for r in rates if not r["spec"].startswith("images")]
    images = [r for r in rates if r["spec"].startswith("images")]
    return (
        f"{geometry[0]['per_cpu_s']:,.0f} profiles per CPU s ({geometry[-1]['per_cpu_s']:,.0f} "
        f"with every noise knob on); {min(r['per_cpu_s'] for r in images):.1f}-"
        f"{max(r['per_cpu_s'] for r in images):.0f} images per CPU s"
    )


def _failures() -> str:
    data = load("failures")
    rows = data["rows"]
    one_line = sum(
        r.get("exit") == 2 and str(r.get("first_line", "")).startswith("seamtrack: error: ")
        for r in rows
    )
    clean = sum(not r.get("problems") for r in rows)
    peaks = [r.get("peak_mb_so_far", r.get("peak_mb", math.nan)) for r in rows]
    peak = max([*peaks, data.get("largest_run", {}).get("peak_mb", math.nan)])
    return (
        f"{len(rows)} inputs: {one_line} answered with one error line and exit 2, {clean} "
        f"without a problem found; largest peak {peak:,.0f} MB"
    )


#: The README's rows: bench, what was measured, the command a user runs to see it.
HEADLINE = (
    ("scaling", "the paper's verification (Fig. 7), seam mode", "seamtrack run"),
    ("loop", "closed loop, mesh mode, 1024 rays at 100 Hz", "seamtrack bench loop"),
    ("arms", "6-axis arms in the closed loop", "seamtrack bench loop"),
    ("raycast", "stripe profile, 1024 rays + shadow rays", "seamtrack bench raycast"),
    ("extractors", "joint-feature extractors", "seamtrack extractors bench"),
    ("angles", "the V-groove extractor against its opening", "seamtrack extractors bench"),
    ("mesh", "meshing CAD at a tolerance", "seamtrack bench mesh"),
    ("camera", "image mode, 1024 x 512 camera", "seamtrack bench camera"),
    ("exposure", "exposure against tilt (image mode)", "seamtrack bench camera"),
    ("speckle", "speckle against line width, aperture, pixel", "seamtrack bench camera"),
    ("tradeoff", "speed against accuracy (60 mm, mesh mode)", "seamtrack bench tradeoff"),
    ("sweep", "sweeps on 2 cores", "seamtrack bench sweep"),
    ("dataset", "labelled datasets, one core", "seamtrack bench dataset"),
    ("failures", "bad input", "seamtrack bench failures"),
    ("multipass", "multi-pass jobs (gantry, 1.2 mm wire)", "seamtrack bench multipass"),
    ("gym", "Gymnasium environment, paper-v-groove", "seamtrack bench gym"),
    ("bridge", "lockstep bridge, algorithm II in another process", "seamtrack bench bridge"),
    ("firstrun", "the demo's first mesh-mode run, empty numba cache", "seamtrack bench firstrun"),
    ("arc", "the arc in the sensor's view (MAG, 250 A, 30 mm ahead)", "seamtrack bench arc"),
    ("beads", "a bead's width and height against published beads", "seamtrack bench beads"),
)


def _multipass() -> str:
    r = load("multipass")
    t = r["jobs"][0]
    forced = next(j for j in r["jobs"] if j["count"] == 12)
    gap = {row["planner"]: row for row in r["varying_gap"]}
    spread = ", ".join(
        f"{k} {v.get('quality_level') or 'none'} ({v['underfilled_stations']} stations under the "
        f"plates' line, spread {v['reinforcement_spread_mm']:.2f} mm)"
        for k, v in gap.items()
    )
    levels = ", ".join(f"{j['count']}: {j.get('quality_level') or 'none'}" for j in r["jobs"])
    busy = r.get("load_average_after")
    return (
        f"{t['passes']} passes on {t['seam_mm']:.0f} mm, {t['status']}: max tracking error "
        f"{t['max_tracking_error_mm']:.2f} mm, reinforcement {t['reinforcement_min_mm']:.2f} to "
        f"{t['reinforcement_max_mm']:.2f} mm, {t['x_real_time']:.1f}x real time of arc time"
        + (f" (load {busy:.1f})" if busy is not None else " (measured beside other work)")
        + f", peak {t['peak_rss_mb']:.0f} MB; forced into {forced['passes']} passes: max "
        f"tracking error {forced['max_tracking_error_mm']:.2f} mm; ISO 5817 level by pass "
        f"count: {levels}; varying gap, ISO 5817 level: {spread}"
    )


def _gym() -> str:
    rows = {row["row"]: row for row in load("gym")["rows"]}
    single = next(v for k, v in rows.items() if k.startswith("1 env"))
    vector = [v for k, v in rows.items() if k.startswith("AsyncVectorEnv")]
    batched = [v for k, v in rows.items() if k.startswith("BatchedVectorEnv")]
    text = (
        f"{single['steps_per_s']:,.0f} steps/s in one process (load "
        f"{single['load_average_before']:.1f}); AsyncVectorEnv "
        + ", ".join(f"{v['steps_per_s']:,.0f} steps/s ({v['row'].split(', ')[1]})" for v in vector)
    )
    if batched:
        text += "; BatchedVectorEnv, 16 envs, " + ", ".join(
            f"{v['steps_per_s']:,.0f} steps/s ({v['row'].split(', ')[2]})" for v in batched
        )
    return text


def _arms() -> str:
    r = load("loop")
    ticks = {t["robot"]: t for t in r["tick_cost"]}
    scenes = ", ".join(f"{a['scene']} {a['sim_s_per_cpu_s']:.1f}x" for a in r["arm_scenes"])
    return (
        f"a control tick (closed-form IK, compiled) {ticks['ur10e']['us_per_tick']:.1f} us on "
        f"the UR10e, {ticks['kr16']['us_per_tick']:.1f} us on the KR 16 "
        f"({ticks['cartesian']['us_per_tick']:.1f} us on the gantry); arm scenes, simulated s "
        f"per CPU s: {scenes}"
    )


def _bridge() -> str:
    r = load("bridge")
    runs = ", ".join(f"{x['run']} {x['x_real_time']:.1f}x" for x in r["runs"])
    return f"x real time (load {r['load_average_before']:.1f}): {runs}"


def _firstrun() -> str:
    rows = load("firstrun")["rows"]
    first = rows[0]
    text = (
        f"{first['first_s']:.0f} s, {first['extra_s']:.0f} s more than the same run again "
        f"({first['variant']}, load {first['load_1min']:.2f}; the goal: 15 s more)"
    )
    if len(rows) > 1:
        one = rows[1]
        text += f"; {one['first_s']:.0f} s in one process"
    return text


def _beads() -> str:
    r = load("beads")
    held, model = r["held_out"], r["model"]
    rows = r["rows"]
    feeds = sorted({row["wire_feed_m_min"] for row in rows})
    speeds = sorted({row["travel_speed_mm_min"] for row in rows})
    return (
        f"{model['shape']}, w/h {model['width_to_height']:g}, wire area calibrated on "
        f"{len(model['calibration_runs'])} centre beads; {sum(row['held_out'] for row in rows)} "
        f"held-out beads ({feeds[0]:g}-{feeds[-1]:g} m/min, {speeds[0]:g}-{speeds[-1]:g} mm/min): "
        f"width within {100 * held['max_width_error']:.1f} %, height within "
        f"{100 * held['max_height_error']:.1f} % ({r['source']}; laser + CMT on Al-Cu)"
    )


def _arc() -> str:
    r = load("arc")
    cells = {
        (row["mode"], row["countermeasures"]): row
        for row in r["rows"]
        if row["current_a"] == 250.0 and row["look_ahead_mm"] == 30.0
    }

    def cell(mode: str, cm: str) -> str:
        row = cells[(mode, cm)]
        text = f"{row['detect_rate']:.0%} found"
        if row["median_mm"] is not None:
            text += f", median {row['median_mm']:.3f} mm, p95 {row['p95_mm']:.3f} mm"
        return text

    # A whole run measures the cost itself; ``--cost`` re-measures it later and says so.
    cost_command = r.get("image_cost_command", r["command"])
    return (
        f"image, default countermeasures: {cell('image', 'default')}; without them: "
        f"{cell('image', 'none')}; profile model, default: {cell('profile', 'default')}; the "
        f"arc costs an image {r['image_cost_ratio']:.2f}x the time of one without it (load "
        f"{r['image_cost_load_1min_before']:.1f}, `{cost_command}`)"
    )


def headline() -> str:
    """The README's table: one line per figure, each with the command that measured it."""
    measured = {
        "scaling": _scaling,
        "loop": _loop,
        "arms": _arms,
        "raycast": _raycast,
        "extractors": _extractors,
        "mesh": _mesh,
        "angles": _angles,
        "camera": _camera,
        "exposure": _exposure,
        "speckle": _speckle,
        "tradeoff": _tradeoff,
        "sweep": _sweep,
        "dataset": _dataset,
        "failures": _failures,
        "multipass": _multipass,
        "gym": _gym,
        "bridge": _bridge,
        "firstrun": _firstrun,
        "arc": _arc,
        "beads": _beads,
    }
    rows = [_row(name, what, measured[name], command) for name, what, command in HEADLINE]
    head = ["| figure | measured | command |", "|---|---|---|"]
    return "\n".join(head + rows) + "\n"


# --------------------------------------------------------------------------- the whole page
def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isnan(value):
            return "-"
        return f"{value:,.0f}" if abs(value) >= 1e4 else f"{value:.4g}"
    if isinstance(value, int):
        return f"{value:,}" if abs(value) >= 1e4 else str(value)
    if isinstance(value, list) and all(not isinstance(v, (dict, list)) for v in value):
        return ", ".join(_cell(v) for v in value)
    # Text as text: "[a][#b]" would read as a reference link, "<b>" as a tag.
    text = str(value).replace("|", "\\|").replace("\n", " ").replace("[", "\\[")
    return text.replace("]", "\\]").replace("<", "&lt;").replace(">", "&gt;")


def _scalar(value: Any) -> bool:
    return not isinstance(value, (dict, list)) or (
        isinstance(value, list) and all(not isinstance(v, (dict, list)) for v in value)
    )


def _tables(obj: Any, title: str, level: int) -> list[str]:
    """Markdown for one JSON value: a key/value table of a dict's scalars, a table of a list of
    records, and a sub-section for anything nested deeper."""
    out: list[str] = []
    hashes = "#" * min(level, 6)
    if isinstance(obj, dict):
        flat = {k: v for k, v in obj.items() if _scalar(v) and k != "machine"}
        if flat:
            out += [f"{hashes} {title}", "", "| quantity | value |", "|---|---|"]
            out += [f"| {k} | {_cell(v)} |" for k, v in flat.items()]
            out.append("")
        for key, value in obj.items():
            if key != "machine" and not _scalar(value):
                out += _tables(value, f"{title}: {key}", level + 1)
    elif isinstance(obj, list) and obj and all(isinstance(v, dict) for v in obj):
        columns: list[str] = []
        for record in obj:
            columns += [k for k, v in record.items() if _scalar(v) and k not in columns]
        out += [f"{hashes} {title}", ""]
        out += ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
        out += ["| " + " | ".join(_cell(r.get(k)) for k in columns) + " |" for r in obj]
        out.append("")
        for i, record in enumerate(obj):
            label = _cell(next(iter(record.values()))) if record else str(i)
            for key, value in record.items():
                if not _scalar(value):
                    out += _tables(value, f"{title}: {label}: {key}", level + 1)
    return out


def _machine(data: dict[str, Any]) -> str:
    m = data.get("machine")
    if not isinstance(m, dict):
        return ""
    return "Machine: " + ", ".join(f"{k} {v}" for k, v in m.items()) + "."


def figures_page() -> str:
    """The "Measured figures" page: the headline table, then every bench's JSON as tables."""
    lines = [
        "# Measured figures",
        "",
        "Rendered from the benches' JSON in `docs/bench/<name>/` by `docs/figures.py` when this",
        "site is built: no figure here is copied by hand. `make bench` runs every bench into",
        "`bench-results/`; copy a bench's folder over `docs/bench/<name>/` to publish it.",
        "",
        "## Headline",
        "",
        headline(),
    ]
    for name, (files, command, what) in BENCHES.items():
        lines += [f"## {name}", "", f"{what[0].upper()}{what[1:]}: `{command}`.", ""]
        for file in files:
            path = BENCH / name / file
            if not path.is_file():
                lines += [f"No `{file}` in `docs/bench/{name}/` yet.", ""]
                continue
            data = json.loads(path.read_text())
            lines += [f"From `docs/bench/{name}/{file}`. {_machine(data)}", ""]
            lines += _tables(data, file.removesuffix(".json"), 3)
        for image in sorted((BENCH / name).glob("*.png")):
            lines += [f"![{image.stem}](bench/{name}/{image.name})", ""]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- README
def readme_table(text: str) -> str:
    """The table between the README's markers."""
    if BEGIN not in text or END not in text:
        raise SystemExit(f"README.md: no {BEGIN} ... {END} markers")
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n") + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--write", action="store_true", help="write the README's table")
    group.add_argument("--check", action="store_true", help="fail if the README's table differs")
    args = parser.parse_args(argv)
    table = headline()
    if not (args.write or args.check):
        print(table, end="")
        return 0
    text = README.read_text()
    if args.check:
        stale = [
            f"{page.relative_to(ROOT)}: {source}"
            for page in pages()
            for source, written, rendered in page_tables(page.read_text())
            if written != rendered
        ]
        if readme_table(text) != table:
            stale.append("README.md: the headline figures")
        for line in stale:
            print(
                f"{line} differs from docs/bench/*/*.json; fix: python docs/figures.py --write",
                file=sys.stderr,
            )
        return 1 if stale else 0
    unread = [line for line in table.splitlines() if "(no figure" in line]
    if unread:  # a bench's JSON lacks a field the table reads: say so, write nothing
        for line in unread:
            print(
                f"README.md: {line.split('(no figure: ')[1].split(')')[0]}; fix: re-run "
                "that bench or teach docs/figures.py its JSON",
                file=sys.stderr,
            )
        return 1
    head, rest = text.split(BEGIN, 1)
    README.write_text(head + BEGIN + "\n" + table + rest[rest.index(END) :])
    for page in pages():
        page_text = page.read_text()
        if TABLE.search(page_text):
            page.write_text(render_pages(page_text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
