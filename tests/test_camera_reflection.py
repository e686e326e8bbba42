"""The groove's false stripe in rendered images: the laser's first specular bounce, traced by the
renderer, against mirror geometry solved by hand on the bevels' planes
(seamtrack.bench.camera.mirror_oracle, which the bench reports too)."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.bench.camera import false_stripe_rows, mirror_oracle, v_groove
from seamtrack.bench.camera import groove_pose as pose
from seamtrack.sensing.camera import Camera
from seamtrack.sensing.sensor import preset

pytestmark = pytest.mark.embree

SENSOR = preset("paper")


@pytest.mark.parametrize(("pitch_deg", "lateral_mm"), [(12.0, 0.0), (20.0, 1.5), (-15.0, -1.0)])
def test_false_stripe_lies_where_the_mirror_geometry_puts_it(pitch_deg, lateral_mm) -> None:
    """Must-show 3: on bright aluminium the image holds a second stripe; its centroid,
    triangulated as the sensor does, is the mirror-geometry point to 0.01 mm."""
    T = pose(pitch_deg, lateral_mm)
    cam = Camera.ideal(rows=512, columns=1024, exposure=5.0)
    image = SENSOR.render(v_groove(), T, camera=cam, material="bright aluminium", seed=0)
    oracle = mirror_oracle(T, image)
    assert image.reflection.sum() >= 20
    measured = false_stripe_rows(image, 0.015)
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
