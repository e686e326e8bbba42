"""The two-plate and generic kernels: their small helpers agree with the numpy calls they
stand in for, and every compiled kernel returns one value or a named tuple (no array of
mixed results read by position)."""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any

import numba
import numpy as np
import pytest
from numba.core import types as nbtypes

from seamtrack.features.extractors import extractor
from seamtrack.features.generic import _slope_turns
from seamtrack.features.plates import _between_plates, _plate_lines, _two_lines, _two_plate_search
from seamtrack.features.plates._plate_lines import _order
from seamtrack.features.plates._two_lines import kept, median
from seamtrack.features.plates.extractor import _pair
from seamtrack.features.refusal import Refusal
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.sensor import preset

#: The compiled modules of the two-plate and generic extractors.
MODULES = (_two_lines, _between_plates, _plate_lines, _two_plate_search, _slope_turns)

#: Kernels that return one array holding one quantity (each element the same kind of
#: thing), not a record of mixed results: what the elements are.
ONE_QUANTITY = {
    "_near": "the points kept, in order",
    "kept": "positions of the True flags",
    "_order": "positions, in order",
    "_along": "coordinates along one line",
    "_pieces_cover": "flags: the points of a hole its pieces cover",
    "_stray": "flags: the points of a hole on a stray line",
    "_loose_cover": "flags: the points of a hole its loose points cover",
}


@pytest.mark.parametrize("n", [1, 2, 3, 8, 9, 101, 400])
def test_median_is_numpys_median(n: int) -> None:
    rng = np.random.default_rng(n)
    for v in (rng.normal(size=n), rng.integers(0, 4, size=n).astype(float)):
        assert median(v) == np.median(v)
    v = rng.normal(size=n)
    v[n // 2] = np.nan
    assert np.isnan(median(v))


def test_order_is_a_stable_argsort() -> None:
    rng = np.random.default_rng(1)
    for n in (0, 1, 5, 64):
        keys = rng.integers(-3, 3, size=n).astype(np.int64)
        assert np.array_equal(_order(keys), np.argsort(keys, kind="stable"))


def test_kept_is_flatnonzero() -> None:
    keep = np.random.default_rng(2).random(50) > 0.5
    assert np.array_equal(kept(keep), np.flatnonzero(keep))


# ------------------------------------------------------------- named results
def _kernels(module: types.ModuleType) -> dict[str, Any]:
    """The module's own numba dispatchers, by name."""
    return {
        name: obj
        for name, obj in vars(module).items()
        if isinstance(obj, numba.core.dispatcher.Dispatcher)
        and obj.py_func.__module__ == module.__name__
    }


def _is_named(cls: Any) -> bool:
    return isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")


def _documented_problem(name: str, kernel: Any) -> str | None:
    """What is wrong with a kernel's documented result type (None: one value, a named tuple
    whose fields are values, arrays or named tuples, or one array of one quantity)."""
    hints = typing.get_type_hints(kernel.py_func)
    result = hints.get("return")
    if result in (float, int, bool):
        return None
    if _is_named(result):
        for field, kind in typing.get_type_hints(result).items():
            if typing.get_origin(kind) is tuple or kind is tuple:
                return f"{name}: field {field} of {result.__name__} is a bare tuple"
        return None
    if typing.get_origin(result) is np.ndarray and name in ONE_QUANTITY:
        return None
    return f"{name} returns {result!r}: neither one value nor a named tuple"


def _compiled_problem(name: str, kernel: Any) -> str | None:
    """The same of each compiled signature's return type (numba's types)."""
    documented = typing.get_type_hints(kernel.py_func).get("return")

    def bad(t: Any, where: str) -> str | None:
        if isinstance(t, (nbtypes.NamedTuple, nbtypes.NamedUniTuple)):
            for field, inner in zip(t.fields, t.types, strict=True):
                wrong = bad(inner, f"{where}.{field}")
                if wrong is not None:
                    return wrong
            return None
        if isinstance(t, nbtypes.BaseTuple):
            return f"{where} is a bare tuple {t}"
        if isinstance(t, nbtypes.Array):
            return None if where != name or name in ONE_QUANTITY else f"{name} returns {t}"
        return None

    for sig in kernel.nopython_signatures:
        t = sig.return_type
        wrong = bad(t, name)
        if wrong is not None:
            return wrong
        if _is_named(documented) and getattr(t, "instance_class", None) is not documented:
            return f"{name} compiles to {t}, not the documented {documented.__name__}"
    return None


def _run_every_extractor() -> None:
    """Compile (or load) the kernels: the two-plate, corner and generic extractors on
    profiles of their joints with reflections and outliers."""
    sensor = preset("paper")
    rng = np.random.default_rng(5)
    level = Imperfections(noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0)
    names = ("square-butt", "lap", "fillet", "outside-corner", "generic")
    for joint in ("square-butt", "lap", "fillet", "outside-corner", "flat"):
        for _ in range(3):
            profile, _ = synthetic_profile(joint, sensor, rng=rng, imperfections=level)
            for name in names:
                extractor(name)(profile)


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__.rsplit(".", 1)[-1])
def test_every_kernel_returns_one_value_or_a_named_tuple(module: types.ModuleType) -> None:
    """Walks the module's dispatchers: each documents (annotates) one value or a named tuple,
    and each signature compiled so far returns what it documents, with no bare tuple or
    mixed array anywhere inside."""
    _run_every_extractor()
    kernels = _kernels(module)
    assert kernels, f"no compiled kernel found in {module.__name__}"
    problems = [
        p
        for name, kernel in kernels.items()
        for p in (_documented_problem(name, kernel), _compiled_problem(name, kernel))
        if p is not None
    ]
    assert not problems, problems


def test_the_extractors_entry_kernels_were_checked_compiled() -> None:
    """The kernels the extractors call from Python have compiled signatures to inspect
    (so the compiled check above is not vacuous for them).

    ``_two_lines.two_lines_share`` is not required here: the corner extractors reach it from
    the compiled ``_corner_search``, and when both load from numba's cache it has no signatures
    of its own (this test failed on every second run of the suite); a fresh checkout compiles
    it, and the check above inspects it then."""
    _run_every_extractor()
    for kernel in (
        _two_plate_search.two_plates,
        _slope_turns.clean_points,
        _slope_turns.window_turns,
        _slope_turns.corner_point,
    ):
        assert kernel.nopython_signatures, kernel.py_func.__name__


def test_the_inspection_fails_on_a_mixed_array() -> None:
    """A kernel returning its results as one array read by position, or as a bare tuple,
    is caught by both checks."""

    @numba.njit
    def mixed(x: float) -> np.ndarray:
        out = np.zeros(3)
        out[0], out[1], out[2] = 1.0, x, 2.0 * x  # found?, y, z
        return out

    @numba.njit
    def bare(x: float) -> tuple[bool, float]:
        return True, x

    for kernel in (mixed, bare):
        kernel(1.0)
        assert _documented_problem(kernel.py_func.__name__, kernel) is not None
        assert _compiled_problem(kernel.py_func.__name__, kernel) is not None


@pytest.mark.parametrize("joint", ["square-butt", "lap"])
def test_pieces_from_lines_read_as_the_table(joint: str) -> None:
    """Segments that kept only ``Line`` objects (no table) give the two-plate search the
    same pieces: the same pairs, lines, ends and holes as the segmentation's table."""
    sensor = preset("paper")
    rng = np.random.default_rng(11)
    level = Imperfections(noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0)
    ex = extractor(joint)
    butt = joint == "square-butt"
    found = 0
    for _ in range(8):
        profile, _ = synthetic_profile(joint, sensor, rng=rng, imperfections=level)
        seg = ex.segments(profile)
        assert not isinstance(seg, Refusal)
        assert seg.table is not None
        from_lines = dataclasses.replace(seg, pieces=list(seg.lines), table=None)
        min_opening = max(ex.min_gap_mm, 3 * seg.tol) if butt else 0.0
        a, b = _pair(seg, ex, butt, min_opening), _pair(from_lines, ex, butt, min_opening)
        assert a == b
        found += a is not None
    assert found >= 6
