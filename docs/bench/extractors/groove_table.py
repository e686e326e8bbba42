"""The groove extractor's accuracy table in docs/extractors.md: p95 of the 7 points' errors
per groove, seed and fill state (20 profiles each, tests/test_groove_extractor.py's draw), the
worst pool of 3 consecutive seeds and all seeds pooled.

    python docs/bench/extractors/groove_table.py            # seeds 11-22, about 10 CPU min
    python docs/bench/extractors/groove_table.py u 12 1     # one cell
"""

from __future__ import annotations

import sys

import numpy as np

from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic_groove import fill, groove, groove_profile

LAYERS = {"v": range(10), "narrow-gap": range(7), "u": range(7)}
SEEDS = {"v": range(11, 14), "narrow-gap": range(11, 23), "u": range(11, 23)}


def errors(kind: str, seed: int, layers: int, n: int = 20) -> np.ndarray:
    """The 7 points' errors (mm) of n profiles (a missed profile: 99 mm each)."""
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


def main() -> None:
    if len(sys.argv) == 4:
        kind, seed, layers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
        print(f"{np.percentile(errors(kind, seed, layers), 95):.3f}")
        return
    for kind, layers in LAYERS.items():
        e = {(s, n): errors(kind, s, n) for s in SEEDS[kind] for n in layers}
        for s in SEEDS[kind]:
            row = " | ".join(f"{np.percentile(e[s, n], 95):.2f}" for n in layers)
            print(f"| {kind} | {s} | {row} |")
        seeds = list(SEEDS[kind])
        pools = [seeds[i : i + 3] for i in range(len(seeds) - 2)]
        worst = [max(np.percentile(np.concatenate([e[s, n] for s in p]), 95) for p in pools)
                 for n in layers]  # fmt: skip
        pooled = [np.percentile(np.concatenate([e[s, n] for s in seeds]), 95) for n in layers]
        print(f"| {kind} | worst 3-seed pool | " + " | ".join(f"{x:.2f}" for x in worst) + " |")
        print(f"| {kind} | all pooled | " + " | ".join(f"{x:.2f}" for x in pooled) + " |")


if __name__ == "__main__":
    main()
