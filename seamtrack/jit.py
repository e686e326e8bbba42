"""The options every seamtrack numba kernel is compiled with: ``@numba.njit(**KERNEL)``.

- ``cache``: numba's on-disk cache, so only a run after an install or a change of the code
  compiles (``docs/speed.md``, "The first run").
- ``nogil``: the kernels release the GIL (a bridge's or a gym's threads keep running).
- ``no_cfunc_wrapper``: numba builds no C-callable wrapper beside each kernel. That wrapper
  only serves a kernel passed as a first-class function value or called through its address
  from C, which no seamtrack kernel is; building it took about 4 % of a first run's compiling.

numba's type stubs list the documented options only, and a plain ``dict[str, Any]`` would
make every kernel ``Any`` to mypy: :data:`KERNEL` is typed as the options the stubs know
(``Dispatcher[F]`` stays checked) and holds ``no_cfunc_wrapper`` as well.
"""

from __future__ import annotations

from typing import Any, TypedDict, cast


class KernelOptions(TypedDict, total=False):
    """The options of :data:`KERNEL` that numba's stubs type (``no_cfunc_wrapper`` is not)."""

    cache: bool
    nogil: bool


KERNEL = cast(KernelOptions, {"cache": True, "nogil": True, "no_cfunc_wrapper": True})


def compile_for(kernel: Any, *args: Any) -> None:
    """Compile ``kernel`` for the types of ``args`` (or load it from numba's cache), without
    calling it: the types numba's dispatcher gives the same arguments at a call (no literal
    values), so the call later finds this compiled version.

    A first run (an empty cache) uses it to compile the control kernels before its first
    frame, while the warming child compiles the extractor (:mod:`seamtrack.features.warm`):
    else the run would compile them only after waiting for that child."""
    kernel.compile(tuple(kernel.typeof_pyval(a) for a in args))
