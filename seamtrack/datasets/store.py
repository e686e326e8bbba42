"""Writing a dataset folder: HDF5 chunk files, resumable, the same bytes on any number of workers.

A dataset folder holds ``dataset.json`` (the manifest: format, seamtrack's version, the spec with
every default filled in, chunk size), ``spec.toml`` (the same spec, to rerun or edit) and
``chunk-000000.h5``, ``chunk-000001.h5``, ...: chunk ``k`` holds samples ``k * chunk_size`` on,
and each file carries the spec and the version in its attributes too.

Why one file per chunk rather than one growing file: HDF5 is not safe against a kill in the
middle of a write (the whole file can become unreadable), and "nothing of an existing dataset
lost" must hold when a run is killed. Each chunk is written to a hidden temporary file and
renamed into place when complete (an atomic step), so a chunk file is either whole or absent;
a rerun of the same command makes only the chunks that are missing, and a larger ``--n``
appends chunks (a last chunk that was short is remade whole; its first samples come out the
same, as every sample has its own seed). Workers write their own chunks; a Dask cluster sends
the arrays back and this process writes them.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack._version import __version__
from seamtrack.datasets import joints
from seamtrack.datasets.generate import PARAM_NAMES, generate
from seamtrack.datasets.layout import (
    FORMAT,
    FORMAT_VERSION,
    MANIFEST,
    REASON_NAMES,
    SPEC_FILE,
    chunk_path,
    read_manifest,
)
from seamtrack.datasets.layout import arrays as arrays_of
from seamtrack.datasets.spec import FAMILIES, MAX_SAMPLES, DatasetSpec, SpecError
from seamtrack.errors import OutputError


def names(spec: DatasetSpec) -> dict[str, Any]:
    """What the integer codes and columns of the arrays mean (stored in every file)."""
    out: dict[str, Any] = {
        "joint_names": list(FAMILIES),
        "feature_names": {f: list(v) for f, v in joints.FEATURES.items()},
        "param_names": list(PARAM_NAMES),
        "path_names": list(spec.path.kinds),
        "material_names": list(spec.part.materials),
        "preset_names": list(spec.sensor.presets),
        "reason_names": list(REASON_NAMES),
    }
    if spec.images:
        from seamtrack.datasets.images import CAMERA_PARAM_NAMES

        out["camera_param_names"] = list(CAMERA_PARAM_NAMES)
        if spec.arc.on:
            from seamtrack.datasets.images import ARC_PARAM_NAMES

            out["arc_param_names"] = list(ARC_PARAM_NAMES)
            out["arc_process_names"] = list(spec.arc.processes)
        out["image_levels"] = 2**spec.camera.bit_depth - 1
    return out


#: HDF5 filters of the image array: byte shuffle then deflate at level 1 (the stripe is a few
#: rows of each column; the rest is dark, so most of an image compresses to nothing).
IMAGE_COMPRESSION: dict[str, Any] = {"compression": "gzip", "compression_opts": 1, "shuffle": True}


def write_chunk(out: Path, spec: DatasetSpec, k: int, arrays: dict[str, np.ndarray]) -> Path:
    """Write chunk ``k`` to a temporary file beside it, then rename it into place.

    The HDF5 file is built in memory and written with Python's own I/O: a full disk is then a
    plain ``OSError`` (ENOSPC) from ``write``, where HDF5 writing to the disk itself fails in
    its flush on close and crashed the process (exit 139)."""
    import io

    import h5py

    path = chunk_path(out, k)
    tmp = out / f".{path.name}.{os.getpid()}.tmp"
    buffer = io.BytesIO()
    try:
        with h5py.File(buffer, "w") as f:
            for name in arrays_of(spec.images, spec.joint.passes[1] > 0, spec.arc.on):
                # One HDF5 chunk an image, compressed (mostly dark pixels).
                filters = (
                    {"chunks": (1, *arrays[name].shape[1:]), **IMAGE_COMPRESSION}
                    if name == "image"
                    else {}
                )
                f.create_dataset(name, data=arrays[name], track_times=False, **filters)
            f.attrs["format"] = FORMAT
            f.attrs["seamtrack_version"] = __version__
            f.attrs["spec"] = spec.canonical()
            f.attrs["spec_toml"] = spec.to_toml()
            f.attrs["chunk"] = k
            f.attrs["start"] = k * spec.chunk_size
            f.attrs["count"] = len(arrays["index"])
            f.attrs["names"] = json.dumps(names(spec), sort_keys=True)
        with open(tmp, "wb") as handle:
            handle.write(buffer.getbuffer())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def chunk_count(path: Path) -> int:
    """Samples in a chunk file; 0 when it is absent or cannot be read."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            return int(f.attrs["count"])
    except (OSError, KeyError):
        return 0


def make_chunk(spec: DatasetSpec, k: int, count: int, out: str | None) -> Any:
    """Generate chunk ``k`` (``count`` samples); write it into ``out`` when given (a local
    worker), else return the arrays (a Dask worker)."""
    arrays = generate(spec, k * spec.chunk_size, count)
    if out is None:
        return arrays
    write_chunk(Path(out), spec, k, arrays)
    return k


def _first_difference(a: Any, b: Any, path: str = "") -> str:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                return _first_difference(a.get(key), b.get(key), f"{path}.{key}" if path else key)
    return f"{path}: {json.dumps(a)} there, {json.dumps(b)} here"


def check_resume(out: Path, spec: DatasetSpec) -> dict[str, Any] | None:
    """The manifest of the dataset already in ``out`` (None for a new or empty folder), or an
    error when the folder holds something else: another spec's dataset, another version's, or
    files that are no dataset. Nothing is written."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"{str(out)!r} is a file, not a folder", field="--out",
                          fix="give a folder path")  # fmt: skip
    manifest = read_manifest(out) if out.is_dir() else None
    if manifest is None:
        if out.is_dir() and any(out.iterdir()):
            raise OutputError(
                f"{str(out)!r} is not empty and holds no dataset ({MANIFEST} is missing)",
                field="--out",
                fix="give a new or empty folder",
            )
        return None
    theirs = manifest.get("spec")
    ours = json.loads(spec.canonical())
    if theirs != ours:
        raise SpecError(
            f"{str(out)!r} holds a dataset of another spec (first difference at "
            f"{_first_difference(theirs, ours)}); resuming would mix the two",
            field="--out",
            fix=f"give a new --out, or rerun with the spec it was written with ({out / SPEC_FILE})",
        )
    if manifest.get("seamtrack_version") != __version__:
        raise SpecError(
            f"{str(out)!r} was written by seamtrack {manifest.get('seamtrack_version')}, this is "
            f"{__version__}: its samples might differ",
            field="--out",
            fix="give a new --out",
        )
    return manifest


def _write_manifest(out: Path, spec: DatasetSpec, n: int) -> None:
    manifest = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "seamtrack_version": __version__,
        "chunk_size": spec.chunk_size,
        "rays": spec.rays,
        "n": n,
        "spec": json.loads(spec.canonical()),
    }
    tmp = out / f".{MANIFEST}.tmp"
    tmp.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
    os.replace(tmp, out / MANIFEST)
    if not (out / SPEC_FILE).exists():
        (out / SPEC_FILE).write_text(spec.to_toml())


def check_run(n: Any, workers: Any, scheduler: str | None) -> None:
    """Refuse a count or worker number that cannot run, before anything is written."""
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_SAMPLES:
        raise SpecError(f"{n!r} samples", field="--n", fix=f"give a whole number 1..{MAX_SAMPLES}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise SpecError(f"{workers!r} workers", field="--workers", fix="give a whole number >= 1")
    if scheduler is not None and workers != 1:
        raise SpecError("--workers and --scheduler both given", field="--workers",
                        fix="use local workers or a Dask cluster, not both")  # fmt: skip


def write_dataset(
    spec: DatasetSpec,
    n: int,
    out: str | Path,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: bool = False,
) -> dict[str, Any]:
    """Generate samples ``0 .. n - 1`` of ``spec`` into the folder ``out`` (resuming or
    appending to the dataset there, if any).

    Returns
    -------
    dict
        ``n``, ``chunks`` (all chunks of n), ``written`` and ``kept`` (chunks made now / found
        whole), ``samples_written``, ``samples_there`` (in whole chunks before this run),
        ``wall_s`` and ``cpu_s`` (this process and its finished workers). When every sample
        asked for is there already, nothing is written.
    """
    import resource

    from seamtrack.io.output import check_writable, new_dir

    check_run(n, workers, scheduler)
    out_path = check_writable(out)
    manifest = check_resume(out_path, spec)
    size = spec.chunk_size
    counts = [min(size, n - k * size) for k in range(math.ceil(n / size))]
    done = (
        [chunk_count(chunk_path(out_path, k)) >= c for k, c in enumerate(counts)]
        if manifest
        else [False] * len(counts)
    )
    todo = [k for k, ok in enumerate(done) if not ok]
    there = 0
    if manifest:  # the samples already written, in whole chunks (a killed run redoes its chunk)
        known = math.ceil(int(manifest["n"]) / size)
        there = sum(chunk_count(chunk_path(out_path, k)) for k in range(known))
    if not todo:  # every sample asked for is there: nothing is written, not even the manifest
        nothing = {"written": 0, "samples_written": 0, "wall_s": 0.0, "cpu_s": 0.0}
        return {"n": n, "chunks": len(counts), "kept": len(counts), "samples_there": there,
                **nothing}  # fmt: skip
    start = time.perf_counter()
    cpu_start = time.process_time()
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    with new_dir(out_path) as folder:
        for stale in folder.glob(".chunk-*.tmp"):  # left by a killed run
            stale.unlink()
        _write_manifest(folder, spec, max(n, int(manifest["n"]) if manifest else 0))
        bar = None
        if progress and todo:
            from tqdm import tqdm

            bar = tqdm(total=sum(counts[k] for k in todo), desc="dataset", unit="sample")
        for k in _execute(spec, folder, todo, counts, workers, scheduler):
            if bar is not None:
                bar.update(counts[k])
        if bar is not None:
            bar.close()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (time.process_time() - cpu_start + after.ru_utime - children.ru_utime
           + after.ru_stime - children.ru_stime)  # fmt: skip
    return {
        "n": n,
        "chunks": len(counts),
        "written": len(todo),
        "kept": len(counts) - len(todo),
        "samples_written": sum(counts[k] for k in todo),
        "samples_there": there,
        "wall_s": time.perf_counter() - start,
        "cpu_s": cpu,
    }


def _execute(
    spec: DatasetSpec, out: Path, todo: list[int], counts: list[int], workers: int,
    scheduler: str | None,
) -> Iterable[int]:  # fmt: skip
    """Make the chunks ``todo``, yielding each chunk index when its file is in place."""
    if scheduler is not None:
        yield from _execute_dask(spec, out, todo, counts, scheduler)
    elif workers <= 1 or len(todo) <= 1:
        for k in todo:
            yield make_chunk(spec, k, counts[k], str(out))
    else:
        from seamtrack.batch.sweep import die_with_parent, usable_workers

        workers, _ = usable_workers(workers, len(todo))  # no more than the machine runs
        with ProcessPoolExecutor(max_workers=workers, initializer=die_with_parent) as pool:
            pending: set[Future[int]] = {
                pool.submit(make_chunk, spec, k, counts[k], str(out)) for k in todo
            }
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    yield future.result()


def _execute_dask(
    spec: DatasetSpec, out: Path, todo: list[int], counts: list[int], scheduler: str
) -> Iterable[int]:
    from seamtrack.batch.sweep import dask_client

    client = dask_client(scheduler)
    from dask.distributed import as_completed

    try:
        futures = {client.submit(make_chunk, spec, k, counts[k], None, pure=False): k
                   for k in todo}  # fmt: skip
        for future in as_completed(futures):
            k = futures[future]
            write_chunk(out, spec, k, future.result())
            yield k
    finally:
        client.close()
