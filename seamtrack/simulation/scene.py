"""Scene files: the paper's ASCII initialization file, as TOML.

``load_scene(name_or_path, overrides)`` reads a built-in scene (``seamtrack init --list``) or a
file, applies ``--set KEY=VALUE`` overrides, and validates everything at once: each bad field is
reported with its dotted path and a fix. :func:`seamtrack.simulation.assemble.build_parts`
builds only what a scene needs: a seam-mode scene never imports CadQuery, Embree or PyVista.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from seamtrack.errors import SceneError
from seamtrack.sensing.camera import Camera
from seamtrack.sensing.materials import material
from seamtrack.sensing.sensor import LaserLineSensor, data_sheet, preset
from seamtrack.simulation.checks import check_plugin_params, check_sizes, union_errors
from seamtrack.simulation.robots import check_robot, is_arm

# Strict: a number is never a boolean or a string, a boolean never "yes" or 1.
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False, strict=True)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False, strict=True)]
Finite = Annotated[float, Field(allow_inf_nan=False, strict=True)]
Flag = Annotated[bool, Field(strict=True)]
NonNegativeInt = Annotated[int, Field(ge=0, strict=True)]
Vec3 = tuple[Finite, Finite, Finite]
PositiveVec3 = tuple[Positive, Positive, Positive]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SimulationConfig(_Section):
    welding_speed_mm_s: Positive = 5.0
    seed: Annotated[int, Field(ge=0, strict=True)] = 0
    end_tolerance_mm: Positive | None = None
    stall_time_s: Positive = 5.0
    time_limit_s: Positive | None = None
    wall_time_limit_s: Positive = 600.0
    trace_period_s: Positive = 0.01


class SeamConfig(_Section):
    source: Literal["paper", "points", "csv", "workpiece"] = "paper"
    step_mm: Positive = 2.0
    length_mm: Positive = 400.0
    points_mm: list[list[Finite]] | None = None
    file: str | None = None
    offset_mm: Vec3 = (0.0, 0.0, 0.0)
    rotation_deg: Vec3 = (0.0, 0.0, 0.0)


class CameraConfig(_Section):
    """``[sensor.camera]``: the camera of image mode (:class:`seamtrack.sensing.camera.Camera`)
    and the peak detector that measures each image."""

    rows: Annotated[int, Field(ge=3, le=20_000, strict=True)] | None = None
    columns: Annotated[int, Field(ge=3, le=20_000, strict=True)] | None = None
    roi: tuple[NonNegativeInt, NonNegativeInt, NonNegativeInt, NonNegativeInt] | None = None
    focal_length_mm: Positive | None = None
    f_number: Positive = 8.0
    # Default: the preset's data sheet, else 660 nm.
    wavelength_nm: (
        Annotated[float, Field(ge=200, le=2000, allow_inf_nan=False, strict=True)] | None
    ) = None
    line_thickness_mm: Positive = 0.2
    line_divergence_mrad: NonNegative | None = None
    waist_range_mm: Positive | None = None
    exposure: Positive = 0.5
    full_well_e: Positive = 10_000.0
    read_noise_e: NonNegative = 5.0
    bit_depth: Annotated[int, Field(ge=0, le=16, strict=True)] = 10  # 0: no quantization
    ambient: NonNegative = 0.0
    speckle: Flag = True
    shot_noise: Flag = True
    supersample: Annotated[int, Field(ge=1, le=8, strict=True)] | None = None
    ideal: Flag = False  # every noise source off (Camera.ideal)
    method: Literal["centroid", "gaussian", "steger"] = "centroid"
    threshold: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False, strict=True)] = 0.1
    choose: Literal["strongest", "first", "widest"] = "strongest"


class SensorConfig(_Section):
    preset: str = "paper"
    mode: Literal["seam", "mesh"] = "seam"
    source: Literal["geometry", "image"] = "geometry"
    camera: CameraConfig | None = None
    frame_rate_hz: Positive = 1.0
    latency_s: NonNegative = 0.0
    look_ahead_mm: NonNegative = 10.0
    range_mm: Positive | None = None
    mount_rotation_deg: Vec3 | None = None
    quantize: Flag = True
    noise_range_mm: NonNegative = 0.0
    noise_lateral_mm: NonNegative = 0.0
    rays: Annotated[int, Field(ge=2, strict=True)] | None = None
    refine_float64: Flag = True
    max_incidence_deg: Annotated[float, Field(gt=0, le=90, strict=True)] = 80.0
    depth_of_field_mm: Positive | None = None
    fov_near_mm: Positive | None = None
    fov_far_mm: Positive | None = None
    angle_deg: Positive | None = None
    depth_resolution_mm: Positive | None = None
    lateral_resolution_mm: Positive | None = None
    focal_length_mm: Positive | None = None
    standoff_mm: Positive | None = None
    stripe_noise: dict[str, Any] = Field(default_factory=dict)


#: Physical ranges of the robot's and the tool's fields: a torch or a sensor bracket reaches
#: well under a metre (TOOL_MM, the torch on the flange and the sensor on the torch); a robot
#: cell is tens of metres (CELL_MM, the base in the world); the start point is an approach of
#: centimetres (START_MM); angles are within a turn; the fastest arms move their tool at a few
#: m/s, turn their wrists at several hundred deg/s and accelerate at a few g. Far beyond these
#: a value is a typo (1e300 mm would also overflow the frames).
TOOL_MM, CELL_MM, START_MM = 2_000.0, 100_000.0, 1_000.0
ToolLength = Annotated[float, Field(ge=-TOOL_MM, le=TOOL_MM, allow_inf_nan=False, strict=True)]
CellLength = Annotated[float, Field(ge=-CELL_MM, le=CELL_MM, allow_inf_nan=False, strict=True)]
StartLength = Annotated[float, Field(ge=-START_MM, le=START_MM, allow_inf_nan=False, strict=True)]
Turn = Annotated[float, Field(ge=-360, le=360, allow_inf_nan=False, strict=True)]
Speed = Annotated[float, Field(gt=0, le=10_000, allow_inf_nan=False, strict=True)]  # mm/s
Accel = Annotated[float, Field(gt=0, le=100_000, allow_inf_nan=False, strict=True)]  # mm/s^2
TurnRate = Annotated[float, Field(gt=0, le=3_600, allow_inf_nan=False, strict=True)]  # deg/s
TurnAccel = Annotated[float, Field(gt=0, le=100_000, allow_inf_nan=False, strict=True)]  # deg/s^2
Gain = Annotated[float, Field(gt=0, allow_inf_nan=False, strict=True)]


class ToolConfig(_Section):
    """The torch on the flange (``T_flange_tcp``) and, optionally, the sensor on the torch
    (``T_tcp_sensor``; default: from ``sensor.look_ahead_mm``, ``range_mm`` and
    ``mount_rotation_deg``). The tcp frame: z along the torch away from the work, x the
    direction the sensor looks ahead in."""

    tcp_xyz_mm: tuple[ToolLength, ToolLength, ToolLength] = (0.0, 0.0, 300.0)
    tcp_rpy_deg: tuple[Turn, Turn, Turn] = (180.0, 0.0, 0.0)
    sensor_xyz_mm: tuple[ToolLength, ToolLength, ToolLength] | None = None
    sensor_rpy_deg: tuple[Turn, Turn, Turn] | None = None


class RobotConfig(_Section):
    model: str = "cartesian"
    urdf: str | None = None
    control_period_s: Positive = 1e-3
    # A list: one per axis or joint (its length is checked against the robot's).
    servo_gain_1_s: Positive | Annotated[list[Gain], Field(min_length=1)] | None = None
    interpolation_period_s: Positive | None = None
    tcp_velocity_max_mm_s: tuple[Speed, Speed, Speed] = (250.0, 250.0, 250.0)
    tcp_acceleration_max_mm_s2: tuple[Accel, Accel, Accel] = (200.0, 200.0, 200.0)
    angular_velocity_max_deg_s: TurnRate = 60.0
    angular_acceleration_max_deg_s2: TurnAccel = 20.0
    joint_acceleration_max_deg_s2: (
        TurnAccel | Annotated[list[TurnAccel], Field(min_length=1)] | None
    ) = None
    min_wrist_angle_deg: Annotated[float, Field(ge=0, lt=90, strict=True)] = 5.0
    tool: ToolConfig = Field(default_factory=ToolConfig)
    position_min_mm: Vec3 = (0.0, 0.0, 0.0)
    position_max_mm: Vec3 = (800.0, 150.0, 150.0)
    velocity_max_mm_s: PositiveVec3 = (20.0, 10.0, 10.0)
    acceleration_max_mm_s2: PositiveVec3 = (30.0, 15.0, 15.0)
    base_origin_mm: tuple[CellLength, CellLength, CellLength] = (-100.0, -75.0, -75.0)
    base_rotation_deg: tuple[Turn, Turn, Turn] = (0.0, 0.0, 0.0)
    start_offset_mm: tuple[StartLength, StartLength, StartLength] = (0.0, 0.0, 0.0)


Angle = Annotated[float, Field(gt=-80, lt=80, allow_inf_nan=False, strict=True)]


class TorchConfig(_Section):
    """Torch angles relative to the seam frame (the trajectory tracker keeps them on a robot
    that turns its tool; the score measures them on every robot)."""

    work_angle_deg: Angle = 0.0
    travel_angle_deg: Angle = 0.0


class TrackerConfig(_Section):
    name: str = "convergence-radius"
    radius_mm: Positive | None = None
    tolerance_mm: Positive | None = None
    params: dict[str, Any] = Field(default_factory=dict)


class ExtractorConfig(_Section):
    name: str | None = None
    offset_mm: tuple[Finite, Finite] = (0.0, 0.0)
    params: dict[str, Any] = Field(default_factory=dict)
    #: Expected joint geometry (``angle_deg``, ``depth_mm``, ``gap_mm`` and their ``_tol``):
    #: a family extractor refuses answers that break it (:mod:`seamtrack.features.expect`).
    expect: dict[str, Any] = Field(default_factory=dict)


class Box(_Section):
    """An axis-aligned box in the world frame (a clamp, a fixture) that the laser can hit."""

    min_mm: Vec3
    max_mm: Vec3


class WorkpieceConfig(_Section):
    script: str | None = None
    step: str | None = None
    seam: str | None = None
    seam_near_mm: list[Vec3] | None = None
    groove: dict[str, Any] | None = None
    tolerance_mm: Positive = 0.01
    angular_tolerance_deg: Positive = 5.0
    params: dict[str, Any] = Field(default_factory=dict)
    offset_mm: Vec3 = (0.0, 0.0, 0.0)
    rotation_deg: Vec3 = (0.0, 0.0, 0.0)
    obstacles: list[Box] = Field(default_factory=list)
    material: str | None = None  # a name of seamtrack.sensing.materials.MATERIALS (image mode)


class SceneConfig(_Section):
    name: str = ""
    description: str = ""
    simulation: SimulationConfig = Field(default_factory=SimulationConfig)
    seam: SeamConfig = Field(default_factory=SeamConfig)
    sensor: SensorConfig = Field(default_factory=SensorConfig)
    robot: RobotConfig = Field(default_factory=RobotConfig)
    torch: TorchConfig = Field(default_factory=TorchConfig)
    tracker: TrackerConfig = Field(default_factory=TrackerConfig)
    extractor: ExtractorConfig = Field(default_factory=ExtractorConfig)
    workpiece: WorkpieceConfig | None = None


# --------------------------------------------------------------------------- loading
def builtin_scenes() -> dict[str, str]:
    """Built-in scene names and their one-line descriptions."""
    out = {}
    for entry in sorted(resources.files("seamtrack.scenes").iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            data = tomllib.loads(entry.read_text())
            out[entry.name[:-5]] = str(data.get("description", ""))
    return out


def scene_text(name_or_path: str | Path) -> tuple[str, Path | None]:
    """The TOML text of a built-in scene or a file, and the file's folder (None: built-in)."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise SceneError(
                f"scene file {str(path)!r} does not exist",
                field="SCENE",
                fix="give a .toml path, or a built-in name (seamtrack init --list)",
            )
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            raise SceneError(
                f"{str(path)!r} is not a text file",
                field="SCENE",
                fix="give a TOML scene file (seamtrack init -o my.toml writes one)",
            ) from None
        except OSError as exc:
            raise SceneError(
                f"cannot read {str(path)!r}: {exc.strerror or exc}",
                field="SCENE",
                fix="check the path and its permissions",
            ) from None
        if _is_toml(text) and not tomllib.loads(text):
            raise SceneError(
                f"{str(path)!r} is empty: no section, no key",
                field="SCENE",
                fix="start from a complete scene: seamtrack init paper-verification -o my.toml",
            )
        return text, path.resolve().parent
    name = str(name_or_path)
    available = builtin_scenes()
    if name not in available:
        close = difflib.get_close_matches(name, list(available), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise SceneError(
            f"no built-in scene {name!r}",
            field="SCENE",
            fix=f"{hint}built-in scenes: {', '.join(available)}",
        )
    return resources.files("seamtrack.scenes").joinpath(f"{name}.toml").read_text(), None


def _is_toml(text: str) -> bool:
    try:
        tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return False  # load_scene reports the syntax error with its line
    return True


def parse_override(text: str) -> tuple[str, Any]:
    """``"tracker.radius_mm=0.5"`` -> ``("tracker.radius_mm", 0.5)``; the value is read as
    TOML (numbers, booleans, arrays, quoted strings), else taken as a bare string."""
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SceneError(
            f"override {text!r} is not KEY=VALUE",
            field="--set",
            fix="write e.g. --set tracker.radius_mm=0.5",
        )
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key, value


def _apply_overrides(data: dict[str, Any], overrides: dict[str, Any]) -> None:
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node = data
        for part in parts[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise SceneError(
                    f"{part!r} is a value, not a table",
                    field=dotted,
                    fix="override the whole value instead",
                )
            node = child
        node[parts[-1]] = value


def _fix_for(error: Any, model: type[BaseModel]) -> str:
    kind = error["type"]
    loc = [str(x) for x in error["loc"]]
    if kind == "extra_forbidden":
        fields = _fields_at(model, loc[:-1])
        close = difflib.get_close_matches(loc[-1], fields, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        return f"{hint}remove it; keys here: {', '.join(fields)}"
    if kind in {"greater_than", "greater_than_equal"} and not any(error.get("ctx", {}).values()):
        return "give a positive number in the unit of the key's suffix"
    if kind in {"greater_than", "greater_than_equal", "less_than", "less_than_equal"}:
        return "give a value within the range the message states"
    if kind == "literal_error":
        return "use one of the values listed"
    if kind in {"float_parsing", "float_type", "int_parsing", "int_type", "finite_number"}:
        return "give a finite number"
    if kind in {"tuple_type", "too_short", "too_long", "list_type"}:
        return "give a list like [x, y, z]"
    if kind == "missing":
        return "add it"
    if kind in {"bool_parsing", "bool_type"}:
        return "give true or false"
    if kind in {"string_type"}:
        return 'give a quoted string, e.g. "paper"'
    return "see the template: seamtrack init"


def _fields_at(model: type[BaseModel], loc: list[str]) -> list[str]:
    current: Any = model
    for part in loc:
        info = getattr(current, "model_fields", {}).get(part)
        if info is None:
            return []
        annotation = info.annotation
        args = [a for a in getattr(annotation, "__args__", ()) if isinstance(a, type)]
        current = next(
            (a for a in [annotation, *args] if isinstance(a, type) and issubclass(a, BaseModel)),
            None,
        )
        if current is None:
            return []
    return list(getattr(current, "model_fields", {}))


def validate(data: dict[str, Any], source: str = "scene") -> SceneConfig:
    """Validate a scene dict; a :class:`SceneError` lists every bad field, one per line."""
    try:
        return SceneConfig.model_validate(data)
    except ValidationError as exc:
        lines, fields, fixes = [], [], []
        for err in union_errors(exc.errors()):
            loc = ".".join(str(x) for x in err["loc"])
            got = err.get("input")
            skip_got = err["type"] in {"missing"} or isinstance(got, dict)
            got_text = "" if skip_got else f" (got {got!r})"
            fix = _fix_for(err, SceneConfig)
            lines.append(f"{loc}: {err['msg']}{got_text}; fix: {fix}")
            fields.append(loc)
            fixes.append(fix)
        raise SceneErrorList(lines, source, fields, fixes) from None


class SceneErrorList(SceneError):
    """Several bad fields at once; ``str()`` gives one line per field."""

    def __init__(self, lines: list[str], source: str, fields: list[str], fixes: list[str]):
        super().__init__(lines[0], field=fields[0], fix=fixes[0])
        self.lines = [f"{source}: {line}" for line in lines]
        self.fields = fields

    def __str__(self) -> str:
        return "\n".join(self.lines)


@dataclass(frozen=True)
class Scene:
    """A validated scene: the config, where it came from, and how to build its parts."""

    config: SceneConfig
    name: str
    base_dir: Path | None = None

    def resolve_path(self, text: str) -> Path:
        """A file named in the scene, relative to the scene file's folder."""
        path = Path(text).expanduser()
        if not path.is_absolute() and self.base_dir is not None:
            path = self.base_dir / path
        return path

    def to_toml(self) -> str:
        import tomli_w

        data = self.config.model_dump(mode="json", exclude_none=True)
        return tomli_w.dumps(data)


def load_scene(
    name_or_path: str | Path = "paper-verification",
    overrides: dict[str, Any] | list[str] | None = None,
) -> Scene:
    """Read, override and validate a scene.

    Parameters
    ----------
    name_or_path : str or Path
        A built-in scene name or a TOML file.
    overrides : dict or list of "KEY=VALUE" strings
        Dotted keys, e.g. ``{"tracker.radius_mm": 1.0}``.
    """
    text, base_dir = scene_text(name_or_path)
    source = str(name_or_path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(
            f"not valid TOML: {exc}",
            field=source,
            fix="check quotes, brackets and '=' on that line",
        ) from None
    if isinstance(overrides, list):
        overrides = dict(parse_override(o) for o in overrides)
    _apply_overrides(data, dict(overrides or {}))
    config = validate(data, source)
    scene = Scene(
        config=config, name=config.name or Path(str(name_or_path)).stem, base_dir=base_dir
    )
    check_consistency(scene)
    return scene


def check_consistency(scene: Scene) -> None:
    """Cross-field checks that the schema alone cannot express."""
    c = scene.config
    if c.seam.source == "points" and not c.seam.points_mm:
        raise SceneError(
            "source is 'points' but seam.points_mm is empty",
            field="seam.points_mm",
            fix="give [[x, y, z], ...] with at least 2 points",
        )
    if c.seam.source == "csv" and not c.seam.file:
        raise SceneError(
            "source is 'csv' but no file is given",
            field="seam.file",
            fix='add file = "my_seam.csv"',
        )
    if c.sensor.mode == "mesh" or c.seam.source == "workpiece":
        w = c.workpiece
        if w is None or (w.script is None and w.step is None and w.groove is None):
            raise SceneError(
                "mesh mode needs a workpiece",
                field="workpiece.script",
                fix='add [workpiece] with script = "v_groove" (or step = "part.step", or a groove)',
            )
        given = [k for k in ("script", "step", "groove") if getattr(w, k) is not None]
        if len(given) > 1:
            raise SceneError(
                f"give one of script, step and groove, not {' and '.join(given)}",
                field=f"workpiece.{given[-1]}",
                fix="remove all but one of them",
            )
        if w.seam is not None and w.seam_near_mm is not None:
            raise SceneError(
                "give either seam or seam_near_mm, not both",
                field="workpiece.seam_near_mm",
                fix="remove one of them",
            )
        if w.groove is not None:
            from seamtrack.workpiece.grooves import groove_spec

            groove_spec(w.groove)  # a groove weldx does not define, or lacks parameters
    for i, box in enumerate(c.workpiece.obstacles if c.workpiece else []):
        if not all(a < b for a, b in zip(box.min_mm, box.max_mm, strict=True)):
            raise SceneError(
                f"min_mm {list(box.min_mm)} must lie below max_mm {list(box.max_mm)}",
                field=f"workpiece.obstacles.{i}.max_mm",
                fix="give opposite corners of the box, smaller one first",
            )
    period = 1.0 / c.sensor.frame_rate_hz
    if c.robot.control_period_s > period:
        raise SceneError(
            f"control period {c.robot.control_period_s} s is longer than the sensor frame "
            f"period {period} s",
            field="robot.control_period_s",
            fix="use a control period at most the frame period (e.g. 0.001)",
        )
    # No path is faster than all three axes at their limits together.
    arm = is_arm(c)
    limits = c.robot.tcp_velocity_max_mm_s if arm else c.robot.velocity_max_mm_s
    speed_limit = math.hypot(*limits)
    if c.simulation.welding_speed_mm_s > speed_limit:
        raise SceneError(
            f"welding speed {c.simulation.welding_speed_mm_s} mm/s exceeds what the axes can "
            f"reach (velocity limits {list(limits)} mm/s)",
            field="simulation.welding_speed_mm_s",
            fix=f"use at most {speed_limit:.4g} mm/s (and at most the axis limit along a seam "
            "that follows one axis)",
        )
    sensor = make_sensor(c.sensor)  # impossible sensor geometry is an error here, before any run
    check_robot(c)
    if c.sensor.source == "image" and c.sensor.mode != "mesh":
        raise SceneError(
            "image mode renders the camera image of the part's mesh",
            field="sensor.source",
            fix='set sensor.mode = "mesh" (with a [workpiece]), or sensor.source = "geometry"',
        )
    if c.sensor.camera is not None or c.sensor.source == "image":
        make_camera(c.sensor.camera, c.sensor.preset).check(sensor)
    if c.workpiece is not None and c.workpiece.material is not None:
        material(c.workpiece.material)
    check_plugin_params(c)
    check_sizes(c)


_SPEC_KEYS = (
    "depth_of_field_mm",
    "fov_near_mm",
    "fov_far_mm",
    "angle_deg",
    "depth_resolution_mm",
    "lateral_resolution_mm",
    "focal_length_mm",
    "standoff_mm",
)


def make_camera(cfg: CameraConfig | None, sensor_preset: str = "paper") -> Camera:
    """The camera of ``[sensor.camera]`` (all defaults when the table is absent); the laser's
    wavelength defaults to the preset's data sheet, else 660 nm."""
    c = cfg if cfg is not None else CameraConfig()
    sheet = data_sheet(sensor_preset)
    wavelength = c.wavelength_nm or (sheet.wavelength_nm if sheet else None) or 660.0
    same = ("rows", "columns", "roi", "focal_length_mm", "f_number",
            "line_thickness_mm", "waist_range_mm", "exposure", "full_well_e", "read_noise_e",
            "ambient", "speckle", "shot_noise", "supersample")  # fmt: skip
    divergence = None if c.line_divergence_mrad is None else 1e-3 * c.line_divergence_mrad
    camera = Camera(**{k: getattr(c, k) for k in same}, bit_depth=c.bit_depth or None,
                    line_divergence_rad=divergence, wavelength_nm=wavelength)  # fmt: skip
    return camera.without_noise() if c.ideal else camera


def make_sensor(cfg: SensorConfig) -> LaserLineSensor:
    """The preset with the scene's data-sheet overrides and switches applied."""
    overrides: dict[str, Any] = {
        k: getattr(cfg, k) for k in _SPEC_KEYS if getattr(cfg, k) is not None
    }
    return preset(
        cfg.preset,
        quantize=cfg.quantize,
        max_incidence_rad=math.radians(cfg.max_incidence_deg),
        **overrides,
    )
