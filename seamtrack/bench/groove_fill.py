"""The groove extractor's accuracy on filled grooves, docs/extractors.md's table: the p95 of the
7 points' errors per groove, seed and fill state (20 profiles each, tests/test_groove_extractor.py's
draw), the worst pool of 3 consecutive seeds and all seeds pooled.

``python docs/bench/extractors/groove_table.py --json docs/bench/extractors/groove_fill.json``
measures it (seeds 11-22, about 10 CPU minutes: run it on a quiet machine);
:func:`groove_fill_table` renders the JSON (docs/figures.py, ``groove_fill.json``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

LAYERS = {"v": range(10), "narrow-gap": range(7), "u": range(7)}
SEEDS = {"v": range(11, 14), "narrow-gap": range(11, 23), "u": range(11, 23)}
#: The grooves as the page names them.
NAMES = {
    "v": "V 60 deg, 20 mm, 2 mm gap on a backing",
    "narrow-gap": "narrow gap (4 deg walls, 25 mm deep, 12 mm)",
    "u": "U (10 deg walls, 3 mm root radius, 8 mm)",
}
#: The issue's bound on the p95 (mm): cells over it are bold.
BOUND_MM = 0.2
PROFILES = 20


def errors(kind: str, seed: int, layers: int, n: int = PROFILES) -> np.ndarray:
    """The 7 points' errors (mm) of n profiles (a missed profile: 99 mm each)."""
    from seamtrack.features.extractors import extractor
    from seamtrack.features.synthetic_groove import fill, groove, groove_profile

    g = groove(kind)
    ex = extractor("groove")
    out = []
    for i in range(n):
        rng = np.random.default_rng([layers, i, seed])
        s = fill(g, layers, bead_area_mm2=20.0, rng=rng, jitter_mm=0.5)[0] if layers else None
        profile, truth = groove_profile(
            g,
            s,
            rng=rng,
            roll_deg=rng.uniform(-5, 5),
            pitch_deg=rng.uniform(-5, 5),
            lateral_offset_mm=rng.uniform(-2, 2),
        )
        f = ex(profile)
        out.append(np.hypot(*(f.edges_laser - truth.points_laser).T) if f else np.full(7, 99.0))
    return np.concatenate(out)


def groove_fill(kind: str) -> dict[str, Any]:
    """One groove: p95 per seed and fill state, the worst 3-seed pool and all seeds pooled."""
    layers, seeds = list(LAYERS[kind]), list(SEEDS[kind])
    e = {(s, n): errors(kind, s, n) for s in seeds for n in layers}
    pools = [seeds[i : i + 3] for i in range(len(seeds) - 2)]

    def p95(arrays: list[np.ndarray]) -> float:
        return float(np.percentile(np.concatenate(arrays), 95))

    return {
        "groove": kind,
        "layers": layers,
        "seeds": {str(s): [p95([e[s, n]]) for n in layers] for s in seeds},
        "worst_pool": [max(p95([e[s, n] for s in p]) for p in pools) for n in layers],
        "pooled": [p95([e[s, n] for s in seeds]) for n in layers],
    }


def _cells(values: list[float], width: int) -> list[str]:
    cells = [f"**{v:.2f}**" if v > BOUND_MM else f"{v:.2f}" for v in values]
    return cells + [""] * (width - len(cells))


def groove_fill_table(result: dict[str, Any]) -> str:
    """The page's table from a ``groove_fill.json`` (``{"grooves": [groove_fill(kind), ...]}``)."""
    width = max(len(g["layers"]) for g in result["grooves"])
    lines = [
        "| groove | seeds | " + " | ".join(str(n) for n in range(width)) + " |",
        "|" + "---|" * (width + 2),
    ]
    for g in result["grooves"]:
        rows = [(s, values) for s, values in g["seeds"].items()]
        rows += [("worst 3-seed pool", g["worst_pool"])]
        rows += [(f"all {len(g['seeds'])} pooled", g["pooled"])]
        for i, (label, values) in enumerate(rows):
            name = NAMES.get(g["groove"], g["groove"]) if i == 0 else ""
            lines.append(f"| {name} | {label} | " + " | ".join(_cells(values, width)) + " |")
    return "\n".join(lines) + "\n"
