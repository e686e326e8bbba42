"""Stage the Keyence root-pass scans (github.com/blackhorsewu/roboweld, history; no licence
stated: the data stay outside this repository) into the layout ``seamtrack extractors bench
--real DIR`` reads (docs/extractors.md, "Real data").

    python docs/bench/extractors/stage_keyence.py ROBOWELD_GIT_DIR OUT_DIR

``ROBOWELD_GIT_DIR``: a clone (or bare mirror) of the repository; the 8 profiles
``profile_0..7.csv`` of commit 2351038 (``J, Z, ...``: column index and world height Z in m,
an LJ-V7200 over a 90 deg V-groove with a root pass) are read with ``git show``. Each moves
into the laser frame as ``stage_real.py`` moves the Keyence sets: y = 0.1 mm x J - 36 mm
(pitch assumed 0.1 mm, centred), z = 200 mm - Z (the reference distance). The label is the
intersection of the two bevel lines, each a total-least-squares line through the profile's
points between 20 % and 50 % of the groove's depth below the plates on its side of the
deepest point (the plates: the median height of the outer 10 % of the points), as
``stage_real.py``'s labels were (bevel lines on the bevels' upper parts).
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

COMMIT = "2351038"
SHIFT = (-36.0, 200.0)


def _tls(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c = p.mean(axis=0)
    _, _, vt = np.linalg.svd(p - c)
    return c, vt[0]


def bevel_label(y: np.ndarray, z: np.ndarray) -> tuple[float, float]:
    ok = np.isfinite(z)
    y, z = y[ok], z[ok]
    n = len(z)
    plate = float(np.median(np.r_[z[: n // 10], z[-(n // 10) :]]))
    deep = int(np.argmax(z))
    depth = float(z[deep]) - plate
    lines = []
    for side in (slice(0, deep), slice(deep, n)):
        ys, zs = y[side], z[side]
        sel = (zs - plate >= 0.2 * depth) & (zs - plate <= 0.5 * depth)
        lines.append(_tls(np.column_stack([ys[sel], zs[sel]])))
    (c1, d1), (c2, d2) = lines
    t = np.linalg.solve(np.column_stack([d1, -d2]), c2 - c1)
    x = c1 + t[0] * d1
    return float(x[0]), float(x[1])


def main(repo: Path, out: Path) -> None:
    profiles, labels = [], []
    for i in range(8):
        text = subprocess.run(
            ["git", "--git-dir", str(repo), "show", f"{COMMIT}:profile_{i}.csv"],
            check=True, capture_output=True, text=True,
        ).stdout  # fmt: skip
        rows = [r.split(",") for r in text.strip().splitlines()[1:]]
        j = np.array([float(r[0]) for r in rows])
        zw = np.array([float(r[1]) if r[1].strip() else np.nan for r in rows]) * 1000.0
        y, z = 0.1 * j + SHIFT[0], SHIFT[1] - zw
        profiles.append((y, z))
        labels.append(bevel_label(y, z))
    d = out / "keyence-vgroove-rootpass"
    d.mkdir(parents=True, exist_ok=True)
    m = max(len(y) for y, _ in profiles)
    y_mm = np.full((len(profiles), m), np.nan)
    z_mm = np.full((len(profiles), m), np.nan)
    for i, (y, z) in enumerate(profiles):
        y_mm[i, : len(y)], z_mm[i, : len(z)] = y, z
    np.savez_compressed(d / "profiles.npz", y_mm=y_mm, z_mm=z_mm)
    meta = {
        "joint": "v-groove",
        "label": "bevel-line intersection (under the root bead)",
        "pitch_mm": 0.1,
        "range_unit_mm": None,
        "source": "github.com/blackhorsewu/roboweld history (commit 2351038), Keyence LJ-V7200"
        " (no licence stated)",
        "shift_to_laser_frame_mm": list(SHIFT),
    }
    (d / "set.json").write_text(json.dumps(meta, indent=2) + "\n")
    with open(d / "labels.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "y_mm", "z_mm"])
        w.writerows([i, f"{y:.4f}", f"{z:.4f}"] for i, (y, z) in enumerate(labels))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
