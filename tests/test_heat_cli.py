"""``seamtrack heat``: the command prints the library's field at the points asked."""

from __future__ import annotations

import numpy as np
import pytest

import seamtrack as st
from seamtrack.cli.main import main
from seamtrack.heat.materials import THERMAL_MATERIALS


@pytest.mark.parametrize("extra", [[], ["--thickness-mm", "4"],
                                   ["--thickness-mm", "4", "--model", "images"]])  # fmt: skip
def test_heat_prints_the_library_field(
    extra: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["heat", "--at", "2,6,0", "--at=-15,3,1", "--speed-mm-s", "4", "--material",
            "stainless_steel", "--voltage-v", "12", "--current-a", "150",
            "--thermal-efficiency", "0.65", *extra]  # fmt: skip
    assert main(argv) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == "x_mm,y_mm,z_mm,temperature_c"
    printed = [float(line.split(",")[3]) for line in lines[1:]]
    m = THERMAL_MATERIALS["stainless_steel"]
    kw = dict(power_w=0.65 * 12 * 150, speed_mm_s=4.0,
              conductivity_w_per_mm_k=m.conductivity_w_per_mm_k,
              diffusivity_mm2_per_s=m.diffusivity_mm2_per_s)  # fmt: skip
    points = [[2.0, 6.0, 0.0], [-15.0, 3.0, 1.0]]
    if "images" in extra:
        expected = st.image_source_temperature(points, thickness_mm=4.0, **kw)
    else:
        expected = st.rosenthal_temperature(points, thickness_mm=4.0 if extra else None, **kw)
    np.testing.assert_allclose(printed, expected, atol=5e-4)
