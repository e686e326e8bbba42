"""Keyword parameters of plugins (trackers, extractors, noise models, CAD scripts), checked
before a run against the signature that takes them.

A parameter's type comes from its annotation, or else from its default value; its range from
``annotated_types`` constraints in the annotation (``Annotated[float, Gt(0)]``, the standard way
pydantic reads, and what the built-in plugins declare). The checks are strict: a number is
never a boolean or a string, a boolean never a number or "yes", and a number is finite unless
its annotation says otherwise. A class that takes ``**kwargs`` accepts any further key
unchecked.

>>> from annotated_types import Gt
>>> from typing import Annotated
>>> def build(width_mm: Annotated[float, Gt(0)] = 10.0, closed: bool = False): ...
>>> check_params(build, {"width_mm": 5}, "workpiece.params")
{'width_mm': 5}
"""

from __future__ import annotations

import inspect
import math
import types
import typing
from collections.abc import Callable
from typing import Annotated, Any

from annotated_types import Ge, Gt, Interval

from seamtrack.errors import SceneError, SeamtrackError

#: Range declarations the built-in plugins use in their signatures.
Positive = Annotated[float, Gt(0)]
NonNegative = Annotated[float, Ge(0)]
Fraction = Annotated[float, Interval(ge=0, le=1)]

_EMPTY = inspect.Parameter.empty


def _strict_scalar(kind: type) -> Any:
    from pydantic import Field

    if kind is float:
        return Annotated[float, Field(strict=True, allow_inf_nan=False)]
    return Annotated[kind, Field(strict=True)]


def _strict(annotation: Any, default: Any) -> Any:
    """The annotation, with its scalars made strict and finite (pydantic metadata added)."""
    if annotation in (_EMPTY, None, Any):
        if isinstance(default, bool):
            return _strict_scalar(bool)
        if isinstance(default, int | float):
            return _strict_scalar(float)
        if isinstance(default, str):
            return _strict_scalar(str)
        return Any
    if annotation in (float, int, bool, str):
        return _strict_scalar(annotation)
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is Annotated:
        base, *meta = args
        if base in (float, int, bool, str):
            return Annotated[(_strict_scalar(base), *meta)]
        return annotation
    if origin in (typing.Union, types.UnionType) and args:
        return typing.Union[tuple(_strict(a, _EMPTY) for a in args)]  # noqa: UP007
    return annotation


def _signature(target: Callable[..., Any]) -> tuple[inspect.Signature, dict[str, Any]]:
    func = target.__init__ if inspect.isclass(target) else target
    signature = inspect.signature(target)
    try:
        hints = typing.get_type_hints(func, include_extras=True)
    except Exception:  # a user's annotations may name anything; fall back to the defaults
        hints = {}
    return signature, hints


def _fix(error: dict[str, Any]) -> str:
    kind = error["type"]
    ctx = error.get("ctx") or {}
    bounds = {
        "greater_than": "> {gt}",
        "greater_than_equal": ">= {ge}",
        "less_than": "< {lt}",
        "less_than_equal": "<= {le}",
    }
    if kind in bounds:
        return "give a number " + bounds[kind].format(**ctx)
    if kind in {"float_type", "int_type", "finite_number", "float_parsing", "int_parsing"}:
        return "give a finite number (not a string, a boolean or a list)"
    if kind in {"bool_type", "bool_parsing"}:
        return "give true or false"
    if kind == "string_type":
        return "give a quoted string"
    if kind in {"tuple_type", "list_type", "too_short", "too_long"}:
        return "give a list of the right length"
    return "see the plugin's docstring for its parameters"


def check_params(
    target: Callable[..., Any],
    params: dict[str, Any],
    field: str,
    error: type[SeamtrackError] = SceneError,
) -> dict[str, Any]:
    """Check ``params`` against the keyword parameters ``target`` (a class or a function)
    takes; return them unchanged, or raise ``error`` naming ``field.KEY``."""
    from pydantic import ConfigDict, ValidationError, create_model

    signature, hints = _signature(target)
    accepts_any = False
    fields: dict[str, Any] = {}
    for name, p in signature.parameters.items():
        if p.kind is p.VAR_KEYWORD:
            accepts_any = True
            continue
        if p.kind is p.VAR_POSITIONAL or name == "self":
            continue
        annotation = _strict(hints.get(name, p.annotation), p.default)
        fields[name] = (annotation, ... if p.default is _EMPTY else p.default)
    unknown = [k for k in params if k not in fields]
    if unknown and not accepts_any:
        allowed = ", ".join(fields) or "none"
        raise error(
            f"takes no parameter {unknown[0]!r}",
            field=f"{field}.{unknown[0]}",
            fix=f"parameters here: {allowed}",
        )
    model = create_model(
        "Params",
        __config__=ConfigDict(extra="allow", arbitrary_types_allowed=True),
        **{k: v for k, v in fields.items() if k in params},
    )
    try:
        model(**params)
    except ValidationError as exc:
        first = exc.errors()[0]
        loc = ".".join(str(x) for x in first["loc"])
        raise error(
            f"{first['msg']} (got {first.get('input')!r})",
            field=f"{field}.{loc}",
            fix=_fix(dict(first)),
        ) from None
    for key in params if accepts_any else ():
        value = params[key]
        if key not in fields and isinstance(value, float) and not math.isfinite(value):
            raise error(
                f"not a finite number (got {value!r})",
                field=f"{field}.{key}",
                fix="give a finite number",
            )
    return params
