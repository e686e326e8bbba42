"""Parameter sweeps: one scene, one key, many values (and seeds).

Cases run in a local process pool (``workers``, default 1) or on a Dask cluster
(``scheduler="tcp://host:port"``, needs the ``dask`` extra). Each finished case is appended to
``results.jsonl`` in the output folder as it finishes, so a killed sweep loses nothing: a rerun
skips the cases already there. A case that fails is recorded with its error and the sweep goes
on; a rerun tries the failed cases again.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack import constants
from seamtrack.errors import SeamtrackError
from seamtrack.io.output import check_writable, json_safe, new_dir, prepare_dir
from seamtrack.simulation.scene import load_scene, parse_override

#: How long to wait for a Dask scheduler to answer before refusing the sweep, s.
DASK_CONNECT_TIMEOUT_S = 10.0

#: Columns of the sweep table, in order.
TABLE_KEYS = (
    "status",
    "max_error_mm",
    "min_error_mm",
    "rms_error_mm",
    "mean_speed_mm_s",
    "completed_fraction",
)

#: What sweep.png draws against the swept value: the largest error and the 95th percentile
#: (the minimum error, 0 wherever the torch crosses the seam, says nothing).
PLOT_KEYS = ("max_error_mm", "p95_error_mm")


@dataclass(frozen=True)
class Case:
    """One run of a sweep: the swept value and the seed."""

    param: str
    value: Any
    seed: int | None = None

    @property
    def key(self) -> str:
        seed = "" if self.seed is None else f"|seed={self.seed}"
        return f"{self.param}={json.dumps(self.value)}{seed}"


def parse_values(text: str) -> list[Any]:
    """``"6,5,1"`` -> ``[6, 5, 1]``; ``"[0,1,1],[1,1,1]"`` -> two lists; values that are not
    TOML (``"I,II,trajectory"``) are split on commas and kept as strings."""
    import tomllib

    try:
        return list(tomllib.loads(f"v = [{text}]")["v"])
    except tomllib.TOMLDecodeError:
        return [parse_override(f"v={item.strip()}")[1] for item in text.split(",") if item.strip()]


def run_case(scene: str, case: Case, overrides: dict[str, Any]) -> dict[str, Any]:
    """Run one case; never raises (a failure is returned as ``{"error": ...}``)."""
    from seamtrack.simulation.loop import simulate

    values = dict(overrides)
    values[case.param] = case.value
    if case.seed is not None:
        values["simulation.seed"] = case.seed
    try:
        result = simulate(load_scene(scene, values))
    except SeamtrackError as exc:
        return {"case": case.key, "value": case.value, "seed": case.seed, "error": str(exc)}
    except Exception as exc:  # a user tracker may raise anything; the sweep must go on
        return {
            "case": case.key,
            "value": case.value,
            "seed": case.seed,
            "error": f"{type(exc).__name__}: {exc}",
        }
    return {
        "case": case.key,
        "value": case.value,
        "seed": case.seed,
        "summary": json_safe(result.summary),
    }


def _done(results_path: Path) -> dict[str, dict[str, Any]]:
    """The cases already finished in ``results.jsonl``; a last line cut by a kill is dropped
    from the file (that case runs again), so that new rows start on a line of their own. A case
    that failed is not finished: a rerun tries it again (its cause may have been fixed)."""
    done: dict[str, dict[str, Any]] = {}
    if not results_path.exists():
        return done
    text = results_path.read_text()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
        results_path.write_text(text)
    for line in text.splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            continue  # a damaged line: that case runs again
        if isinstance(row, dict) and "case" in row and "summary" in row:
            done[row["case"]] = row
    return done


def run_sweep(
    scene: str,
    param: str,
    values: Sequence[Any],
    *,
    overrides: dict[str, Any] | None = None,
    seeds: Sequence[int] | None = None,
    workers: int = 1,
    scheduler: str | None = None,
    out_dir: str | Path | None = None,
    progress: bool = False,
) -> list[dict[str, Any]]:
    """Run every case (value x seed) and return one row per case, in case order.

    ``out_dir`` enables streaming to ``results.jsonl`` and resuming.
    """
    overrides = dict(overrides or {})
    values = expand_values(scene, param, values, overrides)
    seed_list: list[int | None] = list(seeds) if seeds else [None]
    _check_sweep(scene, param, values, overrides, seed_list, workers)
    if scheduler is not None:
        check_scheduler(scheduler)  # before anything is written, within a time bound
    cases = [Case(param, v, s) for v in values for s in seed_list]
    results_path = None
    done: dict[str, dict[str, Any]] = {}
    if out_dir is not None:
        check_writable(out_dir)
        results_path = Path(out_dir) / "results.jsonl"
        done = _done(results_path)
    todo = [c for c in cases if c.key not in done]
    workers, _ = usable_workers(workers, len(todo))
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc="sweep", unit="case", leave=False)
    with new_dir(out_dir) if out_dir is not None else nullcontext():
        for row in _execute(scene, todo, overrides, workers, scheduler):
            done[row["case"]] = row
            if results_path is not None:
                with results_path.open("a") as handle:
                    handle.write(json.dumps(row) + "\n")
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    return [done[c.key] for c in cases]


#: What one worker of a sweep may take (MB): a mesh-mode case holds its libraries and mesh,
#: about 0.7 GB (seamtrack.constants, MAX_MESH_TRIANGLES); a seam-mode case far less.
WORKER_MB = 700.0


def usable_workers(requested: int, cases: int) -> tuple[int, str]:
    """The workers a sweep starts: ``requested``, but no more than the cases, the CPUs this
    process may run on (its affinity), and what the available memory holds at
    :data:`WORKER_MB` each; and a line saying why when that is fewer than asked."""
    import os

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cpus = max(1, cpus or 1)
    available_mb = _available_mb()
    by_memory = max(1, int(available_mb // WORKER_MB)) if math.isfinite(available_mb) else cpus
    limits = {
        f"{cpus} CPUs this process may use": cpus,
        f"{available_mb / 1024:.1f} GB of free memory at {WORKER_MB / 1024:.1f} GB a worker": (
            by_memory
        ),
        f"{cases} case{'' if cases == 1 else 's'} to run": max(1, cases),
    }
    reason, cap = min(limits.items(), key=lambda item: item[1])
    if requested <= cap:
        return requested, ""
    return cap, f"--workers {requested} capped at {cap} ({reason})"


def _available_mb() -> float:
    """Memory available to new processes (MB): Linux's MemAvailable (free plus reclaimable
    cache), else the free pages; inf where neither is known."""
    import os

    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) / 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")) / 2**20
    except (ValueError, OSError, AttributeError):
        return math.inf


def expand_values(
    scene: str, param: str, values: Sequence[Any], overrides: dict[str, Any]
) -> list[Any]:
    """The values as given, except ``workpiece.seam`` over ``all``: every seam id of the
    scene's weldment, in order."""
    if param != "workpiece.seam" or list(values) != ["all"]:
        return list(values)
    return list(seam_labels(scene, overrides))


def seam_labels(scene: str, overrides: dict[str, Any]) -> dict[str, str]:
    """Seam id -> ``"s3 fillet base/web/1"`` for the scene's weldment."""
    from seamtrack.simulation.assemble import workpiece_seams

    return {s.id: s.label for s in workpiece_seams(load_scene(scene, overrides))}


#: A sweep of up to this many values checks every one before running; a longer one its
#: first and last (each check loads the scene).
_CHECK_ALL_VALUES = 200


def _check_sweep(
    scene: str,
    param: str,
    values: Sequence[Any],
    overrides: dict[str, Any],
    seeds: Sequence[int | None],
    workers: int,
) -> None:
    """Refuse a sweep that cannot run, before any case runs or any file is written."""
    if not values:
        raise SeamtrackError("no values given", field="--values", fix="e.g. --values 6,5,1")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise SeamtrackError(
            f"{workers!r} workers", field="--workers", fix="give a whole number >= 1"
        )
    bad_seed = next((s for s in seeds if s is not None and (s < 0 or s >= 2**63)), None)
    if bad_seed is not None:
        raise SeamtrackError(f"seed {bad_seed}", field="--seeds", fix="give seeds >= 0")
    if len(values) * len(seeds) > constants.MAX_SWEEP_CASES:
        raise SeamtrackError(
            f"{len(values)} values x {len(seeds)} seeds is {len(values) * len(seeds)} cases, "
            f"more than {constants.MAX_SWEEP_CASES}",
            field="--values",
            fix="split the sweep into several",
        )
    check = values if len(values) <= _CHECK_ALL_VALUES else [values[0], values[-1]]
    for value in check:  # a bad scene, key or value fails here, with its field
        load_scene(scene, {**overrides, param: value})


def _execute(
    scene: str, cases: list[Case], overrides: dict[str, Any], workers: int, scheduler: str | None
) -> Iterable[dict[str, Any]]:
    if scheduler is not None:
        yield from _execute_dask(scene, cases, overrides, scheduler)
    elif workers <= 1:
        for case in cases:
            yield run_case(scene, case, overrides)
    else:
        with ProcessPoolExecutor(max_workers=workers, initializer=die_with_parent) as pool:
            pending: set[Future[dict[str, Any]]] = {
                pool.submit(run_case, scene, case, overrides) for case in cases
            }
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    yield future.result()


def die_with_parent() -> None:
    """Worker initializer: end this process when the sweep that started it dies, even by
    SIGKILL (which runs no clean-up), so no orphan keeps computing or holds the terminal.

    Linux: the kernel sends SIGKILL on the parent's death (``PR_SET_PDEATHSIG``). Elsewhere,
    and as a second line, a daemon thread watches the parent's pid.
    """
    import ctypes
    import os
    import signal
    import threading
    import time

    parent = os.getppid()
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()


def dask_client(scheduler: str) -> Any:
    """A ``dask.distributed.Client`` of the scheduler at ``scheduler``, or an error naming
    ``--scheduler`` (Dask missing, or the scheduler unreachable within
    :data:`DASK_CONNECT_TIMEOUT_S`)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise SeamtrackError(
            "Dask is not installed", field="--scheduler", fix="pip install 'seamtrack[dask]'"
        ) from None
    check_scheduler(scheduler)
    try:
        return Client(scheduler, timeout=f"{DASK_CONNECT_TIMEOUT_S}s")
    except (OSError, ValueError) as exc:
        raise SeamtrackError(
            f"cannot reach the Dask scheduler {scheduler!r}: {exc}",
            field="--scheduler",
            fix="start it or give its tcp:// address",
        ) from None


def check_scheduler(scheduler: str, timeout_s: float | None = None) -> None:
    """Refuse an address that is not one (``'not a url'``), nothing listening there, or a
    server that does not answer a Dask scheduler's ``identity`` within ``timeout_s`` (default
    :data:`DASK_CONNECT_TIMEOUT_S`; some other server: the Dask client would wait for its
    handshake forever)."""
    import asyncio

    timeout_s = DASK_CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
    try:
        from distributed.comm import connect
        from distributed.comm.addressing import parse_address, parse_host_port
    except ImportError:
        raise SeamtrackError(
            "Dask is not installed", field="--scheduler", fix="pip install 'seamtrack[dask]'"
        ) from None

    fix = "give the scheduler's address, e.g. tcp://127.0.0.1:8786 (dask scheduler prints it)"
    try:
        scheme, location = parse_address(scheduler, strict=True)
        if scheme in ("tcp", "tls", "ws", "wss"):
            _, port = parse_host_port(location)
            if not 0 < int(port) < 65536:
                raise ValueError(f"port {port} is not within 1..65535")
    except ValueError as exc:
        raise SeamtrackError(
            f"{scheduler!r} is not a scheduler address ({exc})", field="--scheduler", fix=fix
        ) from None

    async def identity() -> Any:
        comm = await connect(scheduler, timeout=timeout_s)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    async def bounded() -> Any:
        return await asyncio.wait_for(identity(), timeout_s)

    try:
        reply = asyncio.run(bounded())
    except (OSError, TimeoutError) as exc:
        silent = isinstance(exc, TimeoutError) and not str(exc)  # connected, no answer
        what = "it answered nothing (a server that is not Dask's)" if silent else str(exc)
        raise SeamtrackError(
            f"no Dask scheduler answered at {scheduler!r} within {timeout_s:g} s: {what}",
            field="--scheduler",
            fix="start the scheduler (dask scheduler) or give its address",
        ) from None
    except Exception as exc:  # the server answered, but not in Dask's protocol
        raise SeamtrackError(
            f"the server at {scheduler!r} is not a Dask scheduler ({type(exc).__name__})",
            field="--scheduler",
            fix=fix,
        ) from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise SeamtrackError(
            f"the server at {scheduler!r} is not a Dask scheduler (it says {kind!r})",
            field="--scheduler",
            fix=fix,
        )


def _execute_dask(
    scene: str, cases: list[Case], overrides: dict[str, Any], scheduler: str
) -> Iterable[dict[str, Any]]:
    client = dask_client(scheduler)
    from dask.distributed import as_completed

    try:
        futures = [client.submit(run_case, scene, case, overrides, pure=False) for case in cases]
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per swept value; with several seeds, means and 95 % confidence half-widths."""
    by_value: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_value.setdefault(json.dumps(row["value"]), []).append(row)
    table = []
    for key, group in by_value.items():
        ok = [g["summary"] for g in group if "summary" in g]
        out: dict[str, Any] = {
            "value": json.loads(key),
            "runs": len(group),
            "failed": len(group) - len(ok),
        }
        if not ok:
            out["error"] = group[0].get("error", "")
            table.append(out)
            continue
        statuses = sorted({s["status"] for s in ok})
        out["status"] = "/".join(statuses)
        for metric in (*TABLE_KEYS[1:], *PLOT_KEYS):
            values = np.array(
                [np.nan if s.get(metric) is None else s[metric] for s in ok], dtype=float
            )
            out[metric] = float(np.mean(values))
            if len(values) > 1:
                out[metric + "_ci95"] = float(
                    1.96 * np.std(values, ddof=1) / math.sqrt(len(values))
                )
        table.append(out)
    return table


def _label(value: Any) -> str:
    """A table cell for a swept value (a replaced table shows its ``name``)."""
    if isinstance(value, str):
        return value
    if isinstance(value, dict) and "name" in value:
        return str(value["name"])
    return json.dumps(value)


def markdown_table(table: Sequence[dict[str, Any]], param: str) -> str:
    """The sweep table as markdown (error columns to 3-4 significant digits)."""
    header = [param, *TABLE_KEYS]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in table:
        cells = [row.get("label") or _label(row["value"])]
        if "error" in row:
            cells += [f"error: {row['error']}"] + [""] * (len(TABLE_KEYS) - 1)
        else:
            cells.append(row["status"])
            for metric in TABLE_KEYS[1:]:
                value = row.get(metric, float("nan"))
                ci = row.get(metric + "_ci95")
                text = f"{value:.4g}" if math.isfinite(value) else "n/a"
                cells.append(text + (f" ± {ci:.2g}" if ci is not None else ""))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_csv(
    rows: Sequence[dict[str, Any]], param: str, path: Path, labels: dict[str, str] | None = None
) -> None:
    """One line per case (value and seed): the swept key, the seed, the error if the case
    failed, and every summary key, so ``pandas.read_csv(path)`` is the whole sweep."""
    keys: list[str] = []
    for row in rows:
        keys += [k for k in row.get("summary", {}) if k not in keys]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow([param, "seed", "error", *keys])
        for row in rows:
            summary = row.get("summary", {})
            value = (labels or {}).get(json.dumps(row["value"])) or _label(row["value"])
            seed = "" if row.get("seed") is None else row["seed"]
            cells = ["" if summary.get(k) is None else summary[k] for k in keys]
            writer.writerow([value, seed, row.get("error", ""), *cells])


def write_sweep(
    table: Sequence[dict[str, Any]],
    param: str,
    out_dir: str | Path,
    plot: bool = True,
    rows: Sequence[dict[str, Any]] | None = None,
) -> None:
    """sweep.md, sweep.json, sweep.csv (with ``rows``, one line per case) and sweep.png beside
    results.jsonl."""
    out = prepare_dir(out_dir)
    (out / "sweep.md").write_text(markdown_table(table, param))
    if rows is not None:
        labels = {json.dumps(r["value"]): r["label"] for r in table if r.get("label")}
        write_csv(rows, param, out / "sweep.csv", labels)
    (out / "sweep.json").write_text(json.dumps(json_safe(list(table)), indent=2) + "\n")
    if plot:
        from seamtrack.viz.plots import plot_sweep

        numeric = [r for r in table if isinstance(r["value"], (int, float)) and "error" not in r]
        if numeric:
            plot_sweep(numeric, param, out / "sweep.png", keys=PLOT_KEYS)
