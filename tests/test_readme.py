"""The README: short, the two commands first, its Python tour runs and does what its comments
say, and its headline figures are what the benches' JSON says (``docs/figures.py --check``).

The text that moved into the documentation site is checked in ``tests/test_docs.py``."""

from __future__ import annotations

import importlib.util
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def python_blocks(path: Path) -> list[str]:
    """The ```python blocks of a Markdown file, in order."""
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), flags=re.S | re.M)


def _figures() -> Any:
    spec = importlib.util.spec_from_file_location("figures", ROOT / "docs" / "figures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_is_short_and_starts_with_the_two_commands() -> None:
    lines = README.read_text().splitlines()
    assert len(lines) <= 300
    head = "\n".join(lines[:40])
    assert "make demo" in head and "make test" in head


def test_the_readme_links_only_to_files_that_exist() -> None:
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README.read_text())
    assert targets
    missing = [t for t in targets if "://" not in t and not (ROOT / t).exists()]
    assert not missing


@pytest.fixture(scope="module")
def tour(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    namespace: dict[str, Any] = {}
    cwd = Path.cwd()
    os.chdir(tmp_path_factory.mktemp("readme"))
    try:
        for block in python_blocks(README):
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
    assert tour["env"].observation_space.contains(tour["obs"])  # the Gymnasium block
    assert tour["reward"] <= 0.0 and not tour["truncated"]


def test_the_headline_figures_are_the_benches_json() -> None:
    """The README's table is rendered from docs/bench/*/*.json: written by hand, or left stale
    after a bench's re-run, it differs, and this fails."""
    figures = _figures()
    table = figures.readme_table(README.read_text())
    assert figures.main(["--check"]) == 0
    assert table == figures.headline()
    assert "(no figure" not in table  # every bench's JSON was read
    rows = [line for line in table.splitlines()[2:] if line.startswith("| ")]
    assert len(rows) == len(figures.HEADLINE)
    assert all(row.count(" | ") == 2 and row.endswith("` |") for row in rows)


def test_the_check_fails_on_a_figure_copied_by_hand(tmp_path: Path, monkeypatch) -> None:
    figures = _figures()
    text = README.read_text()
    edited = tmp_path / "README.md"
    edited.write_text(text.replace("| bad input | ", "| bad input | 1 of 1 fine; ", 1))
    monkeypatch.setattr(figures, "README", edited)
    assert figures.main(["--check"]) == 1
