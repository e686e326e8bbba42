"""``seamtrack dataset``: labelled stripe profiles drawn from a spec (see
:mod:`seamtrack.datasets`)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from seamtrack.cli.jobs import progress_wanted as _progress_wanted
from seamtrack.cli.parsing import QUIET_HELP, add_workers_arguments
from seamtrack.errors import OutputError


def cmd_dataset(args: argparse.Namespace) -> int:
    """``seamtrack dataset``: write a commented spec, summarize a dataset, or generate one."""
    from seamtrack.datasets.spec import TEMPLATE, SpecError

    if args.template:
        if args.output is None:
            print(TEMPLATE, end="")
            return 0
        target = Path(args.output)
        if target.exists() and not args.force:
            raise OutputError(f"{str(target)!r} exists", field="-o",
                              fix="choose another name or pass --force to overwrite")  # fmt: skip
        try:
            target.write_text(TEMPLATE)
        except OSError as exc:
            raise OutputError(f"cannot write {str(target)!r}: {exc.strerror}", field="-o",
                              fix="choose a writable path") from None  # fmt: skip
        print(f"wrote {target} (edit it, then: seamtrack dataset {target} --n 1000 --out DIR)")
        return 0
    if args.info is not None:
        from seamtrack.datasets.reader import info

        print(info(args.info))
        return 0
    if args.spec is None:
        raise SpecError(
            "no spec given",
            field="SPEC",
            fix="seamtrack dataset SPEC.toml --n N --out DIR (--template writes one)",
        )
    for flag, value in (("--n", args.n), ("--out", args.out)):
        if value is None:
            raise SpecError("missing", field=flag, fix=f"give {flag}, e.g. --n 1000 --out data")
    from seamtrack.datasets.spec import load_spec, with_images
    from seamtrack.datasets.store import write_dataset

    spec = load_spec(args.spec)
    if args.images:
        spec = with_images(spec)
    if isinstance(args.workers, int) and args.workers > 1 and args.scheduler is None:
        from seamtrack.batch.sweep import usable_workers

        _, note = usable_workers(args.workers, math.ceil(args.n / spec.chunk_size))
        if note:
            print(f"seamtrack: {note}", file=sys.stderr)
    done = write_dataset(spec, args.n, args.out, workers=args.workers, scheduler=args.scheduler,
                         progress=_progress_wanted(args))  # fmt: skip
    if not args.quiet and done["written"] == 0:
        print(f"{done['samples_there']} samples already there; nothing to do")
    elif not args.quiet:
        rate = done["samples_written"] / done["cpu_s"] if done["cpu_s"] > 0 else math.nan
        print(
            f"wrote {done['samples_written']} samples in {done['written']} chunk files "
            f"({done['kept']} chunk files already there) into {args.out} in "
            f"{done['wall_s']:.1f} s "
            f"({rate:,.0f} samples per CPU second); seamtrack dataset --info {args.out}"
        )
    return 0


def add_dataset_parser(add: Callable[..., Any]) -> None:
    """Add the ``dataset`` command through the main parser's ``add``."""
    p = add(
        "dataset",
        cmd_dataset,
        "labelled stripe profiles drawn from a spec, into HDF5 chunk files (resumable)",
        scene=False,
    )
    p.add_argument("spec", nargs="?", help="dataset spec (.toml); --template writes one")
    p.add_argument("--n", type=int, help="number of samples (a rerun resumes or appends)")
    p.add_argument("--out", help="dataset folder")
    add_workers_arguments(p)
    p.add_argument(
        "--images",
        action="store_true",
        help="camera images too, rendered as in image mode (the spec's [camera]); = images = true",
    )
    p.add_argument("--template", action="store_true", help="print (or -o: write) a commented spec")
    p.add_argument("-o", "--output", help="with --template: the file to write")
    p.add_argument("--force", action="store_true", help="with --template -o: overwrite")
    p.add_argument("--info", metavar="DIR", help="summarize the dataset in DIR")
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
