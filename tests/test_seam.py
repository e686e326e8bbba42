"""The seam polyline: the paper's Eq. 15-17, arc length, interpolation, exact closest points."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from seamtrack.errors import SeamError
from seamtrack.geometry.seam import Seam, _point_segment, paper_points


def test_paper_seam_is_eq15_to_17() -> None:
    pts = paper_points()
    assert pts.shape == (201, 3)  # X = 0..400 step 2, both ends
    assert np.allclose(pts[:, 0], np.arange(0, 401, 2))
    assert np.allclose(pts[:, 1], 10 * np.cos(pts[:, 0] * np.pi / 200))
    assert np.allclose(pts[:, 2], 10 * np.sin(pts[:, 0] * np.pi / 200))


def test_paper_seam_length_approaches_the_curve_length() -> None:
    # The curve X -> (X, 10 cos, 10 sin) has speed sqrt(1 + (pi/20)^2): length 400 sqrt(1+...).
    exact = 400 * np.sqrt(1 + (np.pi / 20) ** 2)
    coarse, fine = Seam.from_paper(2.0), Seam.from_paper(0.05)
    assert coarse.length_mm < fine.length_mm <= exact + 1e-9
    assert fine.length_mm == pytest.approx(exact, rel=1e-7)


def test_circle_distance_and_arc_length_are_analytic() -> None:
    theta = np.linspace(0, np.pi, 2001)
    r = 50.0
    seam = Seam.from_points(np.column_stack([r * np.cos(theta), r * np.sin(theta), 0 * theta]))
    rng = np.random.default_rng(3)
    phi = rng.uniform(0.05, np.pi - 0.05, 500)
    rho = rng.uniform(20, 80, 500)
    h = rng.uniform(-5, 5, 500)
    q = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), h])
    c = seam.closest(q)
    exact = np.hypot(rho - r, h)
    sag = r * (1 - np.cos(np.pi / 2000 / 2))  # chord sag of the polyline
    assert np.all(np.abs(c.distance_mm - exact) <= sag + 1e-9)
    assert np.allclose(c.arc_length_mm, r * phi, atol=r * np.pi / 2000)


def test_helix_distance_from_the_axis() -> None:
    t = np.linspace(0, 4 * np.pi, 4001)
    seam = Seam.from_points(np.column_stack([10 * np.cos(t), 10 * np.sin(t), 2 * t]))
    on_axis = np.column_stack([np.zeros(5), np.zeros(5), np.linspace(5, 20, 5)])
    assert np.allclose(seam.distance(on_axis), 10.0, atol=1e-3)


@settings(max_examples=60, deadline=None)
@given(seed=hs.integers(0, 2**32 - 1), n=hs.integers(2, 80))
def test_closest_is_exact_against_brute_force(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    # Uneven segment lengths stress the candidate search and its exactness check.
    steps = rng.normal(size=(n - 1, 3)) * rng.choice([0.01, 1.0, 50.0], size=(n - 1, 1))
    pts = np.vstack([[0, 0, 0], np.cumsum(steps, axis=0)])
    seam = Seam.from_points(pts)
    q = rng.normal(0, 30, size=(40, 3))
    brute, _ = _point_segment(q[:, None, :], pts[None, :-1], np.diff(pts, axis=0)[None])
    assert np.allclose(seam.distance(q), brute.min(axis=1), atol=1e-9)


def test_interpolation_is_linear_between_points() -> None:
    seam = Seam.from_points([[0, 0, 0], [10, 0, 0], [10, 10, 0]])
    assert np.allclose(
        seam.interpolate([0, 5, 10, 15, 20, 99]),
        [[0, 0, 0], [5, 0, 0], [10, 0, 0], [10, 5, 0], [10, 10, 0], [10, 10, 0]],
    )
    assert np.allclose(seam.tangent_at([5, 15]), [[1, 0, 0], [0, 1, 0]])


def test_default_normals_are_vertical_and_orthogonal(paper_seam: Seam) -> None:
    assert np.allclose(np.sum(paper_seam.normals * paper_seam.tangents, axis=1), 0, atol=1e-12)
    assert np.all(paper_seam.normals[:, 2] > 0.9)


def test_csv_round_trip(tmp_path, paper_seam: Seam) -> None:
    path = tmp_path / "seam.csv"
    paper_seam.to_csv(path)
    back = Seam.from_csv(path)
    assert np.allclose(back.points, paper_seam.points, atol=1e-8)
    assert np.allclose(back.normals, paper_seam.normals, atol=1e-8)


@pytest.mark.parametrize(
    "points, message",
    [
        ([[0, 0, 0], [1, np.nan, 0], [2, 0, 0]], "not finite"),
        ([[0, 0, 0]], "at least 2"),
        ([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0]], "same point"),
        ([[0, 0], [1, 0]], "shape"),
    ],
)
def test_bad_points_are_refused(points, message: str) -> None:
    with pytest.raises(SeamError, match=message) as info:
        Seam.from_points(points)
    assert info.value.fix


def test_csv_with_nan_names_the_file(tmp_path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("x_mm,y_mm,z_mm\n0,0,0\n1,nan,0\n2,0,0\n")
    with pytest.raises(SeamError, match="bad.csv"):
        Seam.from_csv(path)


def test_closest_near_matches_the_global_search(paper_seam: Seam) -> None:
    rng = np.random.default_rng(5)
    s = np.sort(rng.uniform(0, paper_seam.length_mm, 300))
    path = paper_seam.interpolate(s) + rng.normal(0, 0.5, (300, 3))
    s_near = 0.0
    for p in path:
        s_near = paper_seam.closest_near(p, s_near)
        assert s_near == pytest.approx(float(paper_seam.closest(p).arc_length_mm[0]), abs=1e-9)


def test_closest_near_follows_the_leg_it_is_on() -> None:
    """A hairpin whose return leg passes 0.5 mm from the first: near the start, the closest
    point overall is on the return leg, but the torch is on the first."""
    seam = Seam.from_points([[0, 0, 0], [50, 0, 0], [0.0, 0.5, 0]])
    assert float(seam.closest([0.0, 0.4, 0.0]).arc_length_mm[0]) > 90
    assert seam.closest_near([0.0, 0.4, 0.0], 0.0) == pytest.approx(0.0)
    assert seam.closest_near([30.0, 0.1, 0.0], 28.0) == pytest.approx(30.0)


@pytest.mark.parametrize("scale", [1e13, 1e200, 1e300])
def test_closest_of_a_far_point_is_the_seam_point_farthest_along_its_direction(
    scale: float,
) -> None:
    """A point far away (a sensor mounted 1e300 mm off, scaled overflowing every squared
    distance) gets the seam's support point in its direction, the vertex maximising p . u (an
    independent oracle), at its true distance; no IndexError."""
    seam = Seam.from_paper(2.0, 40.0)
    rng = np.random.default_rng(7)
    directions = np.vstack([np.eye(3), -np.eye(3), rng.normal(size=(6, 3))])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    found = seam.closest(scale * directions)
    for u, point, distance in zip(directions, found.points, found.distance_mm, strict=True):
        along = seam.points @ u
        if np.sort(along)[-1] - np.sort(along)[-2] < 1e-6:
            continue  # two vertices equally far along u: either is right
        np.testing.assert_allclose(point, seam.points[int(np.argmax(along))], atol=1e-6)
        assert distance == pytest.approx(scale, rel=1e-9)


def test_closest_refuses_non_finite_points() -> None:
    seam = Seam.from_paper(2.0, 40.0)
    for bad in ([np.nan, 0.0, 0.0], [0.0, np.inf, 0.0]):
        with pytest.raises(ValueError, match="finite"):
            seam.closest(bad)
