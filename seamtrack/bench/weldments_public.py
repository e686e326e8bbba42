"""``seamtrack seams`` on STEP files made by other people (part of ``seamtrack bench weldments``):
docs/weldments.md's table of the KittyCAD samples.

What a welder names on each part was decided by hand (``tests/test_weldment_public.py``, which
also checks every found seam against the solids' own faces and bounding boxes): :data:`PUBLIC`
keeps it as the joint type and count expected. The bench reads each file with the command's
defaults and reports the bodies, the seams found (joint type, length, opening or groove angle,
the reachable share; for a closed seam its circle's radius about its centre) and how many of
the expected welds were found, missed and found besides.
"""

from __future__ import annotations

import gzip
import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "tests" / "data" / "step"

#: file -> (its description, the bodies as a welder sees them, the welds a welder names, the
#: joint type and whether the weld is closed, their count).
PUBLIC: dict[str, tuple[str, str, str, str, bool, int]] = {
    "kittycad-exhaust-manifold.step.gz": (
        '"a welded exhaust header" (gunzip first)',
        "4 swept tubes, 1/8 in flange",
        "each tube's fillet all round where it leaves the flange top",
        "fillet",
        True,
        4,
    ),
    "kittycad-shelf-bracket.step": (
        "aluminium shelf bracket",
        "long leg, bend, short leg",
        "2 square butt joints (leg/bend), each from both sides",
        "butt",
        False,
        4,
    ),
}


def _deg(angle_rad: float | None) -> float | None:
    return None if angle_rad is None else math.degrees(angle_rad)


def _circle_radii(points: np.ndarray) -> list[float]:
    """The least and largest distance of a closed seam's points from the centre of the circle
    fitted to them (least squares, in the plane that fits them best)."""
    centred = points - points.mean(axis=0)
    plane = np.linalg.svd(centred, full_matrices=False)[2][:2]
    xy = centred @ plane.T
    a = np.column_stack([2 * xy, np.ones(len(xy))])
    (cx, cy, _), *_ = np.linalg.lstsq(a, (xy**2).sum(axis=1), rcond=None)
    r = np.hypot(xy[:, 0] - cx, xy[:, 1] - cy)
    return [float(r.min()), float(r.max())]


def _seam_row(seam: Any) -> dict[str, Any]:
    points = np.asarray(seam.points, dtype=float)
    closed = bool(np.allclose(points[0], points[-1], atol=1e-6))
    row: dict[str, Any] = {
        "label": seam.label,
        "joint": seam.joint,
        "length_mm": float(seam.length_mm),
        "opening_deg": _deg(seam.opening_rad),
        "groove_angle_deg": _deg(seam.groove_angle_rad),
        "reach_fraction": float(seam.reach_fraction),
        "closed": closed,
    }
    if closed:
        row["radius_mm"] = _circle_radii(points[:-1])
    return row


def public_rows(quick: bool = False) -> list[dict[str, Any]]:
    """One record per file of :data:`PUBLIC` (``quick``: the bracket only, < 1 s)."""
    from seamtrack.workpiece.sources import read_bodies
    from seamtrack.workpiece.weldment import find_seams

    rows = []
    for name, (_, _, _, joint, closed, count) in PUBLIC.items():
        if quick and name.endswith(".gz"):
            continue
        with tempfile.TemporaryDirectory() as folder:
            path = DATA / name
            if name.endswith(".gz"):
                path = Path(folder) / name.removesuffix(".gz")
                path.write_bytes(gzip.decompress((DATA / name).read_bytes()))
            bodies = read_bodies(path)
            seams = [_seam_row(s) for s in find_seams(path)]
        matched = sum(s["joint"] == joint and s["closed"] == closed for s in seams)
        rows.append(
            {
                "file": name,
                "bodies": len(bodies),
                "seams": seams,
                "expected": count,
                "found": min(matched, count),
                "missed": max(count - matched, 0),
                "false": len(seams) - min(matched, count),
            }
        )
    return rows


def _span(values: list[float], spec: str) -> str:
    low, high = format(min(values), spec), format(max(values), spec)
    return low if low == high else f"{low}-{high}"


def _found(row: dict[str, Any]) -> str:
    seams = row["seams"]
    if not seams:
        return "none"
    joints = sorted({s["joint"] for s in seams})
    text = f"{len(seams)} {', '.join(joints)}"
    lengths = [s["length_mm"] for s in seams]
    if any(s["closed"] for s in seams):
        radii = [r for s in seams if s["closed"] for r in s["radius_mm"]]
        text += f", closed, on circles of radius {_span(radii, '.3f')} mm"
    text += f", {_span(lengths, '.1f')} mm long"
    openings = [s["opening_deg"] for s in seams if s["opening_deg"] is not None]
    grooves = [s["groove_angle_deg"] for s in seams if s["groove_angle_deg"] is not None]
    if openings:
        text += f", opening {_span(openings, '.0f')} deg"
    if grooves:
        text += f", groove {_span(grooves, '.0f')} deg"
    reach = [100 * s["reach_fraction"] for s in seams]
    return text + f"; {_span(reach, '.0f')} % of each reachable"


def public_table(result: dict[str, Any]) -> str:
    """docs/weldments.md's table of the public STEP files, from a ``weldments.json``."""
    lines = [
        "| file (KittyCAD KCL sample) | bodies | welds a welder names | found, joint type | "
        "missed | false seams |",
        "|---|---|---|---|---|---|",
    ]
    for row in result.get("public", []):
        about, bodies, welds, _, _, count = PUBLIC[row["file"]]
        lines.append(
            f"| `{row['file']}`, {about} | {bodies} ({row['bodies']} solids) | {count}: {welds} "
            f"| {_found(row)} | {row['missed']} | {row['false']} |"
        )
    return "\n".join(lines) + "\n"
