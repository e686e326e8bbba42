"""The documentation site's pages (``docs/*.md``): their Python examples run as written and do
what their comments say, the tracker and extractor examples work as plugins, and the measured
figures page is rendered from every bench's JSON.

The site's build itself (``make docs``: ``mkdocs build --strict``, the gallery's examples
executed) runs in ``make test``; these tests need no MkDocs."""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import seamtrack as st

DOCS = Path(__file__).resolve().parents[1] / "docs"
#: Pages whose Python blocks run here (in order, one namespace per page; README.md from the
#: repository's root). Left out: cad.md (reads a STEP file of the user's; its commands are
#: covered by tests/test_cad.py), ros.md (its client needs a server; tests/test_bridge*.py),
#: multipass.md (a planner file of the user's; tests/test_job*.py), trackers.md (its block is
#: a plugin file, run below). sweeps.md and views.md run in their own tests below (once: they
#: take a while).
RUN = (
    "index.md",
    "README.md",
    "mesh-mode.md",
    "camera.md",
    "weldments.md",
    "datasets.md",
    "extractors.md",
    "multipass-geometry.md",
    "gym.md",
    "inspection.md",
    "heat.md",
)


def page_path(name: str) -> Path:
    """A page of the docs, or the README at the repository's root."""
    return DOCS / name if (DOCS / name).is_file() else DOCS.parent / name


def python_blocks(path: Path) -> list[str]:
    """The ```python blocks of a Markdown file, in order."""
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), flags=re.S | re.M)


def _module_blocks() -> dict[str, str]:
    """Blocks that are files of the user's own (their first line names the file)."""
    found = {}
    for page in sorted(DOCS.glob("*.md")):
        for block in python_blocks(page):
            first = block.splitlines()[0]
            if first.startswith("# ") and first.endswith(".py"):
                found[first[2:]] = block
    return found


def _run_page(name: str, tmp_path: Path) -> dict[str, Any]:
    namespace: dict[str, Any] = {}
    cwd = Path.cwd()
    os.chdir(tmp_path)
    try:
        for block in python_blocks(page_path(name)):
            if block in _module_blocks().values():
                continue
            exec(compile(block, str(page_path(name)), "exec"), namespace)
    finally:
        os.chdir(cwd)
    return namespace


@pytest.mark.parametrize("page", RUN)
def test_the_pages_python_blocks_run(page: str, tmp_path: Path) -> None:
    assert python_blocks(page_path(page)), f"{page} has no Python example left to run"
    _run_page(page, tmp_path)


@pytest.mark.parametrize("page", ["index.md", "README.md"])
def test_the_tour_gives_what_its_comments_say(page: str, tmp_path: Path) -> None:
    ns = _run_page(page, tmp_path)
    assert ns["sensor"].baseline_mm == pytest.approx(26.41, abs=0.005)  # "26.41 mm, 60 mm"
    assert ns["sensor"].depth_of_field_mm == pytest.approx(60.0)
    np.testing.assert_allclose(ns["y_L"], [0.0, 5.0], atol=1e-9)  # "and back"
    np.testing.assert_allclose(ns["z_L"], [90.0, 100.0], atol=1e-9)
    assert ns["result"].summary["status"] == "completed"
    assert ns["feature"]  # the CAD seam found by the stripe
    assert ns["part"].seam.closest(ns["feature"].point_world).distance_mm[0] < 0.05


def test_the_sweeps_example_gives_one_row_per_value(tmp_path: Path) -> None:
    ns = _run_page("sweeps.md", tmp_path)
    assert [row["value"] for row in ns["table"]] == [6, 5, 1, 0.1]
    assert len(ns["rows"]) == 2  # the Dask block: two cases
    assert (tmp_path / "runs" / "t4" / "results.jsonl").is_file()


def test_the_views_example_writes_its_images(tmp_path: Path) -> None:
    pytest.importorskip("pyvista")
    ns = _run_page("views.md", tmp_path)
    for name in ("view.png", "run.png", "run.gif"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert ns["feature"]


def test_the_pages_bench_tables_are_what_their_json_renders() -> None:
    spec = importlib.util.spec_from_file_location("figures", DOCS / "figures.py")
    assert spec is not None and spec.loader is not None
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    found = {}
    for page in figures.pages():
        for source, written, rendered in figures.page_tables(page.read_text()):
            assert written == rendered, (
                f"{page.name}: {source} is stale; python docs/figures.py --write"
            )
            found[page.name] = source
    assert found.get("trackers.md") == "bench/trackers/trackers.json"


def test_mesh_mode_example_finds_the_cad_seam(tmp_path: Path) -> None:
    ns = _run_page("mesh-mode.md", tmp_path)
    assert ns["feature"]
    assert ns["part"].seam.closest(ns["feature"].point_world).distance_mm[0] < 0.05


def test_camera_example_measures_the_seam_from_pixels(tmp_path: Path) -> None:
    ns = _run_page("camera.md", tmp_path)
    assert ns["image"].pixels.shape == (512, 1024)
    assert ns["seam_point"]
    assert ns["part"].seam.closest(ns["seam_point"].point_world).distance_mm[0] < 0.1
    assert len(ns["ideal"].truth_row) == 1024 and ns["ideal"].reflection.dtype == bool


def test_weldment_example_lists_the_bracket_seams(tmp_path: Path) -> None:
    ns = _run_page("weldments.md", tmp_path)
    assert [(s.id, s.joint, s.name) for s in ns["seams"][:1]] == [("s1", "lap", "base/strap/0")]


def test_dataset_example_gives_what_its_comments_say(tmp_path: Path) -> None:
    ns = _run_page("datasets.md", tmp_path)
    assert (len(ns["data"]), ns["data"].spec.rays) == (64, 256)
    assert ns["sample"]["points_laser"].shape == (256, 2)
    assert ns["sample"]["seam_point_laser"].shape == (2,)
    assert ns["batch"]["points_laser"].shape == (32, 256, 2)


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


def test_the_extractor_example_finds_the_deepest_point(tmp_path: Path) -> None:
    blocks = _module_blocks()
    assert "mypkg/mymod.py" in blocks
    namespace: dict[str, Any] = {}
    exec(compile(blocks["mypkg/mymod.py"], "mymod.py", "exec"), namespace)
    profile = _run_page("mesh-mode.md", tmp_path)["profile"]
    feature = namespace["DeepestPoint"]()(profile)
    assert feature
    valid = profile.valid_points
    deepest = valid[np.isfinite(valid).all(axis=1), 1].max()
    assert feature.point_laser[1] == deepest
    assert not namespace["DeepestPoint"](min_points=10**6)(profile)  # fails with a reason


def test_the_figures_page_renders_every_bench(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("figures", DOCS / "figures.py")
    assert spec is not None and spec.loader is not None
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    page = figures.figures_page()
    for name, (files, _, _) in figures.BENCHES.items():
        for file in files:
            assert (DOCS / "bench" / name / file).is_file(), f"bench {name} wrote no {file}"
            assert f"From `docs/bench/{name}/{file}`" in page
    assert "No `" not in page


def test_make_test_builds_the_site_with_warnings_as_errors() -> None:
    makefile = (DOCS.parent / "Makefile").read_text()
    build = re.search(r"^DOCS_BUILD := (.*)$", makefile, flags=re.M)
    assert build and "mkdocs build --strict" in build.group(1)
    for target in ("docs", "test"):
        recipe = re.search(rf"^{target}:.*\n((?:\t.*\n)+)", makefile, flags=re.M)
        assert recipe and "$(DOCS_BUILD)" in recipe.group(1), target
    assert "site_dir: build/site" in (DOCS.parent / "mkdocs.yml").read_text()  # git-ignored
    assert "build/" in (DOCS.parent / ".gitignore").read_text().splitlines()


def test_multipass_geometry_example_lays_a_bead_of_its_area(tmp_path: Path) -> None:
    from seamtrack.workpiece.beads import bead_polygon, polygon_area_mm2

    ns = _run_page("multipass-geometry.md", tmp_path)
    assert polygon_area_mm2(bead_polygon(ns["first"], ns["second"])) == pytest.approx(24.4)


#: Figure tables still written by hand (tables with measured decimals outside the table
#: markers), per page: a ratchet, these may only fall. Each one left is a measurement no bench
#: writes yet (a test's or a one-off command's); once a bench writes it, render it between
#: markers (docs/figures.py) and lower its count here.
HAND_WRITTEN_FIGURE_TABLES: dict[str, int] = {}

#: Tables with decimals that are no figure (nothing the code measures), per page, and why.
NOT_FIGURE_TABLES = {
    "README.md": 1,  # the documentation map (a decimal in a page's description)
    "cad.md": 1,  # parameters and their defaults
    # the families' models and refusals (their thresholds, parameters); the kernels' speed-up of
    # 2026-11-23, old code against new (history: a comparison of two versions, dated, not a
    # figure of today's code that could go stale)
    "extractors.md": 3,
    "gym.md": 1,  # the observation's slices
    "heat.md": 2,  # the materials' handbook constants and the relations used
    "inspection.md": 1,  # ISO 5817's limits
    "mesh-mode.md": 1,  # the realism knobs' models (a worked value of the dropout law)
    "paper.md": 1,  # the paper's own Table 4, quoted for comparison
    "scenes.md": 1,  # keys and their defaults
    "views.md": 1,  # the notebooks
}


def hand_written_figure_tables(text: str) -> int:
    """Tables with a decimal number in a body row that lie outside the table markers."""
    text = re.sub(r"<!-- (table: .*?) -->.*?<!-- end table -->", "", text, flags=re.S)
    text = re.sub(r"<!-- figures:begin.*?<!-- figures:end -->", "", text, flags=re.S)
    count, body = 0, []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            body.append(line)
            continue
        rows = body[2:]
        if rows and any(re.search(r"\d\.\d", row) for row in rows):
            count += 1
        body = []
    return count


def test_hand_written_figure_tables_only_fall() -> None:
    counts = {}
    for page in [DOCS.parent / "README.md", *sorted(DOCS.glob("*.md"))]:
        n = hand_written_figure_tables(page.read_text())
        if n:
            counts[page.name] = n
    allowed = {
        k: HAND_WRITTEN_FIGURE_TABLES.get(k, 0) + NOT_FIGURE_TABLES.get(k, 0) for k in counts
    }
    grown = {k: v for k, v in counts.items() if v > allowed[k]}
    assert not grown, f"new hand-written figure tables (render them from a bench): {grown}"


@pytest.mark.embree
@pytest.mark.cad
def test_the_vector_env_example_runs_as_a_script(tmp_path: Path) -> None:
    """docs/gym.md's vector-env example, saved as the file it names and run with ``python``: a
    spawned worker re-imports the script, so it needs its own ``import seamtrack.gym`` and the
    ``__main__`` guard; without either the workers fail with tracebacks."""
    pytest.importorskip("gymnasium")
    import subprocess

    blocks = _module_blocks()
    assert "vector_envs.py" in blocks
    script = tmp_path / "vector_envs.py"
    script.write_text(blocks["vector_envs.py"])
    env = {**os.environ, "PYTHONPATH": str(DOCS.parent)}
    done = subprocess.run(
        [sys.executable, script.name], cwd=tmp_path, env=env, capture_output=True, text=True,
        timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    # paper-v-groove's 1024 rays: 3 n + 9 numbers an observation, one row per environment
    assert done.stdout.startswith(f"observations (2, {3 * 1024 + 9}) rewards")
    rewards = done.stdout.split("rewards", 1)[1].strip(" []\n").split()
    assert len(rewards) == 2 and all(float(r) <= 0.0 for r in rewards)
