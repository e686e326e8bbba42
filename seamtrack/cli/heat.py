"""``seamtrack heat``: the moving arc's temperature (Rosenthal's fields) at given points."""

from __future__ import annotations

import argparse
from typing import Any

from seamtrack.cli.parsing import add_command
from seamtrack.errors import SeamtrackError

HELP = "the temperature of the moving arc at points in its frame (Rosenthal's fields)"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the command on the ``seamtrack`` subparsers."""
    p = add_command(sub, "heat", cmd_heat, HELP, scene=False)
    p.add_argument(
        "--at",
        action="append",
        required=True,
        metavar="X,Y,Z",
        help="a point in the arc's frame, mm: x along the travel, y across, z into the plate "
        "(repeatable; --at=-10,4,1 for a point behind the arc)",
    )
    p.add_argument(
        "--material",
        default="carbon_steel",
        help="carbon_steel (default), stainless_steel or aluminium (docs/heat.md)",
    )
    p.add_argument("--speed-mm-s", type=float, required=True, help="travel speed, mm/s")
    p.add_argument("--power-w", type=float, help="heat into the plate, W (else from U, I, eta)")
    p.add_argument("--voltage-v", type=float, default=28.0, help="arc voltage (default 28)")
    p.add_argument("--current-a", type=float, default=250.0, help="arc current (default 250)")
    p.add_argument(
        "--thermal-efficiency", type=float, default=0.8, help="fraction of U*I into the plate "
        "(default 0.8, MIG/MAG)",
    )  # fmt: skip
    p.add_argument(
        "--thickness-mm",
        type=float,
        help="plate thickness; without it a thick plate (point source)",
    )
    p.add_argument(
        "--model",
        choices=["line", "images"],
        default="line",
        help="with --thickness-mm: line source (thin plate, default) or image sources",
    )
    p.add_argument("--ambient-c", type=float, default=20.0, help="ambient, degC (default 20)")
    return p


def _point(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise SeamtrackError(
            f"{text!r} is not a point", field="--at", fix="give three numbers, e.g. --at 0,5,0"
        )
    return values


#: The library's field names as this command's options.
OPTIONS = {
    "points_mm": "--at",
    "speed_mm_s": "--speed-mm-s",
    "power_w": "--power-w",
    "thickness_mm": "--thickness-mm",
    "ambient_c": "--ambient-c",
    "process.voltage_v": "--voltage-v",
    "process.current_a": "--current-a",
    "process.thermal_efficiency": "--thermal-efficiency",
}


def cmd_heat(args: argparse.Namespace) -> int:
    try:
        return _heat(args)
    except SeamtrackError as exc:
        if exc.field in OPTIONS:
            raise SeamtrackError(exc.message, field=OPTIONS[exc.field], fix=exc.fix) from None
        raise


def _heat(args: argparse.Namespace) -> int:
    from seamtrack.heat.materials import thermal_material
    from seamtrack.heat.rosenthal import (
        arc_power_w,
        image_source_temperature,
        rosenthal_temperature,
    )

    points = [_point(t) for t in args.at]
    m = thermal_material(args.material, field="--material")
    power = args.power_w
    if power is None:
        power = arc_power_w(
            voltage_v=args.voltage_v,
            current_a=args.current_a,
            thermal_efficiency=args.thermal_efficiency,
        )
    kw = dict(
        power_w=power,
        speed_mm_s=args.speed_mm_s,
        conductivity_w_per_mm_k=m.conductivity_w_per_mm_k,
        diffusivity_mm2_per_s=m.diffusivity_mm2_per_s,
        ambient_c=args.ambient_c,
    )
    if args.thickness_mm is not None and args.model == "images":
        temps = image_source_temperature(points, thickness_mm=args.thickness_mm, **kw)
    else:
        temps = rosenthal_temperature(points, thickness_mm=args.thickness_mm, **kw)
    print("x_mm,y_mm,z_mm,temperature_c")
    for p, t in zip(points, temps, strict=True):
        print(f"{p[0]:g},{p[1]:g},{p[2]:g},{t:.3f}")
    return 0
