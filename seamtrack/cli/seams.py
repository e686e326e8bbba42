"""``seamtrack seams PART``: the seams of a weldment, as a table, JSON, or a picture."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from seamtrack.errors import SeamtrackError

HELP = "find every weld of a weldment (a STEP file of several bodies, or a weldment script)"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the command on the ``seamtrack`` subparsers."""
    p = sub.add_parser("seams", help=HELP, description=HELP)
    p.set_defaults(fn=cmd_seams)
    p.add_argument("part", metavar="PART", help="a .step/.stp file, or a cad/weldment_*.py script")
    p.add_argument("--json", action="store_true", help="print the seams as a JSON list")
    p.add_argument("--view", metavar="PNG", help="draw the part with its numbered seams")
    p.add_argument(
        "--max-gap-mm",
        type=float,
        default=1.0,
        help="bodies and faces farther apart are not joined (default 1)",
    )
    p.add_argument(
        "--torch-length-mm",
        type=float,
        default=100.0,
        help="free length the torch direction needs to count as reachable (default 100)",
    )
    p.add_argument(
        "--min-length-mm",
        type=float,
        default=1.0,
        help="shorter seams are dropped (default 1)",
    )
    p.add_argument(
        "--param",
        action="append",
        metavar="KEY=VALUE",
        help="a parameter of a weldment script's build(), e.g. --param length_mm=60",
    )
    return p


def _params(items: list[str] | None) -> dict[str, Any]:
    from seamtrack.simulation.scene import parse_override

    out = {}
    for item in items or []:
        key, value = parse_override(item)
        out[key] = value
    return out


def table(seams: list[Any]) -> str:
    """The seams as aligned text columns."""
    header = ["id", "name", "joint", "length_mm", "opening_deg", "gap_mm", "reach", "start_mm",
              "end_mm"]  # fmt: skip
    rows = [
        [
            s.id,
            s.name,
            s.joint,
            f"{s.length_mm:.2f}",
            f"{math.degrees(s.opening_rad):.1f}",
            f"{s.gap_mm:.2f}",
            "yes" if s.reachable else f"no ({s.reach_fraction:.0%})",
            _point(s.points[0]),
            _point(s.points[-1]),
        ]
        for s in seams
    ]
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(line.rstrip() for line in lines)


def _point(p: Any) -> str:
    return "(" + ", ".join(f"{v:.2f}" for v in p) + ")"


def cmd_seams(args: argparse.Namespace) -> int:
    from seamtrack.io.output import check_writable, new_dir
    from seamtrack.workpiece.weldment import find_seams

    params = _params(args.param)
    for name in ("max_gap_mm", "torch_length_mm", "min_length_mm"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            raise SeamtrackError(
                f"{value} is not a length", field="--" + name.replace("_", "-"), fix="give mm > 0"
            )
    view = Path(args.view) if args.view else None
    if view is not None:
        if view.suffix.lower() != ".png":
            raise SeamtrackError(f"{view} is no .png", field="--view", fix="give a .png path")
        check_writable(view.parent if str(view.parent) else Path("."))
    seams = find_seams(
        args.part,
        max_gap_mm=args.max_gap_mm,
        torch_length_mm=args.torch_length_mm,
        min_length_mm=args.min_length_mm,
        field="PART",
        **params,
    )
    if args.json:
        print(json.dumps([s.record() for s in seams], indent=1))
    else:
        joints = {
            j: sum(s.joint == j for s in seams) for j in dict.fromkeys(s.joint for s in seams)
        }
        summary = ", ".join(f"{n} {j}" for j, n in joints.items())
        print(f"{args.part}: {len(seams)} seams ({summary})")
        print(table(seams))
    if view is not None:
        from seamtrack.viz.seams import draw_seams
        from seamtrack.workpiece.weldment import load_bodies

        bodies = load_bodies(args.part, "PART", params)
        with new_dir(view.parent if str(view.parent) else Path(".")):
            draw_seams(bodies, seams, view, title=Path(args.part).name)
        if not args.json:
            print(f"wrote {view}")
    return 0
