"""``seamtrack init`` writes every key of the resolved scene, each under a comment saying what
it means, and the file loads back to the same scene (docs/scenes.md: "complete, every key
commented")."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest
from cli_helpers import run_cli

from seamtrack.simulation.scene import builtin_scenes, load_scene
from seamtrack.simulation.scene_help import KEY_HELP, commented_scene, schema_keys


def flat_keys(data: dict[str, Any], prefix: str = "") -> set[str]:
    """Every key of a TOML document by dotted path (a list of tables by the table's path)."""
    keys = set()
    for name, value in data.items():
        path = prefix + name
        keys.add(path)
        if isinstance(value, dict):
            keys |= flat_keys(value, path + ".")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                keys |= flat_keys(item, path + ".")
    return keys


def written_keys(text: str) -> dict[str, str]:
    """Each key and table written in a file (not commented out) -> the line before it."""
    keys: dict[str, str] = {}
    table = ""
    lines = text.splitlines()
    for before, line in zip(["", *lines], lines, strict=False):
        if line.startswith("["):
            table = line.strip("[]")
            keys[table] = before
        elif line and not line.startswith("#") and "=" in line:
            keys[(table + "." if table else "") + line.split("=")[0].strip()] = before
    return keys


def test_every_key_of_the_schema_is_described_and_no_description_is_stale() -> None:
    keys = schema_keys()
    assert sorted(set(keys) - set(KEY_HELP)) == []
    assert sorted(set(KEY_HELP) - set(keys)) == []
    assert all(len(KEY_HELP[k]) > 10 for k in keys)


@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_the_commented_scene_has_every_resolved_key_under_a_comment(
    name: str, tmp_path: Path
) -> None:
    scene = load_scene(name)
    text = commented_scene(scene)
    resolved = flat_keys(tomllib.loads(scene.to_toml()))  # what a run's scene.toml holds
    written = written_keys(text)
    assert sorted(resolved - set(written)) == []
    for key in resolved:
        assert written[key].startswith("# "), (key, written[key])
    # and it is the same scene
    target = tmp_path / f"{name}.toml"
    target.write_text(text)
    assert load_scene(str(target)).config == scene.config


def test_init_writes_a_complete_commented_scene_that_loads_back(tmp_path: Path) -> None:
    target = tmp_path / "corner.toml"
    res = run_cli("init", "paper-corner", "-o", str(target), "--set", "tracker.radius_mm=0.5")
    assert res.returncode == 0, res.stderr
    text = target.read_text()
    expected = load_scene("paper-corner", {"tracker.radius_mm": 0.5})
    assert load_scene(str(target)).config == expected.config
    resolved = flat_keys(tomllib.loads(expected.to_toml()))
    written = written_keys(text)
    assert sorted(resolved - set(written)) == []
    comments = [line for line in text.splitlines() if line.startswith("# ")]
    assert len(comments) >= len(resolved)
    assert text.startswith("# A seam with a sharp corner")  # the template's own opening
