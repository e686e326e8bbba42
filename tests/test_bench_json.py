"""Every bench writes a JSON beside its tables (docs/figures.py renders the documentation's
figures from them): the extractor benches' JSON holds the same rows as their CSV, NaN as null."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

from seamtrack.bench import extractors as bench


def _row(extractor: str, p95: float) -> dict[str, object]:
    return {
        "extractor": extractor,
        "joint": "v-groove",
        "level": "clean",
        "n": 3,
        "detection_rate": 1.0 if math.isfinite(p95) else 0.0,
        "wrong_rate": 0.0,
        "median_error_mm": p95 / 2,
        "p95_error_mm": p95,
        "flat_false_rate": 0.0,
        "us_per_profile": 80.0,
        "median_us": 79.0,
        "p95_us": 90.0,
    }


def test_the_extractor_bench_writes_its_rows_as_json(tmp_path: Path) -> None:
    rows = [_row("v-groove", 0.01), _row("generic", math.nan)]
    pooled = {"v-groove": [70_000, 80_000, 90_000], "generic": [100_000]}
    bench._write(tmp_path, rows, pooled)
    data = json.loads((tmp_path / "extractors.json").read_text())
    with open(tmp_path / "extractors.csv") as fh:
        from_csv = list(csv.DictReader(fh))
    assert [r["extractor"] for r in data["rows"]] == [r["extractor"] for r in from_csv]
    assert data["rows"][0]["p95_error_mm"] == float(from_csv[0]["p95_error_mm"]) == 0.01
    assert data["rows"][1]["p95_error_mm"] is None and from_csv[1]["p95_error_mm"] == "nan"
    assert data["timing"]["v-groove"] == {
        "profiles": 3,
        "median_us": 80.0,
        "p95_us": 89.0,  # numpy's linear interpolation between 80 and 90 us
        "max_us": 90.0,
    }
    assert {"cpu", "cores", "python"} <= set(data["machine"])


def test_the_committed_extractor_json_matches_the_committed_csv() -> None:
    """The JSON made once from the committed CSV (docs/bench/extractors/json_from_csv.py), or
    written by a later run beside it: the same rows either way."""
    folder = Path(__file__).resolve().parents[1] / "docs" / "bench" / "extractors"
    for name in ("extractors", "extractors_real"):
        rows = json.loads((folder / f"{name}.json").read_text())["rows"]
        with open(folder / f"{name}.csv") as fh:
            from_csv = list(csv.DictReader(fh))
        assert len(rows) == len(from_csv)
        for r, c in zip(rows, from_csv, strict=True):
            for key, text in c.items():
                value = r[key]
                if value is None:
                    assert text == "nan"
                elif isinstance(value, (int, float)):
                    assert math.isclose(value, float(text), rel_tol=1e-12)
                else:
                    assert value == text
