"""Speckle against the laser line's width (issue 27 item 2): the rendered speckle's range noise
against two analytic oracles that do not share the renderer's field synthesis.

- Dorsch, Haeusler and Herrmann (1994): a spot's centroid varies by dz = C lambda /
  (2 pi sin u_obs sin theta) whatever the spot's size; for a Gaussian spot under fully developed
  speckle C = 1 / sqrt(2) (the intensity covariance |mu|^2 of the circular pupil integrates to
  4 (lambda N)^2 / pi). A square patch of the line is such a spot.
- One image column of a line is not: its centroid averages the speckle grains across the stripe
  only, Var = L sigma / (4 sqrt(pi)), growing as the square root of the stripe's width sigma.
"""

from __future__ import annotations

import pytest

from seamtrack.bench.camera_speckle import speckle_sweep_row

pytestmark = pytest.mark.embree

GRID = {"rows": 512, "columns": 1024}


@pytest.fixture(scope="module")
def rows() -> dict[tuple[float, float], dict]:
    return {(n, w): speckle_sweep_row(n, w, GRID, seeds=2) for n in (4.0, 11.0) for w in (0.1, 0.4)}


@pytest.mark.parametrize("f_number", [4.0, 11.0])
@pytest.mark.parametrize("width_mm", [0.1, 0.4])
def test_a_patch_of_the_line_follows_dorsch_whatever_its_width(rows, f_number, width_mm) -> None:
    assert rows[f_number, width_mm]["spot_ratio"] == pytest.approx(1.0, abs=0.3)


@pytest.mark.parametrize("f_number", [4.0, 11.0])
@pytest.mark.parametrize("width_mm", [0.1, 0.4])
def test_one_column_follows_the_line_formula(rows, f_number, width_mm) -> None:
    assert rows[f_number, width_mm]["vs_line_formula"] == pytest.approx(1.0, abs=0.2)


@pytest.mark.parametrize("f_number", [4.0, 11.0])
def test_one_column_grows_with_the_line_width_as_the_formula_says(rows, f_number) -> None:
    """Four times the width: the column's noise grows (about 1.5-2x), the patch's does not."""
    thin, thick = rows[f_number, 0.1], rows[f_number, 0.4]
    growth = thick["centroid_mm"] / thin["centroid_mm"]
    assert growth > 1.3
    assert growth == pytest.approx(thick["line_formula_mm"] / thin["line_formula_mm"], rel=0.2)
    assert thick["spot_mm"] / thin["spot_mm"] == pytest.approx(1.0, abs=0.3)
