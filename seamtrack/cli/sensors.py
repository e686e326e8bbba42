"""``seamtrack sensor``: sensor presets, their data sheets and the geometry solved from them."""

from __future__ import annotations

import json

from seamtrack.cli.tables import print_grid, print_table
from seamtrack.errors import SceneError


def sensor_command(
    name: str, *, list_all: bool = False, as_json: bool = False, overrides: list[str] | None = None
) -> int:
    """``seamtrack sensor``: the presets and their sources, or one preset's geometry and specs
    both ways (Eq. 4-8), with what its data sheet gives and what is assumed."""
    from seamtrack.sensing.sensor import PRESET_SPECS, data_sheet, preset, preset_source
    from seamtrack.simulation.scene import parse_override

    if list_all:
        width = max(len(n) for n in PRESET_SPECS)
        for key in PRESET_SPECS:
            sheet = data_sheet(key)
            label = f"{sheet.make} {sheet.model}" if sheet else preset_source(key)
            print(f"{key:<{width}}  {label}")
            if sheet:
                print(f"{'':<{width}}  source: {sheet.source}")
        return 0
    parsed = dict(parse_override(o) for o in overrides or [])
    changes = {k.removeprefix("sensor."): v for k, v in parsed.items()}
    known = set(PRESET_SPECS[name]) if name in PRESET_SPECS else set()
    for key in changes:
        if key not in known | {"quantize", "focal_length_mm"}:
            raise SceneError(
                f"unknown sensor spec {key!r}",
                field=f"--set {key}",
                fix=f"use one of {', '.join(sorted(known))}",
            )
    sensor = preset(name, **changes)
    specs, geometry = sensor.specs(), sensor.geometry()
    sheet = data_sheet(name)
    if as_json:
        extra = {"source": preset_source(name)}
        if sheet:
            extra["assumed"] = sheet.assumed  # type: ignore[assignment]
        print(json.dumps({"preset": name, "specs": specs, "geometry": geometry, **extra},
                         indent=2))  # fmt: skip
        return 0
    print_table(
        list(geometry.items()),
        f"sensor {name!r}: geometry (b, lambda, theta_s, H, V, N_H, N_V)",
    )
    given = PRESET_SPECS.get(name, {})
    assumed = sheet.assumed if sheet else {}
    print("\nspecs through Eq. 4-8 (and the data sheet they came from; * assumed or derived)")
    print_grid(
        ["spec", "Eq. 4-8", "data sheet"],
        [(k, v, f"{given[k]:g}" + ("*" if k in assumed else "") if k in given else "")
         for k, v in specs.items()],
    )  # fmt: skip
    if sheet:
        facts = [("points_per_profile", sheet.points_per_profile),
                 ("profile_rate_hz", sheet.profile_rate_hz),
                 ("repeatability_z_mm", sheet.repeatability_z_mm),
                 ("resolution_z_mm", sheet.resolution_z_mm),
                 ("wavelength_nm", sheet.wavelength_nm)]  # fmt: skip
        print_table([(k + ("*" if k in assumed else ""), "not given" if v is None else v)
                     for k, v in facts], "\nalso on the sheet")  # fmt: skip
        print_table([(f"{k}*", why) for k, why in assumed.items()], "\nassumed or derived")
    print(f"\nsource: {preset_source(name)}")
    return 0
