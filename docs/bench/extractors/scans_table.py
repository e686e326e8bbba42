"""The extractors on real-scan defects, docs/extractors.md's table (issue 42, item 7): the
v-groove and groove extractors per seeded, labelled variant
(:mod:`seamtrack.bench.extractors_scans`).

    python docs/bench/extractors/scans_table.py            # 100 profiles a cell, about 1.5 min (load 5-8)
    python docs/bench/extractors/scans_table.py --json docs/bench/extractors/extractors_scans.json

With ``--json`` it writes the measurement docs/figures.py renders the page's table from
(``extractors_scans.json``), else it prints the table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from seamtrack.bench.extractors_scans import scans_result, scans_table


def main() -> None:
    result = scans_result()
    if len(sys.argv) == 3 and sys.argv[1] == "--json":
        Path(sys.argv[2]).write_text(json.dumps(result, indent=2) + "\n")
    else:
        print(scans_table(result), end="")


if __name__ == "__main__":
    main()
