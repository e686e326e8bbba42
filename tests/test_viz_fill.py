"""Views of a fill: the cross-section's bead polygons, the GIF's frames, the 3D view's fill."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.workpiece.beads import BeadShape, polygon_area_mm2
from seamtrack.workpiece.fill import FillState

TAN30 = math.tan(math.radians(30))


@pytest.fixture(scope="module")
def filled() -> FillState:
    s = np.arange(0.0, 10.0 + 1e-9, 0.5)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-20.0, 20.0 + 1e-9, 0.05)
    z = np.clip((np.abs(y) - 1.0) / TAN30, 0.0, 12.0)
    state = FillState.from_profiles(s, frames, y, np.repeat(z[None], len(s), 0))
    path = np.column_stack([np.linspace(-1, 11, 50), np.zeros(50), np.full(50, 15.0)])
    for offset, area in ((0.0, 20.0), (-2.5, 18.0), (2.5, 18.0), (0.0, 22.0)):
        state = state.deposit(path, np.full(50, area), BeadShape(), offset_mm=offset)
    return state


def test_section_plot_draws_each_bead_with_its_area(filled, tmp_path) -> None:
    from seamtrack.viz.fill import draw_fill_section, plot_fill_section
    from seamtrack.viz.plots import pyplot_module

    plt = pyplot_module()
    fig, ax = plt.subplots()
    patches = draw_fill_section(ax, filled, 7)
    areas = [polygon_area_mm2(p.get_xy()) for p in patches]
    assert areas == pytest.approx([20.0, 18.0, 18.0, 22.0], rel=1e-6)
    colors = {tuple(p.get_facecolor()) for p in patches}
    assert len(colors) == 4  # one colour per pass
    plt.close(fig)
    out = plot_fill_section(filled, 7, tmp_path / "section.png")
    assert out.stat().st_size > 1000


def test_fill_gif_has_one_frame_per_pass(filled, tmp_path) -> None:
    from PIL import Image

    from seamtrack.viz.fill import animate_fill

    out = animate_fill(filled, 3, tmp_path / "fill.gif")
    with Image.open(out) as gif:
        assert gif.n_frames == filled.n_passes


def test_3d_view_shows_the_fill_coloured_by_pass(filled, tmp_path) -> None:
    pv = pytest.importorskip("pyvista")
    import trimesh

    from seamtrack.viz.fill import fill_plotter, render_fill_png

    plate = trimesh.creation.box(extents=[10, 40, 5])
    plate.apply_translation([5, 0, -2.5])
    plotter = fill_plotter(filled, plate, off_screen=True, window_size=(400, 300))
    try:
        fill = plotter.actors["fill"].mapper.dataset
        assert fill.n_cells == len(filled.mesh().faces)
        passes = np.unique(fill.point_data["pass"])
        assert set(passes.tolist()) <= {0, 1, 2, 3, 4}
        # The last bead (centred) forms the top at the centre line; the seal nodes have none.
        top = np.array([3.5, 0.0, filled.surface_z[7, len(filled.y_mm) // 2]])
        nearest = np.argmin(np.linalg.norm(np.asarray(fill.points) - top, axis=1))
        assert fill.point_data["pass"][nearest] == 4
        assert 0 in passes
    finally:
        plotter.close()
    out = render_fill_png(filled, plate, tmp_path / "fill.png", window_size=(400, 300))
    image = np.asarray(pv.read(str(out)).point_data.active_scalars)
    assert image.shape[0] == 400 * 300
