"""The pieces every part of the bad-input catalogue builds its entries from: :class:`Entry` and
the command lines the entries share."""

from __future__ import annotations

from dataclasses import dataclass

#: A short paper-verification seam: user-code failures show within a few frames.
SHORT = ["--set", "seam.length_mm=20"]
#: paper-v-groove cut to its first 30 mm: a mesh-mode run for the extractor entries.
MESH = ["paper-v-groove", "--set", "workpiece.params.seam_length_mm=30"]
#: The image-mode scene, for the camera's entries on ``seamtrack render``.
CAMERA = ["v-groove-camera", "--at", "10", "--out", "OUT/image.png"]

#: paper-verification on a UR10e beside the seam: the articulated-arm entries.
ARM = ('robot.model="ur10e"', 'tracker.name="trajectory"', "robot.base_origin_mm=[200,-700,0]")


@dataclass(frozen=True)
class Entry:
    """One bad input: a name, the command's arguments, and whether it is quick enough (a few
    seconds) for the test suite."""

    name: str
    args: tuple[str, ...]
    quick: bool = True
    field: str = ""  # the field the error line must name (a substring of it)


def set_args(*pairs: str) -> tuple[str, ...]:
    out: list[str] = []
    for pair in pairs:
        out += ["--set", pair]
    return tuple(out)


def run_args(*extra: str) -> tuple[str, ...]:
    return ("run", *extra, "--out", "OUT")


def sweep_args(param: str, values: str, *extra: str) -> tuple[str, ...]:
    """``seamtrack sweep paper-corner --param PARAM --values VALUES EXTRA... --out OUT``."""
    return ("sweep", "paper-corner", "--param", param, "--values", values, *extra, "--out", "OUT")


def dataset_args(spec: str, n: str = "8", images: bool = False) -> tuple[str, ...]:
    """``seamtrack dataset SPEC --n N --out OUT`` (``--images``: with camera images)."""
    return ("dataset", spec, "--n", n, "--out", "OUT", *(("--images",) if images else ()))


def set_key(args: tuple[str, ...]) -> str:
    """The key the last ``--set KEY=VALUE`` of ``args`` sets."""
    last = len(args) - 1 - args[::-1].index("--set")
    return args[last + 1].split("=")[0]


def naming_key(name: str, args: tuple[str, ...], quick: bool = True) -> Entry:
    """An entry whose error line must name the key its last ``--set`` sets: most of the
    catalogue, written without saying the key twice."""
    return Entry(name, args, quick=quick, field=set_key(args))


def run_set(*pairs: str) -> tuple[str, ...]:
    """``seamtrack run --set PAIR ... --out OUT``: the default scene with the given keys."""
    return run_args(*set_args(*pairs))


def seams_of(name: str, step: str, *extra: str) -> Entry:
    """``seamtrack seams STEP EXTRA... --view OUT/v.png``, its error naming the part."""
    return Entry(name, ("seams", step, *extra, "--view", "OUT/v.png"), field="PART")
