"""What ISO 9692-1 means by every groove parameter, checked before weldx draws a groove.

One table (:data:`KINDS`) gives each parameter's kind by its weldx name, and each kind its
range; one table (:data:`RELATIONS`) gives, per groove type, the relations between its
parameters that keep the drawn groove inside the plate:

- ``t`` plate thickness: 0 < t <= :data:`T_MAX_MM`.
- ``alpha``, ``alpha_1``, ``alpha_2`` groove angles (both walls of a V together): 0 < alpha <=
  :data:`ALPHA_MAX_DEG`; ``beta``, ``beta_1``, ``beta_2`` bevel angles (one wall, from the
  plate's normal): 0 < beta <= :data:`BETA_MAX_DEG`. ISO 9692-1 grooves open 40 to 60 deg with
  bevels of 8 to 60 deg; flatter walls make plates many times wider than they are thick.
- ``b`` root gap: 0 <= b <= t. ``c`` root face: 0 <= c < t. ``h``, ``h1``, ``h2`` depths (of a V
  or a U part of the groove, from its face): 0 <= h < t. ``R``, ``R2`` root radii: 0 < R < t.
- Relations: a V groove's root face below t; a U groove's root face and radius together below t
  (the arc ends inside the plate); a UV groove's U meets its V (R >= h tan(alpha / 2)) and ends
  below the top; a VV groove's upper bevel starts above its root face (c < h, h + c < t); a
  double groove's depths and root face sum to at most t (h1 + h2 + c <= t; weldx fills a missing
  depth with the other, or both with (t - c) / 2), and a double U's radii fit their depths.

Every value must be a finite number (not a boolean). Errors name ``workpiece.groove.<key>``
(keys carry the unit: ``alpha_deg``, ``c_mm``) and the fix.
"""

from __future__ import annotations

import math
from typing import Any

from seamtrack.errors import WorkpieceError

FIELD = "workpiece.groove"
#: The thickest plate a groove is built for (mm).
T_MAX_MM = 500.0
#: Largest groove angle (both walls of a V together) (deg).
ALPHA_MAX_DEG = 160.0
#: Largest bevel angle (one wall) (deg).
BETA_MAX_DEG = 80.0
#: The widest plate a groove part is built with (mm).
PLATE_WIDTH_MAX_MM = 1000.0
#: Sums within this of their bound are at the bound (mm).
EPS_MM = 1e-9

#: weldx name -> kind; a kind's range: (low, low inclusive, high, high inclusive, unit, meaning).
KINDS = {
    "t": "thickness",
    "alpha": "groove angle",
    "alpha_1": "groove angle",
    "alpha_2": "groove angle",
    "beta": "bevel angle",
    "beta_1": "bevel angle",
    "beta_2": "bevel angle",
    "b": "root gap",
    "c": "root face",
    "h": "depth",
    "h1": "depth",
    "h2": "depth",
    "R": "root radius",
    "R2": "root radius",
}


def _range(kind: str, t: float) -> tuple[float, bool, float, bool]:
    """(low, low allowed, high, high allowed) of a kind, for a plate of thickness t."""
    return {
        "thickness": (0.0, False, T_MAX_MM, True),
        "groove angle": (0.0, False, ALPHA_MAX_DEG, True),
        "bevel angle": (0.0, False, BETA_MAX_DEG, True),
        "root gap": (0.0, True, t, True),
        "root face": (0.0, True, t, False),
        "depth": (0.0, True, t, False),
        "root radius": (0.0, False, t, False),
    }[kind]


def _key(name: str) -> str:
    return f"{name}_{'deg' if name.startswith(('alpha', 'beta')) else 'mm'}"


def _error(kind: str, name: str, what: str, fix: str) -> WorkpieceError:
    return WorkpieceError(f"{kind}: {_key(name)} {what}", field=f"{FIELD}.{_key(name)}", fix=fix)


def check_number(value: Any, field: str) -> float:
    """A finite number (not a boolean, not a string) as a float, else the error for ``field``."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise WorkpieceError(
            f"{field.rsplit('.', 1)[-1]} must be a finite number, got {value!r}",
            field=field,
            fix="give a number in the unit of the key's suffix",
        )
    return float(value)


def check_groove(kind: str, values: dict[str, float], given: set[str] | None = None) -> None:
    """Check a groove's parameters (weldx names, mm and deg) against ISO 9692-1's meaning;
    those not in ``given`` are weldx's defaults (and said to be).

    Raises
    ------
    WorkpieceError
        The first parameter out of its range, or of a relation, naming its key and the fix.
    """
    t = values["t"]
    for name in ["t", *sorted(n for n in values if n != "t")]:
        value, meaning = values[name], KINDS[name]
        lo, lo_ok, hi, hi_ok = _range(meaning, t)
        below = value < lo or (value == lo and not lo_ok)
        above = value > hi or (value == hi and not hi_ok)
        if below or above:
            key = _key(name)
            bound = f"{lo:g} {'<=' if lo_ok else '<'} {key} {'<=' if hi_ok else '<'} {hi:g}"
            if key.endswith("mm") and name != "t":
                bound += " (t_mm)"
            default = "" if given is None or name in given else " (weldx's default)"
            raise _error(
                kind,
                name,
                f"= {value:g}{default} is no {meaning} (ISO 9692-1): it needs {bound}",
                f"give {key} in that range",
            )
    for rule in RELATIONS.get(kind, ()):
        rule(kind, values)


# ----------------------------------------------------------------------------- relations
def _u_radius(kind: str, v: dict[str, float]) -> None:
    c = v.get("c", 0.0)
    if c + v["R"] >= v["t"] - EPS_MM:
        raise _error(
            kind,
            "R",
            f"= {v['R']:g} with c_mm = {c:g} reaches the top of the {v['t']:g} mm plate: the "
            "U's arc must end inside it (c_mm + R_mm < t_mm)",
            f"give R_mm below {v['t'] - c:g}, or a thicker plate",
        )


def _uv(kind: str, v: dict[str, float]) -> None:
    h, t, r = v.get("h", 0.0), v["t"], v["R"]
    reach = h * math.tan(math.radians(v["alpha"]) / 2)
    if r < reach:
        raise _error(
            kind,
            "R",
            f"= {r:g} cannot meet the V below it ({h:g} mm deep at alpha {v['alpha']:g} deg: "
            f"{reach:.3g} mm wide)",
            f"give R_mm of at least {reach:.3g}, or a shallower h_mm",
        )
    top = h + math.sqrt(r * r - reach * reach) - r * math.sin(math.radians(v["beta"]))
    if top >= t - EPS_MM:
        raise _error(
            kind,
            "R",
            f"= {r:g} ends the U's arc {top:.3g} mm up, above the {t:g} mm plate",
            "give a smaller R_mm or h_mm, or a thicker plate",
        )


def _vv(kind: str, v: dict[str, float]) -> None:
    c, h, t = v.get("c", 0.0), v["h"], v["t"]
    if h <= c:
        raise _error(
            kind,
            "h",
            f"= {h:g} does not rise above the root face c_mm = {c:g} (weldx draws the lower "
            "V over h_mm - c_mm)",
            f"give h_mm above {c:g}",
        )
    if h + c >= t - EPS_MM:
        raise _error(
            kind,
            "h",
            f"= {h:g} with c_mm = {c:g} leaves no upper bevel in the {t:g} mm plate "
            "(h_mm + c_mm < t_mm)",
            f"give h_mm below {t - c:g}",
        )


def _double(kind: str, v: dict[str, float]) -> None:
    """h1 + h2 + c <= t, with weldx's defaults for missing depths."""
    t, c = v["t"], v.get("c", 0.0)
    h1, h2 = v.get("h1"), v.get("h2")
    if h1 is None and h2 is None:
        h1 = h2 = (t - c) / 2
    h1 = h2 if h1 is None else h1
    h2 = h1 if h2 is None else h2
    assert h1 is not None and h2 is not None
    if h1 + h2 + c > t + EPS_MM:
        name = "h1" if "h1" in v else "h2" if "h2" in v else "c"
        raise _error(
            kind,
            name,
            f"makes the depths and the root face sum to {h1 + h2 + c:g} mm (h1 {h1:g} + h2 "
            f"{h2:g} + c {c:g}), more than the {t:g} mm plate",
            "give h1_mm + h2_mm + c_mm <= t_mm (a missing depth is the other one)",
        )
    if "R" in v:
        for radius, depth, name in ((v["R"], h1, "R"), (v["R2"], h2, "R2")):
            if radius > depth + EPS_MM:
                raise _error(
                    kind,
                    name,
                    f"= {radius:g} is deeper than its U ({depth:g} mm)",
                    f"give {_key(name)} of at most {depth:g}",
                )


#: Relations between a groove type's parameters (beyond each one's own range).
RELATIONS: dict[str, tuple[Any, ...]] = {
    "IGroove": (),
    "VGroove": (),  # c < t: the root face's own range
    "HVGroove": (),
    "UGroove": (_u_radius,),
    "HUGroove": (_u_radius,),
    "UVGroove": (_uv,),
    "VVGroove": (_vv,),
    "DVGroove": (_double,),
    "DHVGroove": (_double,),
    "DUGroove": (_double,),
    "DHUGroove": (_double,),
}


def check_plate_width(value: Any) -> float:
    """A groove part's ``plate_width_mm``: a number in (0, :data:`PLATE_WIDTH_MAX_MM`]."""
    field = "workpiece.params.plate_width_mm"
    width = check_number(value, field)
    if not 0.0 < width <= PLATE_WIDTH_MAX_MM:
        raise WorkpieceError(
            f"plate_width_mm must lie in (0, {PLATE_WIDTH_MAX_MM:g}] mm, got {width:g}",
            field=field,
            fix="give e.g. 50",
        )
    return width


#: A groove part's path parameters that are numbers, with their largest value.
PATH_NUMBERS = {"seam_length_mm": 10_000.0, "arc_radius_mm": 100_000.0, "corner_angle_deg": 180.0}


def check_path_params(params: dict[str, Any]) -> None:
    """A groove part's path parameters: ``path`` a name, the others finite numbers in range
    (the path itself checks what depends on the path)."""
    if "path" in params and not isinstance(params["path"], str):
        raise WorkpieceError(
            f"path must be a name, got {params['path']!r}",
            field="workpiece.params.path",
            fix='give e.g. "straight", "arc" or "paper"',
        )
    for name, high in PATH_NUMBERS.items():
        if params.get(name) is None:
            continue
        field = f"workpiece.params.{name}"
        value = check_number(params[name], field)
        if not 0.0 < value <= high:
            raise WorkpieceError(
                f"{name} must lie in (0, {high:g}], got {value:g}",
                field=field,
                fix=f"give {name} in that range",
            )
