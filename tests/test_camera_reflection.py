"""The groove's false stripe in rendered images: the laser's first specular bounce, traced by the
renderer, against mirror geometry solved by hand on the bevels' planes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh

from seamtrack.geometry import frames
from seamtrack.sensing.camera import Camera
from seamtrack.sensing.peaks import find_peaks
from seamtrack.sensing.sensor import preset

pytestmark = pytest.mark.embree

SENSOR = preset("paper")
HALF_WIDTH, DEPTH, LENGTH, PLATE = 5.0, 5.0 * math.tan(math.radians(60.0)), 120.0, 40.0


def v_groove() -> trimesh.Trimesh:
    """A 60 deg V-groove along world x, apex at (y, z) = (0, -DEPTH), plates at z = 0."""
    section = [(-PLATE, 0.0), (-HALF_WIDTH, 0.0), (0.0, -DEPTH), (HALF_WIDTH, 0.0), (PLATE, 0.0)]
    vertices, faces = [], []
    for (y0, z0), (y1, z1) in itertools.pairwise(section):
        k = len(vertices)
        for x in (-0.5 * LENGTH, 0.5 * LENGTH):
            vertices += [(x, y0, z0), (x, y1, z1)]
        faces += [(k, k + 2, k + 1), (k + 1, k + 2, k + 3)]
    return trimesh.Trimesh(np.array(vertices, float), np.array(faces), process=False)


def pose(pitch_deg: float, lateral_mm: float) -> np.ndarray:
    """The laser pointing down, tilted by ``pitch_deg`` about world y (the travel angle of a
    look-ahead sensor), aimed at the groove 3 mm above its apex, ``lateral_mm`` off its centre."""
    R = frames.from_xyz_rpy_deg([0, 0, 0], [180.0, pitch_deg, 0.0])[:3, :3]
    target = np.array([0.0, lateral_mm, -DEPTH + 3.0])
    return frames.make(R, target - SENSOR.range_center_mm * R[:, 2])


def _plane_hit(origin, direction, point, normal):
    den = direction @ normal
    return np.inf if abs(den) < 1e-15 else float((point - origin) @ normal / den)


def mirror_oracle(T: np.ndarray, image) -> np.ndarray:
    """Per image column, where the sensor reports the false stripe: each laser ray hits the left
    bevel at P1, reflects (r = d - 2 (d.n) n), lights the right bevel at P2 (or the other way
    round); the camera sees P2 where it would see the laser-plane point on its line of sight,
    C + s (P2 - C), s = b / (b - x_P2). Solved on the planes (no mesh, no ray caster), sampled
    densely along the fan and interpolated to the column centres (a line images to a line)."""
    b = SENSOR.baseline_mm
    R, origin = T[:3, :3], T[:3, 3]
    camera = R @ np.array([b, 0, 0]) + origin
    bevels = {
        "left": (np.array([0.0, -HALF_WIDTH, 0.0]), np.array([0.0, DEPTH, HALF_WIDTH])),
        "right": (np.array([0.0, HALF_WIDTH, 0.0]), np.array([0.0, -DEPTH, HALF_WIDTH])),
    }
    bevels = {k: (p, n / np.linalg.norm(n)) for k, (p, n) in bevels.items()}

    def on(name, q):
        y = q[1] if name == "right" else -q[1]
        return 0.0 <= y <= HALF_WIDTH and abs(q[0]) <= 0.5 * LENGTH

    rows = []
    for phi in np.linspace(-0.14, 0.14, 20001):
        d = R @ np.array([0.0, math.sin(phi), math.cos(phi)])
        hits = {k: _plane_hit(origin, d, *bevels[k]) for k in bevels}
        first = min(hits, key=lambda k: hits[k])
        p1 = origin + hits[first] * d
        if not on(first, p1):
            rows.append((np.nan, np.nan))
            continue
        n1 = bevels[first][1]
        r = d - 2 * (d @ n1) * n1
        other = "right" if first == "left" else "left"
        p2 = p1 + _plane_hit(p1, r, *bevels[other]) * r
        # Seen: the camera on the lit side of the other bevel, and the first bevel not between.
        n2 = bevels[other][1]
        to_cam = camera - p2
        t_block = _plane_hit(p2, to_cam, *bevels[first])
        blocked = 1e-9 < t_block < 1.0 and on(first, p2 + t_block * to_cam)
        if not on(other, p2) or (to_cam @ n2) * (r @ n2) >= 0 or blocked:
            rows.append((np.nan, np.nan))
            continue
        q = R.T @ (p2 - origin)
        x_c, z_c = image.sensor.project(q[1] * b / (b - q[0]), q[2] * b / (b - q[0]))
        rows.append((float(x_c), float(z_c)))
    x_c, z_c = np.array(rows).T
    r0, _, c0, _ = image.window
    pitch_h, pitch_v = image.sensor.pixel_pitch_mm
    u = (x_c + 0.5 * image.sensor.chip_h_mm) / pitch_h - 0.5 - r0
    w = (z_c + 0.5 * image.sensor.chip_v_mm) / pitch_v - 0.5 - c0
    out = np.full(image.shape[1], np.nan)
    for i in range(len(u) - 1):
        if np.isfinite(w[i]) and np.isfinite(w[i + 1]) and abs(w[i + 1] - w[i]) < 1.0:
            lo, hi = sorted((w[i], w[i + 1]))
            col = math.ceil(lo)
            if col <= hi and 0 <= col < len(out) and hi > lo:
                out[col] = u[i] + (col - w[i]) / (w[i + 1] - w[i]) * (u[i + 1] - u[i])
    return out


@pytest.mark.parametrize(("pitch_deg", "lateral_mm"), [(12.0, 0.0), (20.0, 1.5), (-15.0, -1.0)])
def test_false_stripe_lies_where_the_mirror_geometry_puts_it(pitch_deg, lateral_mm) -> None:
    """Must-show 3: on bright aluminium the image holds a second stripe; its centroid,
    triangulated as the sensor does, is the mirror-geometry point to 0.01 mm."""
    T = pose(pitch_deg, lateral_mm)
    cam = Camera.ideal(rows=512, columns=1024, exposure=5.0)
    image = SENSOR.render(v_groove(), T, camera=cam, material="bright aluminium", seed=0)
    oracle = mirror_oracle(T, image)
    assert image.reflection.sum() >= 20
    peaks = find_peaks(image.pixels, 0.015)
    measured = np.full(image.shape[1], np.nan)
    for col in np.flatnonzero(image.reflection & np.isfinite(oracle)):
        mine = np.flatnonzero(peaks.column == col)
        direct = np.isfinite(image.truth_row[col]) & (
            (peaks.start[mine] - 3 <= image.truth_row[col])
            & (image.truth_row[col] <= peaks.stop[mine] + 2)
        )
        others = mine[~direct]
        if len(others):
            measured[col] = peaks.centroid[others[np.argmax(peaks.peak[others])]]
    both = np.isfinite(measured) & np.isfinite(oracle)
    # Where the false stripe ends inside a column, that column sees part of it: not compared.
    both[1:-1] &= both[:-2] & both[2:]
    both[[0, -1]] = False
    assert both.sum() >= 20, both.sum()
    # The renderer's own truth agrees with the oracle too.
    np.testing.assert_allclose(image.reflection_row[both], oracle[both], atol=0.02)
    error = np.linalg.norm(
        image.triangulate_rows(np.where(both, measured, np.nan))[both]
        - image.triangulate_rows(np.where(both, oracle, np.nan))[both],
        axis=1,
    )
    assert error.max() <= 0.01, f"max {error.max():.4f} mm over {both.sum()} columns"


def test_matte_groove_has_no_false_stripe_and_a_shiny_one_is_brighter() -> None:
    T = pose(15.0, 0.0)
    cam = Camera.ideal(rows=256, columns=512)
    matte = SENSOR.render(v_groove(), T, camera=cam, material="white matte", seed=0)
    shiny = SENSOR.render(v_groove(), T, camera=cam, material="bright aluminium", seed=0)
    assert not matte.reflection.any() and np.isnan(matte.reflection_row).all()
    assert shiny.reflection.sum() > 10


def test_groove_perpendicular_to_the_laser_reflects_onto_the_stripe_itself() -> None:
    """Without tilt the bevels' normals lie in the laser plane: the bounce stays in it and
    lights the other bevel on the laser line, so the second 'stripe' is the true one."""
    T = pose(0.0, 0.0)
    image = SENSOR.render(v_groove(), T, camera=Camera.ideal(rows=256, columns=512),
                          material="bright aluminium", seed=0)  # fmt: skip
    both = image.reflection & np.isfinite(image.truth_row)
    assert both.any()
    assert np.nanmax(np.abs(image.reflection_row[both] - image.truth_row[both])) < 0.2
