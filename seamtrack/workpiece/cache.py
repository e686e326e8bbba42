"""The on-disk cache of loaded workpieces: one folder per part, arrays checked by SHA-256.

``$SEAMTRACK_CACHE_DIR`` or else ``~/.cache/seamtrack`` holds ``workpieces/<key>/`` with
``mesh.npz``, ``seam.npz`` and ``meta.json``; an entry that is truncated, edited or
inconsistent is rebuilt, never trusted. Imports nothing heavy (a cache hit needs no OCP).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Bump when the cache layout changes.
CACHE_FORMAT = 1


def cache_dir() -> Path:
    """The cache folder: ``$SEAMTRACK_CACHE_DIR`` or ``~/.cache/seamtrack``."""
    env = os.environ.get("SEAMTRACK_CACHE_DIR")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "seamtrack"


def clear_cache(cache_dir: str | Path | None = None) -> int:
    """Delete every cached workpiece; return how many entries were removed."""
    root = Path(cache_dir) if cache_dir is not None else globals()["cache_dir"]()
    root = root / "workpieces"
    if not root.is_dir():
        return 0
    count = 0
    for entry in root.iterdir():
        if entry.is_dir():
            shutil.rmtree(entry, ignore_errors=True)
            count += 1
    return count


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def cache_key(parts: dict[str, Any]) -> str:
    text = json.dumps(parts, sort_keys=True, default=repr)
    return sha256(text.encode())[:32]


def read_cache(entry: Path, key: str) -> dict[str, Any] | None:
    """The cached arrays and metadata, or None when missing or corrupt (never trusted blindly)."""
    try:
        meta = json.loads((entry / "meta.json").read_text())
        if meta.get("key") != key or meta.get("format") != CACHE_FORMAT:
            return None
        arrays: dict[str, Any] = {"meta": meta}
        for name in ("mesh.npz", "seam.npz"):
            blob = (entry / name).read_bytes()
            if sha256(blob) != meta["sha256"][name]:
                return None
            with np.load(entry / name, allow_pickle=False) as data:
                arrays.update({k: np.array(data[k]) for k in data.files})
        v, f, p = arrays["vertices"], arrays["faces"], arrays["points"]
        ok = (
            v.ndim == 2
            and v.shape[1] == 3
            and f.ndim == 2
            and f.shape[1] == 3
            and len(f) == meta["triangle_count"]
            and f.max() < len(v)
            and f.min() >= 0
            and p.ndim == 2
            and p.shape[1] == 3
            and arrays["normals"].shape == p.shape
            and arrays["face_normals"].shape == (len(p), 2, 3)
        )
        return arrays if ok else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError, json.JSONDecodeError):
        return None
    except Exception:  # zipfile.BadZipFile and kin from a truncated npz
        return None


def write_cache(entry: Path, key: str, arrays: dict[str, FloatArray], meta: dict[str, Any]) -> None:
    entry.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".tmp-", dir=entry.parent))
    try:
        np.savez(tmp / "mesh.npz", vertices=arrays["vertices"], faces=arrays["faces"])
        np.savez(
            tmp / "seam.npz",
            points=arrays["points"],
            normals=arrays["normals"],
            face_normals=arrays["face_normals"],
        )
        sums = {n: sha256((tmp / n).read_bytes()) for n in ("mesh.npz", "seam.npz")}
        full = {**meta, "key": key, "format": CACHE_FORMAT, "sha256": sums}
        (tmp / "meta.json").write_text(json.dumps(full, indent=1, default=repr))
        if entry.exists():
            shutil.rmtree(entry, ignore_errors=True)  # stale: read_cache refused it
        try:
            os.replace(tmp, entry)
        except OSError:
            # Another process (a sweep's worker loading the same part) wrote the entry between
            # the two lines above: its arrays are the same, keep them.
            if not entry.exists():
                raise
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def source_hash(*names: str) -> str:
    """Hash of modules of this package (by file name): a change in them changes the key."""
    folder = Path(__file__).parent
    return sha256(b"".join((folder / n).read_bytes() for n in names if (folder / n).exists()))
