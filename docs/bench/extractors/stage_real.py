"""Convert the staged real scans (``/tmp/realdata``: ``load.py`` + per-set folders) into the
layout ``seamtrack extractors bench --real DIR`` reads (see docs/extractors.md, "Real data"):

    DIR/<set>/set.json      {"joint": ..., "pitch_mm": ..., "range_unit_mm": ..., "source": ...}
    DIR/<set>/profiles.npz  y_mm (n, m), z_mm (n, m) float: laser-frame (y_L, z_L), the emitter
                            at the origin, z_L the range; NaN where the sensor saw nothing
    DIR/<set>/labels.csv    index,y_mm,z_mm  (the seam point per profile; joint sets only)

Both sets come in their own frames: the LDS as column x pitch and count x unit, the Keyence
as world height (z = -Z_world, about -30..+6 mm). Each is moved into the laser frame, where
the extractors put the emitter (which side of a line faces the sensor, where a ray runs): y
centred on the field of view; z shifted by 100 mm for the LDS (its columns are evenly spaced
in y, as of nearly parallel rays: the emitter far above) and by the LJ-V7200's reference
distance (200 mm) for the Keyence. Labels move alike.

The data stay outside the repository (no licence allows redistributing them)::

    python docs/bench/extractors/stage_real.py /tmp/realdata /tmp/realdata_bench
"""

from __future__ import annotations

import csv
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np


def _write(
    out: Path,
    name: str,
    meta: dict,
    profiles: list,
    labels: np.ndarray | None,
    shift: tuple[float, float],
) -> None:
    d = out / name
    d.mkdir(parents=True, exist_ok=True)
    m = max(len(y) for y, _ in profiles)
    y_mm = np.full((len(profiles), m), np.nan)
    z_mm = np.full((len(profiles), m), np.nan)
    for i, (y, z) in enumerate(profiles):
        y_mm[i, : len(y)], z_mm[i, : len(z)] = y + shift[0], z + shift[1]
    meta = {**meta, "shift_to_laser_frame_mm": list(shift)}
    if labels is not None:
        labels = labels + np.asarray(shift)
    np.savez_compressed(d / "profiles.npz", y_mm=y_mm, z_mm=z_mm)
    (d / "set.json").write_text(json.dumps(meta, indent=2) + "\n")
    if labels is not None:
        with open(d / "labels.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["index", "y_mm", "z_mm"])
            w.writerows([i, f"{y:.4f}", f"{z:.4f}"] for i, (y, z) in enumerate(labels))


def main(src: Path, out: Path) -> None:
    spec = importlib.util.spec_from_file_location("realdata_load", src / "load.py")
    assert spec is not None and spec.loader is not None
    load = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(load)
    lds_src = "github.com/joshkaura/Robotics-Research Sample_Data (no licence stated)"
    lab = load.load_labels("lds_joshkaura")
    seam = np.column_stack([lab["y_mm"], lab["z_mm"]])  # bevel-line intersection, z unit 0.05
    # y centred on the 2048 columns; the columns are evenly spaced in y (nearly parallel rays):
    # the emitter 100 mm behind the zero of the range counts.
    lds_shift = (-0.5 * 2047 * 0.01, 100.0)
    for unit in (0.05, 0.01):
        scale = np.array([1.0, unit / load.LDS_Z_UNIT_MM])  # an affine map keeps intersections
        meta = {"pitch_mm": 0.01, "range_unit_mm": unit, "source": lds_src}
        _write(out, f"lds-vgroove-z{unit}", {**meta, "joint": "v-groove",
               "label": "bevel-line intersection"},
               load.load_lds_vgroove(z_unit_mm=unit), seam * scale, lds_shift)  # fmt: skip
        _write(out, f"lds-block-z{unit}", {**meta, "joint": "none",
               "shape": "raised block on a plate"}, load.load_lds_block(z_unit_mm=unit), None,
               lds_shift)  # fmt: skip
    key_src = "github.com/blackhorsewu/roboweld history, Keyence LJ-V7200 (no licence stated)"
    names, prof = load.load_keyence_vgroove(with_names=True)
    lab = load.load_labels("keyence_roboweld")
    seam = np.column_stack([lab["y_mm"], lab["z_mm"]])
    root = [i for i, n in enumerate(names) if n.startswith("profile_")]
    open_ = [i for i in range(len(names)) if i not in root]
    meta = {"pitch_mm": 0.1, "range_unit_mm": None, "source": key_src}
    key_shift = (-36.0, 200.0)  # y centred on the ~72 mm line; the reference distance
    _write(out, "keyence-vgroove-open", {**meta, "joint": "v-groove",
           "label": "bevel-line intersection"}, [prof[i] for i in open_], seam[open_],
           key_shift)  # fmt: skip
    _write(out, "keyence-vgroove-rootpass", {**meta, "joint": "v-groove",
           "label": "bevel-line intersection (under the root bead)"},
           [prof[i] for i in root], seam[root], key_shift)  # fmt: skip
    _write(out, "keyence-flat", {**meta, "joint": "none", "shape": "flat welding table"},
           load.load_keyence_flat(), None, key_shift)  # fmt: skip


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
