"""Section 2 of ``seamtrack bench camera``: laser speckle's range noise over line width,
aperture and pixel pitch, against Dorsch, Haeusler and Herrmann (1994) and against the
statistics of fully developed speckle for one image column of a line (issue 27 item 2).

Dorsch's dz = C lambda / (2 pi sin u_obs sin theta) holds for a spot's centroid whatever the
spot's size: a wider spot holds more grains (in two dimensions) and the two cancel. One image
column of a laser line averages the grains across the stripe only, so its centroid's noise grows
as the square root of the stripe's width (:func:`line_speckle_mm`); a square patch of the line
is Dorsch's spot again (:data:`SPOT_C`). The sweep measures all three.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from seamtrack.bench.camera_parts import SENSOR, down, plate
from seamtrack.sensing.camera import Camera

GRID: dict[str, Any] = {"rows": 512, "columns": 1024}


# --------------------------------------------------------------------------- the plate
def dorsch_mm(f_number: float, wavelength_nm: float = 660.0) -> float:
    """dz = lambda / (2 pi sin u_obs sin theta) at the range centre (C = 1); the pupil is
    lambda_camera / N across, seen from b / sin(theta)."""
    distance = SENSOR.baseline_mm / math.sin(SENSOR.angle_rad)
    sin_u = 0.5 * SENSOR.focal_length_mm / f_number / distance
    return wavelength_nm * 1e-6 / (2 * math.pi * sin_u * math.sin(SENSOR.angle_rad))


def speckle_noise(
    f_number: float,
    thickness_mm: float,
    seeds: int,
    grid: dict[str, Any] = GRID,
    methods: tuple[str, ...] = ("centroid", "gaussian", "steger"),
    spot_columns: int = 0,
) -> dict[str, Any]:
    """Range noise of each detector on a plate across the laser, speckle alone; with
    ``spot_columns``, also of the centroid averaged over that many neighbouring columns."""
    cam = Camera.ideal(
        speckle=True, f_number=f_number, line_thickness_mm=thickness_mm, exposure=0.1, **grid
    )
    errors: dict[str, list[np.ndarray]] = {m: [] for m in methods}
    spots: list[np.ndarray] = []
    for seed in range(seeds):
        image = SENSOR.render(plate(), down(), camera=cam, material="white matte", seed=seed)
        truth = image.truth_laser[:, 1]
        for method, store in errors.items():
            profile = image.profile(method=method, threshold=0.0)
            ok = profile.valid & np.isfinite(truth)
            store.append(profile.points_laser[ok, 1] - truth[ok])
            if method == "centroid" and spot_columns:
                error = np.where(ok, profile.points_laser[:, 1] - truth, np.nan)
                window = np.lib.stride_tricks.sliding_window_view(error, spot_columns)
                spots.append(window.mean(axis=1)[np.isfinite(window).all(axis=1)])
    predicted = dorsch_mm(f_number)
    row: dict[str, Any] = {
        "f_number": f_number,
        "line_thickness_mm": thickness_mm,
        "seeds": seeds,
        "dorsch_mm": predicted,
    }
    for method, store in errors.items():
        sigma = float(np.sqrt(np.mean(np.concatenate(store) ** 2)))
        row[f"{method}_mm"], row[f"{method}_ratio"] = sigma, sigma / predicted
    if spots:
        sigma = float(np.sqrt(np.mean(np.concatenate(spots) ** 2)))
        row["spot_columns"], row["spot_mm"] = spot_columns, sigma
        row["spot_ratio"] = sigma / (SPOT_C * predicted)
    return row


def envelope_sigma_mm(f_number: float, thickness_mm: float, grid: dict[str, Any]) -> float:
    """The mean stripe's standard deviation across the rows on the chip (mm): the speckle-free
    image (line profile and diffraction blur), its per-column second moment less a pixel's."""
    cam = Camera.ideal(
        speckle=False, f_number=f_number, line_thickness_mm=thickness_mm, exposure=0.1, **grid
    )
    image = SENSOR.render(plate(), down(), camera=cam, material="white matte", seed=0)
    pixels = image.pixels.astype(np.float64)
    r = np.arange(pixels.shape[0])[:, None]
    total = pixels.sum(axis=0)
    ok = total > 0
    mean = (pixels * r).sum(axis=0)[ok] / total[ok]
    var = ((pixels[:, ok] * (r - mean) ** 2).sum(axis=0) / total[ok]) - 1.0 / 12.0
    pitch_h = cam.imaging_sensor(SENSOR).pixel_pitch_mm[0]
    return math.sqrt(max(float(np.median(var)), 0.0)) * pitch_h


def line_speckle_mm(f_number: float, thickness_mm: float, grid: dict[str, Any]) -> float:
    """The centroid's speckle noise for a laser *line*, one image column at a time, from the
    statistics of fully developed speckle (Goodman): Cov(I(r), I(r')) = <I(r)><I(r')> |mu|^2
    with |mu(r)|^2 = (2 J1(pi r / lambda N) / (pi r / lambda N))^2 for the circular pupil. For a
    mean stripe of standard deviation sigma across the rows (:func:`envelope_sigma_mm`), wider
    than lambda N, the column's centroid varies by Var = L sigma / (4 sqrt(pi)) on the chip, L
    the integral of |mu|^2 across the stripe averaged over the pixel's width along it: it grows
    as sqrt(sigma), where Dorsch's spot does not. Returned in range mm (Dorsch's image-side
    lambda N / pi maps to :func:`dorsch_mm`). Independent of the renderer's field synthesis."""
    from scipy import special

    sigma = envelope_sigma_mm(f_number, thickness_mm, grid)
    pitch_v = Camera.ideal(**grid).imaging_sensor(SENSOR).pixel_pitch_mm[1]
    grain = 660e-6 * f_number
    x = np.linspace(-20 * grain, 20 * grain, 4001)
    d = np.linspace(-pitch_v, pitch_v, 201)  # y - y' over one pixel: a triangle
    weight = 1.0 - np.abs(d) / pitch_v
    weight /= weight.sum()
    a = math.pi * np.hypot(x[:, None], d[None, :]) / grain
    safe = np.where(a > 1e-9, a, 1.0)
    mu2 = np.where(a > 1e-9, (2.0 * special.j1(safe) / safe) ** 2, 1.0)
    length = float((mu2 @ weight).sum() * (x[1] - x[0]))
    chip_sigma = math.sqrt(length * sigma / (4.0 * math.sqrt(math.pi)))
    return chip_sigma / (grain / math.pi) * dorsch_mm(f_number)


#: A Gaussian spot's 2-D centroid under fully developed speckle: Var_x = A_c / (8 pi), A_c =
#: 4 (lambda N)^2 / pi the speckle's correlation area: sigma = lambda N / (pi sqrt 2), Dorsch's
#: law with C = 1 / sqrt(2) whatever the spot's size.
SPOT_C = 1.0 / math.sqrt(2.0)


def speckle_sweep_row(
    f_number: float, thickness_mm: float, grid: dict[str, Any], seeds: int
) -> dict[str, Any]:
    """Speckle-only range noise on ``grid``: the column centroid against Dorsch and against
    :func:`line_speckle_mm`; the centroids averaged over a square patch of the line (as many
    columns as the mean stripe's equivalent width 2 sqrt(pi) sigma) against Dorsch's spot."""
    cam = Camera.ideal(speckle=True, f_number=f_number, **grid)
    imaging = cam.imaging_sensor(SENSOR)
    patch = 2.0 * math.sqrt(math.pi) * envelope_sigma_mm(f_number, thickness_mm, grid)
    row = speckle_noise(
        f_number, thickness_mm, seeds, grid, methods=("centroid",),
        spot_columns=max(1, round(patch / imaging.pixel_pitch_mm[1])),
    )  # fmt: skip
    line = line_speckle_mm(f_number, thickness_mm, grid)
    row.update(
        image_px=[grid["rows"], grid["columns"]],
        pixel_pitch_um=[1e3 * p for p in imaging.pixel_pitch_mm],
        supersample=cam.supersampling(imaging),
        line_formula_mm=line,
        vs_line_formula=row["centroid_mm"] / line,
    )
    return row


def speckle_sweep(quick: bool) -> list[dict[str, Any]]:
    """Section 2 over pixel pitch (the image's size on the same chip), f-number, line width."""
    widths = (0.05, 0.2, 0.5) if quick else (0.05, 0.1, 0.2, 0.5)
    stops = (2.0, 5.6, 16.0) if quick else (2.0, 2.8, 4.0, 5.6, 8.0, 11.0, 16.0)
    grids = ((256, 512), (512, 1024)) if quick else ((256, 512), (512, 1024), (1024, 2048))
    return [
        speckle_sweep_row(f_number, width, {"rows": r, "columns": c}, 1 if quick else 2)
        for (r, c), f_number, width in itertools.product(grids, stops, widths)
    ]


def speckle_sweep_table(rows: list[dict[str, Any]], table: Any) -> list[str]:
    """Section 2's sweep: the column centroid against Dorsch (C = 1) and against the line's
    own formula (:func:`line_speckle_mm`); the centroid over a square patch of the line
    against Dorsch's spot (C = 1 / sqrt 2, :data:`SPOT_C`)."""
    if not rows:
        return []
    lines = [
        "",
        "Sweep over pixel pitch, aperture and line width (one image column's centroid; a "
        "patch: the centroids averaged over as many columns as the stripe is wide):",
        "",
    ]
    return lines + table(
        [
            "pixels",
            "pitch um",
            "sub-px",
            "f-number",
            "line mm",
            "column / Dorsch",
            "column / line formula",
            "patch cols",
            "patch / Dorsch spot",
        ],
        [
            [
                f"{r['image_px'][0]} x {r['image_px'][1]}",
                f"{r['pixel_pitch_um'][0]:.3g} x {r['pixel_pitch_um'][1]:.3g}",
                r["supersample"],
                r["f_number"],
                r["line_thickness_mm"],
                r["centroid_ratio"],
                r["vs_line_formula"],
                r["spot_columns"],
                r["spot_ratio"],
            ]
            for r in rows
        ],
    )


def speckle_summary_table(result: dict[str, Any]) -> str:
    """docs/camera.md's summary of the speckle sweep (a ``camera.json``): per chip, the range of
    each ratio over line widths and f-numbers, and the camera's default 0.2 mm line at 512 x
    1024, f/2.8, 5.6 and 11."""
    rows = result["speckle_sweep"]
    keys = ("centroid_ratio", "vs_line_formula", "spot_ratio")
    lines = [
        "| pixels (pitch um) | column / Dorsch (C = 1) | column / line formula "
        "| patch / Dorsch spot |",
        "|---|---|---|---|",
    ]
    for px in sorted({tuple(r["image_px"]) for r in rows}):
        chip = [r for r in rows if tuple(r["image_px"]) == px]
        pitch = chip[0]["pixel_pitch_um"]
        cells = [f"{min(r[k] for r in chip):.2f}-{max(r[k] for r in chip):.2f}" for k in keys]
        lines.append(
            f"| {px[0]} x {px[1]} ({pitch[0]:.1f} x {pitch[1]:.1f}) | " + " | ".join(cells) + " |"
        )
    stops = (2.8, 5.6, 11.0)
    default = {
        r["f_number"]: r
        for r in rows
        if tuple(r["image_px"]) == (512, 1024) and r["line_thickness_mm"] == 0.2
    }
    if all(f in default for f in stops):
        cells = [" / ".join(f"{default[f][k]:.2f}" for f in stops) for k in keys]
        lines.append(
            "| the camera's default 0.2 mm line, 512 x 1024, f/2.8 / 5.6 / 11 | "
            + " | ".join(cells)
            + " |"
        )
    return "\n".join(lines) + "\n"
