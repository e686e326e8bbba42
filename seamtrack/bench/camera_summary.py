"""docs/camera.md's "must show" table, rendered from a ``camera.json`` (``seamtrack bench
camera``): one row per requirement of image mode, its figures read from the bench's rows.

docs/figures.py renders the page's copy from the committed JSON with :func:`must_show_table`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

Rows = list[dict[str, Any]]


def _span(values: list[float], spec: str) -> str:
    """``a-b`` (or ``a`` where both ends print alike)."""
    low, high = format(min(values), spec), format(max(values), spec)
    return low if low == high else f"{low}-{high}"


def _plane(result: dict[str, Any]) -> str:
    worst = {}
    for method in ("centroid", "gaussian", "steger"):
        rows = [r for r in result["plane"] if r["method"] == method]
        worst[method] = max(rows, key=lambda r: r["rms_px"])
    c = worst["centroid"]
    tilt = max(abs(c["roll_deg"]), abs(c["pitch_deg"]))
    return (
        f"worst RMS {c['rms_px']:.3f} px (centroid at {tilt:g} deg), Gaussian fit <= "
        f"{worst['gaussian']['rms_px']:.4f} px, Steger <= {worst['steger']['rms_px']:.3f} px"
    )


def _speckle(result: dict[str, Any]) -> str:
    cells = [f"f/{r['f_number']:g}: {r['centroid_ratio']:.2f}" for r in result["speckle"]]
    return ", ".join(cells) + " times the formula"


def _speckle_sweep(result: dict[str, Any]) -> str:
    rows: Rows = result["speckle_sweep"]
    within = sum(0.7 <= r["spot_ratio"] <= 1.3 for r in rows)
    coarse = max(r["pixel_pitch_um"][0] for r in rows)
    fine = [r["vs_line_formula"] for r in rows if r["pixel_pitch_um"][0] < coarse]
    wide = [r["vs_line_formula"] for r in rows if r["pixel_pitch_um"][0] == coarse]
    column = [r["centroid_ratio"] for r in rows]
    return (
        f"a patch of the line as long as it is wide: within 30 % of Dorsch's spot (C = 1/sqrt 2) "
        f"in {within} of {len(rows)} cases, the rest explained below; one column: "
        f"{_span(fine, '.2f')} times the line's own speckle formula on the finer pixels "
        f"({_span(wide, '.2f')} on {coarse:.0f} um pixels, where a narrow stripe falls on one "
        f"or two pixels); the column against Dorsch's C = 1 grows with the line, "
        f"{_span(column, '.2f')} (physics, not a fault: below)"
    )


def _false_stripe(result: dict[str, Any]) -> str:
    rows: Rows = result["false_stripe"]
    return (
        f"within {max(r['max_error_mm'] for r in rows):.3f} mm (median "
        f"{_span([r['median_error_mm'] for r in rows], '.4f')} mm) over "
        f"{_span([r['columns_compared'] for r in rows], 'd')} columns"
    )


def _rate(rows: Rows, joint: str, profile: str) -> str:
    found = [r["detection_rate"] for r in rows if r["joint"] == joint and r["profile"] == profile]
    return f"{100 * found[0]:.0f} %" if found else "-"


def _always_found(rows: Rows, key: str) -> tuple[list[str], list[str]]:
    """The values of ``key`` in row order, and those whose every row has a detection rate of 1
    (the rest, in the same order, are the first list less the second)."""
    values = list(dict.fromkeys(r[key] for r in rows))
    return values, [v for v in values if all(r["detection_rate"] == 1 for r in rows if r[key] == v)]


def _extractors(result: dict[str, Any]) -> str:
    rows: Rows = result["extractors"]
    images = ("image, mill-scale steel", "image, bright aluminium")
    joints, every = _always_found(rows, "joint")
    rest = [j for j in joints if j not in every]
    p95_image = [r["p95_error_mm"] for r in rows if r["joint"] in every and r["profile"] in images]
    p95_geometry = [r["p95_error_mm"] for r in rows if r["profile"] == "geometry"]
    text = (
        f"detected 100 % in both modes for {', '.join(every)} (p95 {_span(p95_image, '.2f')} mm "
        f"in image mode against {max(p95_geometry):.3f} mm or less from geometry)"
    )
    for joint in rest:
        text += (
            f"; {joint} {_rate(rows, joint, 'geometry')} from geometry, "
            f"{_rate(rows, joint, images[0])} / {_rate(rows, joint, images[1])} from images"
        )
    return text


def _throughput(result: dict[str, Any]) -> str:
    t = result["throughput"]
    ideal, full, geometry = t["ideal"], t["full"], t["geometry"]
    return (
        f"{ideal['images_per_s']:.0f} images/s ideal, {full['images_per_s']:.0f} images/s with "
        f"speckle at f/8; an image-mode frame (render, detect, extract) costs "
        f"{ideal['cost_vs_geometry']:.0f}x (ideal) to {full['cost_vs_geometry']:.0f}x a "
        f"geometry-mode frame ({ideal['frame_ms']:.1f} / {full['frame_ms']:.1f} ms against "
        f"{geometry['frame_ms']:.2f} ms)"
    )


def _image_sets(result: dict[str, Any]) -> str:
    rows: Rows = result["image_sets"]
    materials = ("bright aluminium", "mill-scale steel")
    families, every = _always_found(rows, "family")
    found = [r for r in rows if r["family"] in every]

    def rates(family: str) -> str:
        by = {r["material"]: r["detection_rate"] for r in rows if r["family"] == family}
        return " / ".join(f"{100 * by[m]:.0f} %" if m in by else "-" for m in materials)

    text = (
        f"{' / '.join(materials)}: {', '.join(every)} 100 % (median "
        f"{_span([r['median_error_mm'] for r in found], '.3f')} mm, p95 "
        f"{_span([r['p95_error_mm'] for r in found], '.2f')} mm)"
    )
    text += "".join(f", {f} {rates(f)}" for f in families if f not in every)
    false = max(r["false_joint_rate"] for r in rows)
    return text + f"; false joints from the other families' extractors {false:g} on every set"


#: The requirements, each with the function that reads its figures from ``camera.json``.
MUST_SHOW: tuple[tuple[str, Callable[[dict[str, Any]], str]], ...] = (
    (
        "ideal camera, matte plate tilted 0-60 deg about both axes, each detector within "
        "0.05 px RMS of the analytic plane section",
        _plane,
    ),
    (
        "speckle alone, 0.1 mm line, range noise of the centroid against Dorsch et al. (1994) "
        "dz = lambda / (2 pi sin u_obs sin theta), C = 1",
        _speckle,
    ),
    (
        "speckle over line width 0.05-0.5 mm, f/2-f/16, pixel pitch 2.5-10 um "
        "([below](#speckle-against-line-width))",
        _speckle_sweep,
    ),
    (
        "false stripe on bright aluminium (laser pitched 12-20 deg) against mirror geometry "
        "solved on the bevels' planes",
        _false_stripe,
    ),
    (
        "extractors, 20 poses per joint family, geometry vs image mode (mill-scale / bright "
        "aluminium)",
        _extractors,
    ),
    ("throughput, 1024 x 512, one core (CPU time)", _throughput),
    (
        "the image-mode profiles as labelled sets of the real-data bench (`seamtrack "
        "extractors bench --real`, issue 15 item 4): label = the CAD seam's crossing of the "
        "laser plane",
        _image_sets,
    ),
    (
        "bad input (f-number <= 0, wavelength outside 200-2000 nm, a line wider than the field, "
        "an unknown material, detector or preset)",
        lambda result: "one line naming the field, exit 2 (`seamtrack bench failures`)",
    ),
)


def must_show_table(result: dict[str, Any]) -> str:
    """docs/camera.md's table of what image mode must show and what the bench measured."""
    lines = ["| must show | measured |", "|---|---|"]
    lines += [f"| {need} | {measured(result)} |" for need, measured in MUST_SHOW]
    return "\n".join(lines) + "\n"
