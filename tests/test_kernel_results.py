"""The compiled kernels of the segmentation and the V-groove side of seamtrack.features return
named results and are read by name (issue 24): a kernel that returns several values returns a
numba named tuple, never a bare tuple or an array of mixed results (``out[12]``); no caller
reads a kernel's result by position or compares a code with a bare number.

Two independent checks: the kernels' source (every return of every ``numba.njit`` function,
and every read of a kernel's result in these modules), and the compiled dispatchers' return
types once the extractors have run.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import math
from pathlib import Path

import numba
import numpy as np
import pytest
from numba.core import types

from seamtrack.features.extractors import BUILTIN, extractor
from seamtrack.features.lines import segment_profile
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.profiles import Profile
from seamtrack.sensing.sensor import preset

#: The modules whose kernels this file holds to the rule (the two-plate side's are held to
#: it by tests/test_plate_kernels.py as well).
MODULES = (
    "seamtrack.features.select",
    "seamtrack.features.counts",
    "seamtrack.features.robust",
    "seamtrack.features._segmentation",
    "seamtrack.features.lines",
    "seamtrack.features.vgroove._v_search",
    "seamtrack.features.vgroove._v_root",
    "seamtrack.features.vgroove._v_groove_model",
    "seamtrack.features.vgroove.extractor",
    "seamtrack.features.base",
    "seamtrack.features.extractors",
    "seamtrack.features.classify",
    "seamtrack.features.plates._two_lines",
    "seamtrack.features.plates._between_plates",
    "seamtrack.features.plates._plate_lines",
    "seamtrack.features.plates._two_plate_search",
    "seamtrack.features.generic._slope_turns",
    "seamtrack.features.plates.extractor",
    "seamtrack.features.generic.extractor",
)


def _tree(name: str) -> ast.Module:
    module = importlib.import_module(name)
    return ast.parse(Path(inspect.getfile(module)).read_text())


def _is_njit(fn: ast.FunctionDef) -> bool:
    return any("njit" in ast.unparse(d) for d in fn.decorator_list)


def _kernels(tree: ast.Module) -> list[ast.FunctionDef]:
    return [n for n in tree.body if isinstance(n, ast.FunctionDef) and _is_njit(n)]


def _bare(value: ast.expr | None) -> bool:
    """A bare tuple display, in either branch of a conditional expression."""
    if isinstance(value, ast.Tuple):
        return True
    if isinstance(value, ast.IfExp):
        return _bare(value.body) or _bare(value.orelse)
    return False


def _mixed_arrays(fn: ast.FunctionDef) -> set[str]:
    """Names written at two or more distinct constant positions (``out[0] = ...``,
    ``out[12] = ...``): an array of mixed results."""
    writes: dict[str, set[object]] = {}
    for node in ast.walk(fn):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            for t in node.targets:
                targets += t.elts if isinstance(t, ast.Tuple) else [t]
        for t in targets:
            if (
                isinstance(t, ast.Subscript)
                and isinstance(t.value, ast.Name)
                and isinstance(t.slice, ast.Constant)
                and isinstance(t.slice.value, int)
            ):
                writes.setdefault(t.value.id, set()).add(t.slice.value)
    return {k for k, v in writes.items() if len(v) >= 2}


@pytest.mark.parametrize("name", MODULES)
def test_kernels_return_named_results(name: str) -> None:
    """No compiled kernel returns a bare tuple or an array written at fixed positions."""
    bad = []
    for fn in _kernels(_tree(name)):
        mixed = _mixed_arrays(fn)
        for node in ast.walk(fn):
            if isinstance(node, ast.Return):
                if _bare(node.value):
                    bad.append(f"{fn.name}: returns a bare tuple at line {node.lineno}")
                if isinstance(node.value, ast.Name) and node.value.id in mixed:
                    bad.append(f"{fn.name}: returns the mixed array {node.value.id!r}")
    assert not bad, "\n".join(bad)


#: Kernels whose result is one quantity, an array of like values (indices of the kept
#: points, an order, positions along a line): indexing it by position is reading that array,
#: not a slot of a mixed result.
ONE_QUANTITY = {"kept", "_order", "_along"}


def _kernel_names(name: str) -> set[str]:
    """The names under which module ``name`` holds compiled kernels of several results."""
    module = importlib.import_module(name)
    return {
        attr
        for attr, value in vars(module).items()
        if isinstance(value, numba.core.registry.CPUDispatcher) and attr not in ONE_QUANTITY
    }


def _fixed(index: ast.expr) -> bool:
    """A position fixed in the source: a number, or a slice between numbers."""
    if isinstance(index, ast.Constant):
        return isinstance(index.value, int)
    if isinstance(index, ast.Slice):
        return any(isinstance(b, ast.Constant) for b in (index.lower, index.upper))
    return False


@pytest.mark.parametrize("name", MODULES)
def test_kernel_results_are_read_by_name(name: str) -> None:
    """A kernel's result is never indexed by a number (``out[12]``, ``out[1:3]``), and no
    code is compared with a bare number (``code == 4``): named fields and constants."""
    kernels = _kernel_names(name)
    bad = []
    for fn in ast.walk(_tree(name)):
        if not isinstance(fn, ast.FunctionDef):
            continue
        results = set()  # names bound to a kernel's whole result
        for node in ast.walk(fn):
            if (
                isinstance(node, ast.Assign)
                and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name)
                and isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name)
                and node.value.func.id in kernels
            ):
                results.add(node.targets[0].id)
        for node in ast.walk(fn):
            if isinstance(node, ast.Subscript) and _fixed(node.slice):
                direct = isinstance(node.value, ast.Call) and (
                    isinstance(node.value.func, ast.Name) and node.value.func.id in kernels
                )
                named = isinstance(node.value, ast.Name) and node.value.id in results
                if direct or named:
                    bad.append(f"{fn.name}: {ast.unparse(node)} (line {node.lineno})")
            if isinstance(node, ast.Compare):
                left = ast.unparse(node.left)
                numbers = [
                    c
                    for c in node.comparators
                    if isinstance(c, ast.Constant) and type(c.value) is int and c.value != 0
                ]
                if left.split(".")[-1] == "code" and numbers:
                    bad.append(f"{fn.name}: {ast.unparse(node)} (line {node.lineno})")
    assert not bad, "\n".join(bad)


def test_the_check_catches_a_mixed_array() -> None:
    """The source check flags what it is meant to flag."""
    src = """
@numba.njit
def k(x):
    out = np.empty(3)
    out[0], out[2] = 1, x
    return out

@numba.njit
def t(x):
    return (x, 1) if x else (0, 0)
"""
    fns = _kernels(ast.parse(src))
    assert _mixed_arrays(fns[0]) == {"out"}
    assert _bare(next(n for n in ast.walk(fns[1]) if isinstance(n, ast.Return)).value)
    assert _fixed(ast.parse("out[12]").body[0].value.slice)  # type: ignore[attr-defined]
    assert _fixed(ast.parse("out[1:3]").body[0].value.slice)  # type: ignore[attr-defined]
    assert not _fixed(ast.parse("out[k]").body[0].value.slice)  # type: ignore[attr-defined]


def test_compiled_kernels_return_named_tuples() -> None:
    """After every built-in extractor has run, every compiled overload of these modules'
    kernels returns a scalar, a homogeneous array or a named tuple: no anonymous tuple."""
    rng = np.random.default_rng(3)
    for joint in ("v-groove", "fillet", "outside-corner", "flat"):
        profile, _ = synthetic_profile(
            joint, preset("paper"), rng=rng, imperfections=Imperfections(noise_mm=0.05)
        )
        for name in BUILTIN:
            extractor(name)(profile)
    seen = set()
    bad = []
    for name in MODULES:
        module = importlib.import_module(name)
        for attr, value in vars(module).items():
            if not isinstance(value, numba.core.registry.CPUDispatcher):
                continue
            if value.__module__ != name:
                continue  # imported from another module: checked there
            for sig in value.nopython_signatures:
                seen.add(f"{name.rsplit('.', 1)[1]}.{attr}")
                ret = sig.return_type
                if isinstance(ret, types.BaseTuple) and not isinstance(ret, types.BaseNamedTuple):
                    bad.append(f"{name}.{attr} -> {ret}")
    # the extractors' entry kernels ran (the kernels they call run inside them, compiled: one
    # loaded with its callers from numba's cache, as _v_search.search is inside v_groove on a
    # second run, has no signatures of its own; a fresh clone compiles and checks it)
    assert {"_segmentation.segment", "_v_groove_model.v_groove"} <= seen
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    ("wall_deg", "depth_mm", "root_y_mm"), [(60.0, 5.0, 0.0), (45.0, 3.0, 1.3), (70.0, 8.0, -2.1)]
)
def test_the_kernels_results_are_the_analytic_groove(wall_deg, depth_mm, root_y_mm) -> None:
    """What the named results hold, not only their form: on a V drawn analytically (plates at
    range 100 mm, walls ``wall_deg`` from them, 3 um seeded noise), the compiled segmentation
    gives the four straight pieces at the drawn angles, each on its drawn line, and the
    compiled V-groove model gives the root and the top corners where the geometry puts them."""
    slope = math.tan(math.radians(wall_deg))
    half = depth_mm / slope  # the walls' half-width at the plates
    y = np.linspace(-15.0, 15.0, 1501) + root_y_mm
    z = 100.0 + np.clip(depth_mm - np.abs(y - root_y_mm) * slope, 0.0, None)
    noise = np.random.default_rng(4).normal(0.0, 0.003, y.size)
    profile = Profile(np.column_stack([y, z + noise]))
    segments = segment_profile(profile)
    assert not isinstance(segments, str)
    lines = sorted(segments.lines, key=lambda line: line.centroid[0])
    angles = [math.degrees(math.atan2(ln.direction[1], ln.direction[0])) for ln in lines]
    np.testing.assert_allclose(angles, [0.0, wall_deg, -wall_deg, 0.0], atol=0.05)
    for line, (y0, z0, a) in zip(
        lines,
        [(root_y_mm - half, 100.0, 0.0), (root_y_mm, 100.0 + depth_mm, wall_deg),
         (root_y_mm, 100.0 + depth_mm, -wall_deg), (root_y_mm + half, 100.0, 0.0)],
        strict=True,
    ):  # fmt: skip
        normal = np.array([-math.sin(math.radians(a)), math.cos(math.radians(a))])
        assert abs((line.centroid - (y0, z0)) @ normal) < 0.002  # on the drawn line
    feature = extractor("v-groove")(profile)
    assert feature and feature.joint == "v-groove"
    np.testing.assert_allclose(feature.point_laser, [root_y_mm, 100.0 + depth_mm], atol=0.01)
    np.testing.assert_allclose(
        feature.edges_laser, [[root_y_mm - half, 100.0], [root_y_mm + half, 100.0]], atol=0.02
    )
