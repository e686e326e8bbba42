"""The groove extractor's accuracy table in docs/extractors.md: p95 of the 7 points' errors
per groove, seed and fill state (20 profiles each, tests/test_groove_extractor.py's draw), the
worst pool of 3 consecutive seeds and all seeds pooled (:mod:`seamtrack.bench.groove_fill`).

    python docs/bench/extractors/groove_table.py            # seeds 11-22, about 10 CPU min
    python docs/bench/extractors/groove_table.py --json docs/bench/extractors/groove_fill.json
    python docs/bench/extractors/groove_table.py u 12 1     # one cell

With ``--json`` it writes the measurement docs/figures.py renders the page's table from
(``groove_fill.json``), else it prints the table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from seamtrack.bench.common import machine_info
from seamtrack.bench.groove_fill import LAYERS, errors, groove_fill, groove_fill_table


def main() -> None:
    if len(sys.argv) == 4:
        kind, seed, layers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
        print(f"{np.percentile(errors(kind, seed, layers), 95):.3f}")
        return
    result = {"machine": machine_info(), "grooves": [groove_fill(kind) for kind in LAYERS]}
    if len(sys.argv) == 3 and sys.argv[1] == "--json":
        Path(sys.argv[2]).write_text(json.dumps(result, indent=2) + "\n")
    else:
        print(groove_fill_table(result), end="")


if __name__ == "__main__":
    main()
