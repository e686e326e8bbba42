"""One-off: extractors.json and extractors_real.json from the committed CSV and markdown.

The bench writes its JSON itself since issue 24; these two were made once from its earlier
outputs (the real sets are not shipped, so that bench cannot be re-run here). Run from the
repository's root: ``python docs/bench/extractors/json_from_csv.py``.
"""

import csv
from pathlib import Path

from seamtrack.bench.extractors import write_json

HERE = Path("docs/bench/extractors")
TIMING_HEAD = "| extractor | profiles | median us per profile | p95 us per profile | max us |"


def typed(v: str) -> object:
    for cast in (int, float):
        try:
            return cast(v)
        except ValueError:
            pass
    return v


def rows(name: str) -> list[dict[str, object]]:
    with open(HERE / name) as fh:
        return [{k: typed(v) for k, v in r.items()} for r in csv.DictReader(fh)]


timing = {}
lines = (HERE / "extractors.md").read_text().splitlines()
for line in lines[lines.index(TIMING_HEAD) + 2 :]:
    if not line.startswith("|"):
        break
    name, n, med, p95, mx = [c.strip() for c in line.strip("|").split("|")]
    timing[name] = {"profiles": int(n), "median_us": float(med), "p95_us": float(p95)}
    timing[name]["max_us"] = float(mx)
write_json(HERE / "extractors.json", rows("extractors.csv"), timing)
write_json(HERE / "extractors_real.json", rows("extractors_real.csv"))
