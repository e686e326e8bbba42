"""error.png's path plots: the sensed seam points do not bury the seam and torch lines."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

import seamtrack as st
from seamtrack.viz.plots import MAX_SENSED_MARKERS, draw_path, sensed_point_step


@pytest.fixture(scope="module")
def result_100_fps() -> st.Result:
    scene = st.load_scene(
        "paper-verification", {"sensor.frame_rate_hz": 100.0, "seam.length_mm": 100.0}
    )
    return st.simulate(scene)


def test_at_most_the_cap_of_sensed_points_is_drawn_under_the_lines(
    result_100_fps: st.Result,
) -> None:
    found = np.asarray(result_100_fps.trace.frames["found"], dtype=bool)
    n = int(found.sum())
    assert n > 3 * MAX_SENSED_MARKERS  # the case of the issue: thousands of frames
    fig, ax = plt.subplots()
    try:
        draw_path(ax, result_100_fps, "top")
        lines = {line.get_label(): line for line in ax.get_lines()}
        sensed = next(line for label, line in lines.items() if label.startswith("sensed"))
        drawn = len(sensed.get_xdata())
        assert drawn <= MAX_SENSED_MARKERS
        assert drawn == len(range(0, n, sensed_point_step(n)))  # every k-th, none lost between
        for name in ("seam (closest points)", "torch tip"):
            assert lines[name].get_zorder() > sensed.get_zorder()
    finally:
        plt.close(fig)


def test_few_points_are_all_drawn() -> None:
    assert sensed_point_step(MAX_SENSED_MARKERS) == 1
    assert sensed_point_step(MAX_SENSED_MARKERS + 1) == 2
    assert sensed_point_step(8000) == 40
