"""The dataset spec: what each sample is drawn from, as a TOML file validated with pydantic.

Every knob is a range ``[min, max]`` (drawn uniformly per sample) or one number (fixed); lists
of names (joint families, materials, sensor presets) are drawn with equal odds (or ``weights``).
Checks are strict (a number is never a boolean or a string) and an error names the field:
``joint.gap_mm: range min 2 > max 1; fix: ...``. :data:`TEMPLATE` is the commented spec that
``seamtrack dataset --template`` writes; every key is optional.
"""

from __future__ import annotations

import difflib
import itertools
import json
import math
import tomllib
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    PlainSerializer,
    ValidationError,
    model_validator,
)

from seamtrack import constants
from seamtrack.errors import SeamtrackError

#: Joint families a dataset draws from (``flat``: a plate with no seam, a negative sample).
FAMILIES = ("square-butt", "v-groove", "fillet", "lap", "outside-corner", "flat")

#: Path kinds of the seam. Geometry mode extrudes the joint's cross-section, which is exact on
#: a straight seam only.
PATHS = ("straight",)

#: Largest number of profile points one chunk file holds in memory while it is built (about
#: 150 MB of arrays): ``chunk_size * rays`` above it is refused.
MAX_CHUNK_POINTS = 8_000_000

#: Largest ``--n`` (the sample index is an int64; beyond this the disk is the limit anyway).
MAX_SAMPLES = 1_000_000_000

#: The ``[noise]`` of a spec with every knob off: the exact stripe of the drawn joint,
#: pixel-quantized.
NOISE_OFF = {
    "range_sigma_mm": 0.0,
    "speckle_sigma_mm": 0.0,
    "dropout_rate": 0.0,
    "secondary_probability": 0.0,
    "outlier_fraction": 0.0,
}

#: Tilts and yaws at or beyond this put the laser plane along the seam.
MAX_TILT_DEG = 80.0


#: Largest number of image pixels one chunk holds in memory while it is built (128 MB of
#: uint16): with ``images``, ``chunk_size * rows * columns`` above it is refused.
MAX_CHUNK_PIXELS = 64 * 1024 * 1024


class SpecError(SeamtrackError):
    """A dataset spec (or a flag of ``seamtrack dataset``) that cannot be used."""


def _as_range(value: float | list[float]) -> tuple[float, float]:
    if isinstance(value, list):
        if len(value) != 2:
            raise ValueError(f"a range is [min, max], got {len(value)} numbers")
        lo, hi = value
    else:
        lo = hi = value
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError("range bounds must be finite")
    if lo > hi:
        raise ValueError(f"range min {lo:g} > max {hi:g}")
    return float(lo), float(hi)


_Number = Annotated[float, Field(strict=True, allow_inf_nan=True)]
if TYPE_CHECKING:  # what a validated range is
    Range = tuple[float, float]
else:  #: ``[min, max]`` or one number; validated to a ``(min, max)`` tuple.
    Range = Annotated[
        _Number | list[_Number], AfterValidator(_as_range), PlainSerializer(list, return_type=list)
    ]
Flag = Annotated[bool, Field(strict=True)]
Names = Annotated[list[Annotated[str, Field(strict=True)]], Field(min_length=1)]


def _nonnegative(r: tuple[float, float]) -> tuple[float, float]:
    if r[0] < 0:
        raise ValueError(f"must be >= 0, got min {r[0]:g}")
    return r


def _positive(r: tuple[float, float]) -> tuple[float, float]:
    if r[0] <= 0:
        raise ValueError(f"must be > 0, got min {r[0]:g}")
    return r


def _fraction(r: tuple[float, float]) -> tuple[float, float]:
    if r[0] < 0 or r[1] > 1:
        raise ValueError(f"must lie in [0, 1], got [{r[0]:g}, {r[1]:g}]")
    return r


def _open_angle(r: tuple[float, float]) -> tuple[float, float]:
    if r[0] <= 0 or r[1] >= 180:
        raise ValueError(f"must lie in (0, 180) deg, got [{r[0]:g}, {r[1]:g}]")
    return r


def _tilt(r: tuple[float, float]) -> tuple[float, float]:
    if max(abs(r[0]), abs(r[1])) >= MAX_TILT_DEG:
        raise ValueError(f"must lie in (-{MAX_TILT_DEG:g}, {MAX_TILT_DEG:g}) deg")
    return r


NonNegativeRange = Annotated[Range, AfterValidator(_nonnegative)]
PositiveRange = Annotated[Range, AfterValidator(_positive)]
FractionRange = Annotated[Range, AfterValidator(_fraction)]
AngleRange = Annotated[Range, AfterValidator(_open_angle)]
TiltRange = Annotated[Range, AfterValidator(_tilt)]


def _check_known(
    names: Sequence[str], known: Iterable[str], field: str, says: str, quoted: bool = False
) -> None:
    """Refuse the first of ``names`` that is not ``known``: a :class:`_FieldError` at
    ``field.i`` saying ``says`` (formatted with the name), its fix the nearest known name and
    the list (each name quoted where ``quoted``)."""
    known = list(known)
    for i, name in enumerate(names):
        if name not in known:
            close = difflib.get_close_matches(name, known, n=1)
            listing = ", ".join(repr(k) if quoted else k for k in known)
            raise _FieldError(
                f"{field}.{i}",
                says.format(name),
                (f"did you mean {close[0]!r}? " if close else "") + f"use one of {listing}",
            )


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class JointSpec(_Section):
    families: Names = ["square-butt", "v-groove", "fillet", "lap", "outside-corner"]
    weights: list[Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]] | None = None
    thickness_mm: PositiveRange = (4.0, 12.0)
    groove_angle_deg: AngleRange = (40.0, 90.0)
    root_face_mm: NonNegativeRange = (0.0, 2.0)
    gap_mm: NonNegativeRange = (0.0, 2.0)
    misalignment_mm: Range = (-1.0, 1.0)
    web_angle_deg: AngleRange = (70.0, 110.0)
    corner_angle_deg: AngleRange = (70.0, 110.0)
    sheet_thickness_mm: PositiveRange = (1.0, 2.5)
    sheet_gap_mm: NonNegativeRange = (0.0, 0.5)
    tack_probability: FractionRange = (0.0, 0.0)
    tack_height_mm: PositiveRange = (0.5, 1.5)
    tack_width_mm: PositiveRange = (3.0, 6.0)
    #: Layers of beads laid in a V-groove (issue 25): an integer drawn in [min, max]; (0, 0):
    #: none, and no groove labels stored.
    passes: NonNegativeRange = (0.0, 0.0)
    bead_area_mm2: PositiveRange = (8.0, 20.0)

    @model_validator(mode="after")
    def _consistent(self) -> JointSpec:
        _check_known(self.families, FAMILIES, "families", "unknown joint family {!r}")
        if self.passes[1] > 12:
            raise _FieldError(
                "passes", f"up to {self.passes[1]:g} layers", "draw at most 12 layers of beads"
            )
        if self.weights is not None and len(self.weights) != len(self.families):
            raise _FieldError(
                "weights",
                f"{len(self.weights)} weights for {len(self.families)} families",
                "give one weight per family, or none",
            )
        if "v-groove" in self.families and self.root_face_mm[1] >= self.thickness_mm[0]:
            raise _FieldError(
                "root_face_mm",
                f"a root face up to {self.root_face_mm[1]:g} mm does not fit in plates from "
                f"{self.thickness_mm[0]:g} mm",
                "keep root_face_mm's max below thickness_mm's min",
            )
        return self


class PathSpec(_Section):
    kinds: Names = ["straight"]
    position_mm: NonNegativeRange = (0.0, 200.0)

    @model_validator(mode="after")
    def _known(self) -> PathSpec:
        _check_known(
            self.kinds,
            PATHS,
            "kinds",
            "path {!r} is not available in geometry mode (an extruded cross-section is exact "
            "on a straight seam only)",
        )
        return self


class PartSpec(_Section):
    materials: Names = ["mill-scale steel", "blasted steel", "brushed stainless"]

    @model_validator(mode="after")
    def _known(self) -> PartSpec:
        from seamtrack.sensing.materials import MATERIALS

        _check_known(self.materials, MATERIALS, "materials", "unknown material {!r}", quoted=True)
        return self


class SensorSpec(_Section):
    presets: Names = ["paper"]
    quantize: Flag = True
    standoff_offset_mm: Range = (-15.0, 15.0)
    lateral_offset_mm: Range = (-4.0, 4.0)
    tilt_deg: TiltRange = (-10.0, 10.0)
    roll_deg: TiltRange = (-10.0, 10.0)
    yaw_deg: TiltRange = (0.0, 0.0)

    @model_validator(mode="after")
    def _known(self) -> SensorSpec:
        from seamtrack.sensing.sensor import PRESET_SPECS

        _check_known(self.presets, PRESET_SPECS, "presets", "unknown sensor preset {!r}")
        for name in self.presets:
            self._seam_in_view(name)
        return self

    def _seam_in_view(self, name: str) -> None:
        """The seam point within the preset's range (its depth of field about the range
        centre) and, at the nearest standoff drawn (the narrowest field), its field of view."""
        from seamtrack.sensing.sensor import preset

        sensor = preset(name)
        centre = sensor.range_center_mm
        low, high = sensor.range_near_mm - centre, sensor.range_far_mm - centre
        lo, hi = self.standoff_offset_mm
        slack = 1e-9 * sensor.depth_of_field_mm
        if lo < low - slack or hi > high + slack:
            raise _FieldError(
                "standoff_offset_mm",
                f"[{lo:g}, {hi:g}] mm puts the seam outside the range of preset {name!r} "
                f"({sensor.range_near_mm:.4g}-{sensor.range_far_mm:.4g} mm, centre "
                f"{centre:.4g} mm): those samples would see nothing",
                f"keep it within [{_inward(low, +1):g}, {_inward(high, -1):g}] mm",
            )
        half = float(sensor.half_width_mm(centre + lo))
        widest = max(abs(x) for x in self.lateral_offset_mm)
        if widest > half * (1 + 1e-9):
            raise _FieldError(
                "lateral_offset_mm",
                f"{list(self.lateral_offset_mm)} mm puts the seam outside the field of view of "
                f"preset {name!r} ({2 * half:.4g} mm wide at the nearest standoff drawn, "
                f"{centre + lo:.4g} mm)",
                f"keep it within [-{_inward(half, -1):g}, {_inward(half, -1):g}] mm (or raise "
                "standoff_offset_mm's min: the field widens with range)",
            )


def _inward(value: float, direction: int) -> float:
    """``value`` rounded to 0.01 towards ``direction`` (+1 up, -1 down): a bound to print."""
    step = math.ceil if direction > 0 else math.floor
    return step(round(value * 100, 6)) / 100


class NoiseSpec(_Section):
    """The knobs of :class:`seamtrack.sensing.stripe.StripeNoise`, each a range."""

    range_sigma_mm: NonNegativeRange = (0.0, 0.01)
    speckle_sigma_mm: NonNegativeRange = (0.0, 0.01)
    speckle_correlation_rays: PositiveRange = (8.0, 8.0)
    dropout_rate: FractionRange = (0.0, 0.02)
    secondary_probability: FractionRange = (0.0, 0.05)
    outlier_fraction: FractionRange = (0.0, 0.01)


class CameraSpec(_Section):
    """The camera of ``--images`` (:class:`seamtrack.sensing.camera.Camera`), its knobs drawn
    per sample, and the peak detector that measures each image as a sensor's firmware does."""

    # The physical ranges are the camera's (_physical); a dataset's chunks cap the chip at 4096.
    rows: Annotated[int, Field(strict=True, le=4096)] = 512
    columns: Annotated[int, Field(strict=True, le=4096)] = 1024
    bit_depth: Annotated[int, Field(strict=True)] = 10
    f_number: PositiveRange = (4.0, 16.0)
    wavelength_nm: PositiveRange = (660.0, 660.0)
    line_thickness_mm: PositiveRange = (0.1, 0.3)
    exposure: PositiveRange = (0.3, 0.8)
    full_well_e: PositiveRange = (10_000.0, 10_000.0)
    read_noise_e: NonNegativeRange = (0.0, 10.0)
    ambient: NonNegativeRange = (0.0, 0.005)
    speckle_probability: FractionRange = (1.0, 1.0)
    shot_noise_probability: FractionRange = (1.0, 1.0)
    method: Literal["centroid", "gaussian", "steger"] = "centroid"
    threshold: Annotated[float, Field(strict=True, ge=0, le=1, allow_inf_nan=False)] = 0.03
    choose: Literal["strongest", "first", "widest"] = "strongest"

    @model_validator(mode="after")
    def _physical(self) -> CameraSpec:
        """Both ends of every range within the camera's physical range (the one definition,
        :data:`seamtrack.sensing.camera.RANGES`)."""
        from seamtrack.sensing.camera import RANGES, range_error

        for key in CameraSpec.model_fields:
            if key not in RANGES:
                continue
            value = getattr(self, key)
            for end in value if isinstance(value, tuple) else (value,):
                if error := range_error(key, end):
                    raise _FieldError(key, error.message, error.fix or "")
        return self


ArcProcess = Literal["mag-short", "mag-spray", "tig"]


class ArcSpec(_Section):
    """The welding arc in ``--images`` (image mode's ``[arc]``, docs/arc.md), drawn per sample:
    its light through the camera's band-pass filter, the plate it lights and heats, fume and
    spatter. The labels stay the noise-free truth (``image_truth_*``); ``arc_params`` says what
    was drawn. The arc stands on the seam ``look_ahead_mm`` behind the laser plane (the torch
    follows the sensor along +x of the seam frame)."""

    #: Chance that a sample's image has the arc (0: never, and no arc arrays are stored).
    probability: FractionRange = (0.0, 0.0)
    processes: Annotated[list[ArcProcess], Field(min_length=1)] = ["mag-spray"]
    #: The welding current (A), as a scene's ``arc.current_a`` (0-1000 A).
    current_a: PositiveRange = (150.0, 300.0)
    #: The laser line's distance ahead of the arc (mm). Published trackers look 20-40 mm ahead
    #: (ABB Weldguide / Scansonic TH6D product data).
    look_ahead_mm: PositiveRange = (20.0, 40.0)
    #: The band-pass filter's full width at half maximum (nm), centred on the laser's line.
    filter_fwhm_nm: PositiveRange = (10.0, 10.0)
    spatter: Flag = True
    fume: Flag = True
    glow: Flag = True

    @model_validator(mode="after")
    def _physical(self) -> ArcSpec:
        if self.current_a[1] > 1000.0:
            raise _FieldError(
                "current_a",
                f"up to {self.current_a[1]:g} A",
                "draw at most 1000 A (a scene's bound)",
            )
        if self.filter_fwhm_nm[0] < 0.1:
            raise _FieldError(
                "filter_fwhm_nm",
                f"a filter {self.filter_fwhm_nm[0]:g} nm wide",
                "give at least 0.1 nm (the narrowest interference filters)",
            )
        return self

    @property
    def on(self) -> bool:
        """Whether any sample can draw the arc."""
        return self.probability[1] > 0.0


class DatasetSpec(_Section):
    """A validated dataset spec (frozen)."""

    seed: Annotated[int, Field(strict=True, ge=0, lt=2**63)] = 0
    rays: Annotated[int, Field(strict=True, ge=2, le=constants.MAX_RAYS)] = 1024
    chunk_size: Annotated[int, Field(strict=True, ge=1, le=1_000_000)] = 1024
    joint: JointSpec = JointSpec()
    path: PathSpec = PathSpec()
    part: PartSpec = PartSpec()
    sensor: SensorSpec = SensorSpec()
    noise: NoiseSpec = NoiseSpec()
    images: Flag = False
    camera: CameraSpec = CameraSpec()
    arc: ArcSpec = ArcSpec()

    @model_validator(mode="before")
    @classmethod
    def _image_chunks(cls, data: Any) -> Any:
        """With images and no chunk size given, chunks as large as :data:`MAX_CHUNK_PIXELS`
        allows (at most the default 1024)."""
        if isinstance(data, dict) and data.get("images") is True and "chunk_size" not in data:
            given = data.get("camera")
            camera = given if isinstance(given, dict) else {}
            rows, columns = camera.get("rows", 512), camera.get("columns", 1024)
            if isinstance(rows, int) and isinstance(columns, int) and rows > 0 and columns > 0:
                size = max(1, min(1024, MAX_CHUNK_PIXELS // (rows * columns)))
                data = {**data, "chunk_size": size}
        return data

    @model_validator(mode="after")
    def _chunk_fits(self) -> DatasetSpec:
        if self.chunk_size * self.rays > MAX_CHUNK_POINTS:
            raise _FieldError(
                "chunk_size",
                f"{self.chunk_size} samples x {self.rays} rays is more than "
                f"{MAX_CHUNK_POINTS:,} points in one chunk",
                f"use chunk_size <= {MAX_CHUNK_POINTS // self.rays}",
            )
        pixels = self.camera.rows * self.camera.columns
        if self.images and self.chunk_size * pixels > MAX_CHUNK_PIXELS:
            raise _FieldError(
                "chunk_size",
                f"{self.chunk_size} images of {self.camera.rows} x {self.camera.columns} are more "
                f"than {MAX_CHUNK_PIXELS:,} pixels in one chunk",
                f"use chunk_size <= {max(1, MAX_CHUNK_PIXELS // pixels)}",
            )
        if self.images:
            self._check_camera()
        if self.arc.on and not self.images:
            raise _FieldError(
                "arc.probability",
                "the arc is drawn into camera images, and this spec has none",
                "set images = true (or --images), or arc.probability = 0",
            )
        return self

    def _check_camera(self) -> None:
        """The spec's laser line fits each preset's field (:meth:`Camera.check`)."""
        from seamtrack.errors import SensorGeometryError
        from seamtrack.sensing.camera import Camera
        from seamtrack.sensing.sensor import preset

        c = self.camera
        # A thick line is wide at its waist, a thin one diverges most (at the longest
        # wavelength): check the ends. The fastest lens at the shortest wavelength supersamples
        # most: the image's memory bound.
        ends = itertools.product(self.sensor.presets, c.line_thickness_mm, c.wavelength_nm)
        for name, thickness, wavelength in ends:
            try:
                Camera(
                    rows=c.rows,
                    columns=c.columns,
                    wavelength_nm=wavelength,
                    f_number=c.f_number[0],
                    line_thickness_mm=thickness,
                ).check(preset(name))
            except SensorGeometryError as exc:
                key = (exc.field or "line_thickness_mm").rsplit(".", 1)[-1]
                fix = exc.fix or "give a thinner line"
                if key == "supersample":  # a spec has no supersample: it follows the f-number
                    key = "rows"
                    fix = "give fewer rows x columns, or raise f_number's min (a faster lens "
                    fix += "needs finer sub-pixels for its speckle)"
                raise _FieldError(
                    f"camera.{key}", f"{exc.message} with preset {name!r}", fix
                ) from None

    def canonical(self) -> str:
        """The spec as sorted JSON, every default filled in: equal specs give equal text."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True)

    def to_toml(self) -> str:
        import tomli_w

        return tomli_w.dumps(self.model_dump(mode="json", exclude_none=True))


class _FieldError(ValueError):
    """Raised inside a model validator: pydantic wraps it; :func:`parse_spec` unwraps it."""

    def __init__(self, field: str, message: str, fix: str):
        super().__init__(message)
        self.field, self.message, self.fix = field, message, fix


_SECTIONS = {
    "joint": JointSpec,
    "path": PathSpec,
    "part": PartSpec,
    "sensor": SensorSpec,
    "noise": NoiseSpec,
    "camera": CameraSpec,
    "arc": ArcSpec,
}


def _fix(kind: str, loc: list[str]) -> str:
    if kind == "extra_forbidden":
        import difflib

        model: Any = _SECTIONS.get(loc[0], DatasetSpec) if len(loc) > 1 else DatasetSpec
        keys = list(model.model_fields)
        close = difflib.get_close_matches(loc[-1], keys, n=1)
        return (f"did you mean {close[0]!r}? " if close else "") + f"keys here: {', '.join(keys)}"
    if kind in {"float_type", "int_type", "finite_number", "float_parsing", "int_parsing"}:
        return "give a finite number, or [min, max]"
    if kind in {"bool_type", "bool_parsing"}:
        return "give true or false"
    if kind in {"string_type", "list_type", "too_short"}:
        return 'give a list of names, e.g. ["v-groove"]'
    if kind in {"greater_than", "greater_than_equal", "less_than", "less_than_equal"}:
        return "give a number within the bound"
    return "give [min, max] with min <= max in the key's unit (seamtrack dataset --template)"


def parse_spec(data: dict[str, Any], source: str = "spec") -> DatasetSpec:
    """Validate a spec dict; raise :class:`SpecError` naming the first bad field."""
    try:
        return DatasetSpec.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = [str(x) for x in err["loc"]]
        cause = (err.get("ctx") or {}).get("error")
        if isinstance(cause, _FieldError):
            field = ".".join([*loc, cause.field])
            raise SpecError(cause.message, field=f"{source}: {field}", fix=cause.fix) from None
        # A union type reports its branch ("float", "list[float]") in the location: drop it.
        loc = [p for p in loc if not p.startswith(("float", "list[", "function-after"))]
        got = err.get("input")
        got_text = "" if isinstance(got, dict) or err["type"] == "missing" else f" (got {got!r})"
        message = err["msg"].removeprefix("Value error, ") + got_text
        raise SpecError(
            message, field=f"{source}: {'.'.join(loc)}", fix=_fix(err["type"], loc)
        ) from None


def with_images(spec: DatasetSpec) -> DatasetSpec:
    """``spec`` with ``images = true`` (what ``--images`` does): the keys it was given stay, a
    chunk size it was not given follows the image size."""
    if spec.images:
        return spec
    return parse_spec({**spec.model_dump(mode="json", exclude_unset=True), "images": True})


def load_spec(path: str | Path) -> DatasetSpec:
    """Read and validate a spec file."""
    p = Path(path)
    try:
        text = p.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or "not a text file"
        raise SpecError(
            f"cannot read {str(p)!r}: {reason}",
            field="SPEC",
            fix="give a spec file (seamtrack dataset --template -o spec.toml writes one)",
        ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"not valid TOML: {exc}", field=p.name, fix="fix the syntax") from None
    return parse_spec(data, source=p.name)


TEMPLATE = """\
# seamtrack dataset spec: every sample is drawn at random (seeded) from these ranges.
#   seamtrack dataset THIS.toml --n 10000 --out DIR [--workers 2]
# A range is [min, max] (drawn uniformly per sample) or one number (fixed). Units are in the key
# names (mm); angles are in degrees only in keys ending _deg. Every key is optional: a missing
# key takes the value shown here.

seed = 0            # the same spec and seed give the same bytes, on any number of workers
rays = 1024         # laser rays per profile (points per sample)
chunk_size = 1024   # samples per HDF5 file (chunk-000000.h5, ...); a killed run redoes one chunk
                    # (with images and no chunk_size: as many as 64 Mpixel hold, e.g. 128)
images = false      # camera images too ([camera] below); the --images flag sets it

[joint]
# Families drawn with equal odds (or give weights = [...], one per family). "flat" is a plate
# with no seam (seam_point_laser is NaN). See the README ("Datasets") for each seam point.
families = ["square-butt", "v-groove", "fillet", "lap", "outside-corner"]
thickness_mm = [4.0, 12.0]       # plate thickness (square butt, V-groove)
groove_angle_deg = [40.0, 90.0]  # V-groove included angle
root_face_mm = [0.0, 2.0]        # V-groove root face (its max must stay below thickness's min)
gap_mm = [0.0, 2.0]              # root gap (square butt, V-groove)
misalignment_mm = [-1.0, 1.0]    # high-low: the right plate this much deeper (butt, V-groove)
web_angle_deg = [70.0, 110.0]    # fillet: angle between web and flange
corner_angle_deg = [70.0, 110.0] # outside corner: angle between the two faces
sheet_thickness_mm = [1.0, 2.5]  # lap: the top sheet
sheet_gap_mm = [0.0, 0.5]        # lap: between the sheets
tack_probability = 0.0           # chance that the stripe crosses a tack weld over the seam
tack_height_mm = [0.5, 1.5]      # the tack's mound (the seam label stays the true root)
tack_width_mm = [3.0, 6.0]
passes = [0, 0]                  # layers of beads in a V-groove (their 7 points are stored)
bead_area_mm2 = [8.0, 20.0]      # each bead's cross-section

[path]
kinds = ["straight"]             # geometry mode extrudes the cross-section: straight seams
position_mm = [0.0, 200.0]       # where along the seam the profile is taken (T_world_seam)

[part]
# Reflectance models of seamtrack.sensing.materials (they shape the images; the geometric
# profile does not depend on them): "mill-scale steel", "blasted steel", "brushed stainless",
# "bright aluminium", "white matte".
materials = ["mill-scale steel", "blasted steel", "brushed stainless"]

[sensor]
presets = ["paper"]              # seamtrack sensor --list
quantize = true                  # snap points to the chip's pixels (Eq. 1-3)
standoff_offset_mm = [-15.0, 15.0]  # range z_L of the seam point minus the preset's range centre
                                    # (within each preset's range: paper -21.6 to 38.4)
lateral_offset_mm = [-4.0, 4.0]  # y_L of the seam point (within each preset's field of view at
                                 # the nearest standoff drawn: paper +-9.77 at -15)
tilt_deg = [-10.0, 10.0]         # travel angle: the sensor leans along the seam (about y_S)
roll_deg = [-10.0, 10.0]         # work angle: about the seam (x_S)
yaw_deg = 0.0                    # about the laser axis (the plane turns against the seam)

[noise]
# The knobs of the mesh-mode stripe (sensor.stripe_noise in a scene), each drawn per sample.
# All zero: the exact geometry, pixel-quantized.
range_sigma_mm = [0.0, 0.01]         # Gaussian range noise at the centre of the depth of field
speckle_sigma_mm = [0.0, 0.01]       # correlated range noise along the stripe
speckle_correlation_rays = 8.0       # its correlation length, rays
dropout_rate = [0.0, 0.02]           # chance a point is lost at normal incidence
secondary_probability = [0.0, 0.05]  # chance a ray shows its specular secondary reflection
outlier_fraction = [0.0, 0.01]       # points replaced by a spurious peak on the chip

[camera]
# Used with images = true (--images): the image of the stripe on the drawn joint, rendered as in
# image mode (seamtrack.sensing.render), the profile measured from it by the peak detector below.
# Each range lies within what real lenses, lasers and chips have (seamtrack.sensing.camera.RANGES,
# as in a scene's [sensor.camera]): the bounds are given per key.
rows = 512                       # pixels along the range (x_c), 3-4096; the chip keeps its size
columns = 1024                   # pixels along the stripe (z_c), 3-4096
bit_depth = 10                   # 1-16: stored as uint16 grey levels 0 .. 2^bit_depth - 1
f_number = [4.0, 16.0]           # working f-number, 0.95-64: diffraction blur and speckle grain
wavelength_nm = 660.0            # 200-2000
line_thickness_mm = [0.1, 0.3]   # 1/e^2 thickness of the laser sheet at its waist, 0.005-5
exposure = [0.3, 0.8]            # peak of a white plane at the range centre, share of full well,
                                 # 1e-4-100
full_well_e = 10000.0            # electrons, 1000-1000000
read_noise_e = [0.0, 10.0]       # electrons RMS, 0-100
ambient = [0.0, 0.005]           # ambient or arc light, share of full well on every pixel, 0-1
speckle_probability = 1.0        # chance a sample's image has laser speckle (0: never)
shot_noise_probability = 1.0     # chance it has shot noise
method = "centroid"              # peak detector: centroid, gaussian or steger
threshold = 0.03                 # candidate pixels above this share of full scale (keep it
                                 # above ambient: dark steel peaks at 0.05-0.2 of full scale)
choose = "strongest"             # several peaks in a column: strongest, first or widest

[arc]                            # the welding arc in the images (docs/arc.md); labels: the truth
probability = 0.0                # chance a sample's image has the arc (0: never)
processes = ["mag-spray"]        # drawn from: mag-short, mag-spray, tig
current_a = [150.0, 300.0]       # welding current, A, up to 1000
look_ahead_mm = [20.0, 40.0]     # the laser line ahead of the arc (trackers: 20-40 mm)
filter_fwhm_nm = 10.0            # band-pass width at half maximum, >= 0.1, on the laser's line
spatter = true                   # droplets streaking through the exposure
fume = true                      # the fume's veil and attenuation
glow = true                      # the plate glowing near the arc
"""
