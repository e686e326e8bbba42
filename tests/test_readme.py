"""The README's Python blocks run as written, in order, and do what their comments say."""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import seamtrack as st

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks() -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", README.read_text(), flags=re.S | re.M)


def _module_blocks() -> dict[str, str]:
    """Blocks that are files of the user's own (their first line names the file)."""
    found = {}
    for block in _blocks():
        first = block.splitlines()[0]
        if first.startswith("# ") and first.endswith(".py"):
            found[first[2:]] = block
    return found


@pytest.fixture(scope="module")
def tour(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    namespace: dict[str, Any] = {}
    cwd = Path.cwd()
    os.chdir(tmp_path_factory.mktemp("readme"))
    try:
        for block in _blocks():
            exec(compile(block, str(README), "exec"), namespace)
    finally:
        os.chdir(cwd)
    return namespace


def test_the_python_tour_runs_and_its_comments_hold(tour: dict[str, Any]) -> None:
    assert tour["result"].status == "completed"
    assert tour["sensor"].depth_of_field_mm == pytest.approx(60.0)
    assert np.allclose(tour["y_L"], [0.0, 5.0], atol=1e-9)
    assert np.allclose(tour["z_L"], [90.0, 100.0], atol=1e-9)
    feature = tour["feature"]
    assert feature  # the v-groove extractor found the seam in the scanned stripe
    assert tour["part"].seam.closest(feature.point_world).distance_mm[0] < 0.05
    # Camera images: the same extractor on the profile measured from the rendered image.
    assert tour["image"].pixels.shape == (512, 1024)
    assert tour["seam_point"]
    assert tour["part"].seam.closest(tour["seam_point"].point_world).distance_mm[0] < 0.1
    assert len(tour["ideal"].truth_row) == 1024 and tour["ideal"].reflection.dtype == bool


def test_the_tracker_example_tracks_the_paper_seam(
    tmp_path: Path, monkeypatch, request: pytest.FixtureRequest
) -> None:
    blocks = _module_blocks()
    assert "my_trackers.py" in blocks
    (tmp_path / "my_trackers.py").write_text(blocks["my_trackers.py"])
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "my_trackers", raising=False)
    request.addfinalizer(lambda: sys.modules.pop("my_trackers", None))  # other tests' module
    scene = st.load_scene(
        "paper-verification",
        {
            "seam.length_mm": 40.0,
            "tracker.name": "my_trackers:FollowNewest",
            "tracker.params.slow_factor": 0.5,
        },
    )
    result = st.simulate(scene)
    assert result.status == "completed"
    assert result.summary["max_error_mm"] < 1.0


def test_the_extractor_example_finds_the_deepest_point(tour: dict[str, Any]) -> None:
    blocks = _module_blocks()
    assert "mypkg/mymod.py" in blocks
    namespace: dict[str, Any] = {}
    exec(compile(blocks["mypkg/mymod.py"], "mymod.py", "exec"), namespace)
    profile = tour["profile"]
    feature = namespace["DeepestPoint"]()(profile)
    assert feature
    deepest = profile.valid_points[:, 1].max()
    assert feature.point_laser[1] == deepest
    assert not namespace["DeepestPoint"](min_points=10**6)(profile)  # fails with a reason
