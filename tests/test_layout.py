"""The package tree shows the data flow: one subpackage per stage, imports pointing down the
pipeline, no import cycle between modules (lazy imports inside functions count, and so do
imports for annotations only, under ``if TYPE_CHECKING:``);
no private name imported across modules; no function over the complexity bounds.

Every ``import`` and ``from ... import`` statement of every module is read with :mod:`ast`,
wherever it stands (module level, inside a function, under ``try``, under ``if TYPE_CHECKING:``).
An import ``from a.b import c`` is an edge to ``a.b.c`` when that is a module, else to ``a.b``.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import seamtrack

ROOT = Path(seamtrack.__file__).parent

#: The pipeline, bottom first: a module may import its own stage and the stages below it.
STAGES = [
    (
        "base",
        {
            "seamtrack.errors",
            "seamtrack.constants",
            "seamtrack._version",
            "seamtrack.params",
            "seamtrack.jit",
        },
    ),
    ("geometry", {"seamtrack.geometry"}),
    ("heat", {"seamtrack.heat"}),  # the arc's temperature field and the distortion it drives
    ("workpiece", {"seamtrack.workpiece", "seamtrack.cad"}),
    ("sensing", {"seamtrack.sensing"}),
    (
        "features",
        {
            "seamtrack.features",
            # the extractor families, each its own subpackage (issue 40)
            "seamtrack.features.generic",
            "seamtrack.features.groove",
            "seamtrack.features.plates",
            "seamtrack.features.vgroove",
        },
    ),
    ("control", {"seamtrack.control"}),
    ("simulation", {"seamtrack.simulation"}),
    ("multipass", {"seamtrack.multipass"}),  # the multi-pass job, pass after pass of the loop
    ("io", {"seamtrack.io"}),
    ("viz", {"seamtrack.viz"}),
    ("batch", {"seamtrack.batch"}),
    ("datasets", {"seamtrack.datasets"}),  # draws on sensing and features, uses io and batch
    ("bridge", {"seamtrack.bridge"}),  # other processes: ROS 2 messages, MCAP, lockstep serve
    ("gym", {"seamtrack.gym"}),  # the Gymnasium environment
    ("bench", {"seamtrack.bench"}),
    ("cli", {"seamtrack.cli"}),
    ("package", {"seamtrack"}),  # the lazy public names of `import seamtrack as st`
]


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    found = {_module_name(p): p for p in ROOT.rglob("*.py")}
    cad = ROOT.parent / "cad"  # installed as seamtrack.cad
    found.update({f"seamtrack.cad.{p.stem}": p for p in cad.glob("*.py") if p.stem != "__init__"})
    return found


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(
    name: str, path: Path, modules: dict[str, Path], *, type_only: bool = True
) -> set[str]:
    """The modules ``name`` imports; ``type_only=False`` leaves out the imports under
    ``if TYPE_CHECKING:`` (they never run, but a circle through them is still a circle: the two
    modules cannot be read, typed or moved apart)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    skip: set[int] = set()
    for node in ast.walk(tree):
        if not type_only and isinstance(node, ast.If) and _is_type_checking(node):
            skip.update(id(n) for child in node.body for n in ast.walk(child))
    targets: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            targets.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                targets.add(sub if sub in modules else base)
    return {t for t in targets if t in modules and t != name}


def _stage(module: str) -> int:
    if module == "seamtrack":
        return len(STAGES) - 1
    for rank, (_, prefixes) in enumerate(STAGES[:-1]):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return rank
    raise AssertionError(f"{module} belongs to no stage: add it to STAGES")


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def test_every_import_points_down_the_pipeline(graph: dict[str, set[str]]) -> None:
    upward = [
        f"{a} ({STAGES[_stage(a)][0]}) imports {b} ({STAGES[_stage(b)][0]})"
        for a, targets in graph.items()
        for b in targets
        if _stage(b) > _stage(a)
    ]
    assert upward == []


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components: any component of more than one module is a
    cycle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(cycles)


def stage_edges(graph: dict[str, set[str]]) -> set[tuple[str, str]]:
    """Which stage imports which, as few edges as draw the same order: an edge a -> b is left
    out where a imports another stage c that reaches b (the transitive reduction; the stages'
    imports form no cycle, so it is unique)."""
    names = [name for name, _ in STAGES]
    edges = {
        (names[_stage(a)], names[_stage(b)])
        for a, targets in graph.items()
        for b in targets
        if _stage(a) != _stage(b)
    }
    reach = {name: {b for a, b in edges if a == name} for name in names}
    grown = True
    while grown:
        grown = False
        for name in names:
            more = set().union(reach[name], *(reach[b] for b in reach[name]))
            grown, reach[name] = grown or more != reach[name], more
    return {
        (a, b)
        for a, b in edges
        if not any((a, c) in edges and b in reach[c] for c in names if c not in (a, b))
    }


def test_docs_layout_draws_the_stages_as_they_import(graph: dict[str, set[str]]) -> None:
    """docs/layout.md's drawing (a Mermaid flowchart, ``a --> b``: a imports b) has exactly the
    stages' import edges, reduced (:func:`stage_edges`): it cannot go stale."""
    text = (ROOT.parent / "docs" / "layout.md").read_text()
    block = re.search(r"```mermaid\n(.*?)```", text, flags=re.S)
    assert block, "docs/layout.md lost its ```mermaid drawing of the stages"
    drawn = set(re.findall(r"^\s*(\w+) --> (\w+)\s*$", block.group(1), flags=re.M))
    assert drawn == stage_edges(graph)


def test_no_import_cycle(graph: dict[str, set[str]]) -> None:
    """No cycle among the imports that run (lazy ones included)."""
    modules = _modules()
    running = {
        name: _imports(name, path, modules, type_only=False) for name, path in modules.items()
    }
    assert _cycles(running) == []


#: Circles left through imports for annotations only: none. The last one (the sensor, whose
#: ``scan()``/``render()`` hand it to scan.py and render.py, which named its class) ended when
#: those modules took the sensor's geometry as a protocol
#: (:mod:`seamtrack.sensing.sensor_geometry`). Listed exactly: a new circle fails.
KNOWN_TYPE_ONLY_CIRCLES: list[list[str]] = []


def test_no_circle_even_through_imports_for_annotations(graph: dict[str, set[str]]) -> None:
    """A circle closed by an ``if TYPE_CHECKING:`` import is a circle too: the modules cannot
    be read, typed or moved apart (simulation/scene.py and checks.py/robots.py were one, until
    the scene's types moved to simulation/config.py)."""
    assert _cycles(graph) == KNOWN_TYPE_ONLY_CIRCLES


def test_the_checker_sees_a_lazy_import_cycle(tmp_path: Path) -> None:
    """The checker itself can fail: a lazy import inside a function is an edge."""
    a = tmp_path / "a.py"
    a.write_text("def f():\n    from seamtrack.geometry import frames\n")
    modules = {"seamtrack.sensing.a": a, "seamtrack.geometry.frames": a}
    assert _imports("seamtrack.sensing.a", a, modules) == {"seamtrack.geometry.frames"}


def test_the_checker_sees_an_import_for_annotations_only(tmp_path: Path) -> None:
    """An import under ``if TYPE_CHECKING:`` is an edge too (a type-only circle is a circle)."""
    b = tmp_path / "b.py"
    b.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import seamtrack.x\n")
    modules = {"seamtrack.x": b, "seamtrack.y": b}
    assert _imports("seamtrack.y", b, modules) == {"seamtrack.x"}
    assert _imports("seamtrack.y", b, modules, type_only=False) == set()


def private_imports() -> list[str]:
    """Each ``from x import _name`` across modules: ``_name`` a private name of module ``x``,
    or a private module of package ``x`` imported from outside that package."""
    found = []
    for name, path in _modules().items():
        if ROOT not in path.parents:  # cad/'s scripts are the users' own
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = path.parent
                for _ in range(node.level - 1):
                    base = base.parent
                pkg = base.joinpath(*(node.module or "").split("."))
            elif (node.module or "").startswith("seamtrack.cad"):  # cad/ is seamtrack.cad
                pkg = ROOT.parent.joinpath("cad", *(node.module or "").split(".")[2:])
            elif (node.module or "").startswith("seamtrack"):
                pkg = ROOT.parent.joinpath(*(node.module or "").split("."))
            else:
                continue
            for alias in node.names:
                private = alias.name.startswith("_") and not alias.name.startswith("__")
                module = (pkg / f"{alias.name}.py").exists() or (pkg / alias.name).is_dir()
                if private and (not module or path.parent != pkg):
                    found.append(f"{name}: {alias.name}")
    return found


def test_no_module_imports_another_modules_private_names() -> None:
    """No ``from x import _name`` across modules (a private module of a package, such as
    ``_section_tree.py``, may be imported by name within its package only). The 600-line cap
    that this rule replaced had made 93 of them (issue 40); a name that other modules need is
    public in the module that owns it (cad/'s shared helpers: the package ``cad/kit/``)."""
    assert private_imports() == []


def test_every_subpackage_is_a_stage() -> None:
    stages = {p for _, prefixes in STAGES for p in prefixes}
    subpackages = {
        f"seamtrack.{p.parent.name}"
        for p in ROOT.glob("*/__init__.py")
        if p.parent.name != "scenes"
    }
    assert subpackages <= stages


def test_every_subpackage_is_installed() -> None:
    """pyproject.toml lists every subpackage (an editable install hides a missing one; a wheel
    or a fresh non-editable install would not have it)."""
    import tomllib

    listed = set(
        tomllib.loads((ROOT.parent / "pyproject.toml").read_text())["tool"]["setuptools"][
            "packages"
        ]
    )
    present = {f"seamtrack.{p.parent.name}" for p in ROOT.glob("*/__init__.py")}
    assert present <= listed


def test_every_data_folder_is_declared() -> None:
    """A folder of data files inside the package (the arms' URDFs) is a package of its own in
    pyproject.toml, with its files as package data: setuptools otherwise warns "Package would be
    ignored" on every install, and a wheel might leave the files out."""
    import tomllib

    setuptools = tomllib.loads((ROOT.parent / "pyproject.toml").read_text())["tool"]["setuptools"]
    for folder in ROOT.rglob("*"):
        if not folder.is_dir() or folder.name == "__pycache__":
            continue
        files = [p for p in folder.iterdir() if p.is_file() and p.suffix not in (".py", ".pyc")]
        if files and not (folder / "__init__.py").exists():
            name = ".".join(("seamtrack", *folder.relative_to(ROOT).parts))
            assert name in setuptools["packages"], name
            patterns = setuptools["package-data"][name]
            assert all(any(p.match(g) for g in patterns) for p in files), (name, files)


# ------------------------------------------------------------------ the size of one function

#: The bounds a function must keep (issue 40): McCabe's complexity (ruff's C901) at most 15, the
#: limit NIST SP 500-235 (Watson and McCabe 1996) allows a team with the experience to justify
#: it (10 its default), and at most 60 statements (pylint's PLR0915 is 50; 60 leaves a numba
#: kernel, whose loops are spelt out, room for one more loop). ``pyproject.toml`` holds both.
#: The functions over them today, each to be cut by what its steps mean: a ratchet, the list may
#: only shrink (a function that now keeps the bounds must leave it, and a new one may not join).
OVER_THE_BOUNDS_TODAY: set[str] = set()


def over_the_bounds() -> set[str]:
    """``path::function`` of every function over the complexity or the statement bound, as
    ruff (the project's linter, with the bounds in pyproject.toml) finds them."""
    import json
    import subprocess
    import sys

    ruff = Path(sys.executable).with_name("ruff")
    assert ruff.exists(), "ruff comes with the dev extra: pip install -e .[dev]"
    done = subprocess.run(
        [str(ruff), "check", "--select", "C901,PLR0915", "--output-format", "json",
         "--exit-zero", "--quiet", str(ROOT)],
        capture_output=True, text=True, check=True, cwd=ROOT.parent,
    )  # fmt: skip
    found = set()
    for row in json.loads(done.stdout):
        path = Path(row["filename"])
        line = row["location"]["row"]
        names = [
            node.name
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.lineno == line
        ]
        assert names, row
        found.add(f"{path.relative_to(ROOT.parent).as_posix()}::{names[0]}")
    return found


def test_no_function_over_the_bounds() -> None:
    found = over_the_bounds()
    assert found - OVER_THE_BOUNDS_TODAY == set(), "cut these by what their steps mean"
    assert OVER_THE_BOUNDS_TODAY - found == set(), "these keep the bounds now: strike them"


def test_features_define_each_geometric_type_once() -> None:
    """One line geometry in features/ (issue 40 item 2): a class named ``Line``, ``Point`` or
    ``Corner`` is defined once across the extractors, not once per family."""
    names = ("Line", "Point", "Corner")
    found: dict[str, list[str]] = {n: [] for n in names}
    for path in sorted((ROOT / "features").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and node.name in names:
                found[node.name].append(str(path.relative_to(ROOT)))
    assert {n: len(where) for n, where in found.items() if len(where) > 1} == {}, found
    assert found["Line"] == ["features/line_geometry.py"]
