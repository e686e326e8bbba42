"""Scene files: the paper's ASCII initialization file, as TOML.

``load_scene(name_or_path, overrides)`` reads a built-in scene (``seamtrack init --list``) or a
file, applies ``--set KEY=VALUE`` overrides, and validates everything at once: each bad field is
reported with its dotted path and a fix. :func:`seamtrack.simulation.assemble.build_parts`
builds only what a scene needs: a seam-mode scene never imports CadQuery, Embree or PyVista.
"""

from __future__ import annotations

import difflib
import itertools
import math
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from seamtrack import constants
from seamtrack.control.registry import tracker_class
from seamtrack.errors import SceneError
from seamtrack.features.extractors import extractor_target
from seamtrack.params import check_params
from seamtrack.sensing.scan import StripeNoise
from seamtrack.sensing.sensor import LaserLineSensor, preset

# Strict: a number is never a boolean or a string, a boolean never "yes" or 1.
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False, strict=True)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False, strict=True)]
Finite = Annotated[float, Field(allow_inf_nan=False, strict=True)]
Flag = Annotated[bool, Field(strict=True)]
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


class SensorConfig(_Section):
    preset: str = "paper"
    mode: Literal["seam", "mesh"] = "seam"
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


class RobotConfig(_Section):
    control_period_s: Positive = 1e-3
    position_min_mm: Vec3 = (0.0, 0.0, 0.0)
    position_max_mm: Vec3 = (800.0, 150.0, 150.0)
    velocity_max_mm_s: PositiveVec3 = (20.0, 10.0, 10.0)
    acceleration_max_mm_s2: PositiveVec3 = (30.0, 15.0, 15.0)
    base_origin_mm: Vec3 = (-100.0, -75.0, -75.0)
    base_rotation_deg: Vec3 = (0.0, 0.0, 0.0)
    start_offset_mm: Vec3 = (0.0, 0.0, 0.0)


class TrackerConfig(_Section):
    name: str = "convergence-radius"
    radius_mm: Positive | None = None
    tolerance_mm: Positive | None = None
    params: dict[str, Any] = Field(default_factory=dict)


class ExtractorConfig(_Section):
    name: str | None = None
    offset_mm: tuple[Finite, Finite] = (0.0, 0.0)
    params: dict[str, Any] = Field(default_factory=dict)


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


class SceneConfig(_Section):
    name: str = ""
    description: str = ""
    simulation: SimulationConfig = Field(default_factory=SimulationConfig)
    seam: SeamConfig = Field(default_factory=SeamConfig)
    sensor: SensorConfig = Field(default_factory=SensorConfig)
    robot: RobotConfig = Field(default_factory=RobotConfig)
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
    if kind in {"greater_than", "greater_than_equal"}:
        return "give a positive number in the unit of the key's suffix"
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
        for err in exc.errors():
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
    speed_limit = math.hypot(*c.robot.velocity_max_mm_s)
    if c.simulation.welding_speed_mm_s > speed_limit:
        raise SceneError(
            f"welding speed {c.simulation.welding_speed_mm_s} mm/s exceeds what the axes can "
            f"reach (velocity limits {list(c.robot.velocity_max_mm_s)} mm/s)",
            field="simulation.welding_speed_mm_s",
            fix=f"use at most {speed_limit:.4g} mm/s (and at most the axis limit along a seam "
            "that follows one axis)",
        )
    make_sensor(c.sensor)  # impossible sensor geometry is an error here, before any run
    check_plugin_params(c)
    check_sizes(c)


def default_time_limit_s(seam_length_mm: float, welding_speed_mm_s: float) -> float:
    """The run's time limit when the scene sets none: three times the nominal welding time,
    plus a minute."""
    return 3.0 * seam_length_mm / welding_speed_mm_s + 60.0


def check_ticks(c: SceneConfig, seam_length_mm: float | None) -> None:
    """Refuse a run of more than :data:`constants.MAX_TICKS` control ticks (the loop's logs
    grow with them); ``seam_length_mm`` None: not known before the seam is built."""
    limit = c.simulation.time_limit_s
    if limit is None and seam_length_mm is None:
        return
    if limit is None:
        assert seam_length_mm is not None
        limit = default_time_limit_s(seam_length_mm, c.simulation.welding_speed_mm_s)
    ticks = limit / c.robot.control_period_s
    if ticks > constants.MAX_TICKS:
        raise SceneError(
            f"a time limit of {limit:.4g} s at a control period of {c.robot.control_period_s:.3g} "
            f"s is {ticks:.3g} control ticks, more than the {constants.MAX_TICKS:.0e} a run holds "
            "in memory",
            field="robot.control_period_s",
            fix=f"use a control period of at least {limit / constants.MAX_TICKS:.3g} s, or "
            "set a shorter simulation.time_limit_s",
        )


def _polyline_length(points: list[list[float]]) -> float:
    return sum(math.dist(a, b) for a, b in itertools.pairwise(points))


def check_sizes(c: SceneConfig) -> None:
    """Every knob that sets an array size, against the bounds in :mod:`seamtrack.constants`."""
    s = c.seam
    if s.source == "paper" and s.length_mm / s.step_mm + 1 > constants.MAX_SEAM_POINTS:
        raise SceneError(
            f"a {s.length_mm:.4g} mm seam at a {s.step_mm:.3g} mm step has "
            f"{s.length_mm / s.step_mm + 1:.3g} points, more than {constants.MAX_SEAM_POINTS:.0e}",
            field="seam.step_mm",
            fix=f"use a step of at least {s.length_mm / (constants.MAX_SEAM_POINTS - 1):.3g} mm "
            "(or a shorter seam.length_mm)",
        )
    if s.points_mm is not None and len(s.points_mm) > constants.MAX_SEAM_POINTS:
        raise SceneError(
            f"{len(s.points_mm)} points, more than {constants.MAX_SEAM_POINTS:.0e}",
            field="seam.points_mm",
            fix="thin the points out, or give them as a CSV file",
        )
    if c.sensor.rays is not None and c.sensor.rays > constants.MAX_RAYS:
        raise SceneError(
            f"{c.sensor.rays} rays, more than the {constants.MAX_RAYS} a profile may have",
            field="sensor.rays",
            fix=f"use at most {constants.MAX_RAYS} (a real sensor has 1024-4096 points)",
        )
    if c.simulation.trace_period_s < c.robot.control_period_s:
        raise SceneError(
            f"trace period {c.simulation.trace_period_s:.3g} s is shorter than the control "
            f"period {c.robot.control_period_s:.3g} s: the trace would repeat ticks",
            field="simulation.trace_period_s",
            fix=f"use at least the control period ({c.robot.control_period_s:.3g} s)",
        )
    if c.workpiece is not None and c.workpiece.tolerance_mm < constants.MIN_MESH_TOLERANCE_MM:
        raise SceneError(
            f"meshing tolerance {c.workpiece.tolerance_mm:.3g} mm is finer than "
            f"{constants.MIN_MESH_TOLERANCE_MM:.0e} mm: a curved face would mesh into more "
            "triangles than fit in memory",
            field="workpiece.tolerance_mm",
            fix=f"use at least {constants.MIN_MESH_TOLERANCE_MM:.0e} mm (0.01 is the default)",
        )
    length = {"paper": s.length_mm, "points": _polyline_length(s.points_mm or [])}.get(s.source)
    check_ticks(c, length)


def check_plugin_params(c: SceneConfig) -> None:
    """The free-form sections against the signatures that take them (strict types, declared
    ranges), so that a bad value is refused before the run rather than deep inside it."""
    check_params(StripeNoise, c.sensor.stripe_noise, "sensor.stripe_noise")
    check_params(tracker_class(c.tracker.name), c.tracker.params, "tracker.params")
    if c.extractor.params and c.extractor.name is None:
        raise SceneError(
            "extractor.params given, but no extractor.name (the joint type picks one)",
            field="extractor.name",
            fix='name the extractor the parameters are for, e.g. extractor.name = "fillet"',
        )
    if c.extractor.name is not None and (c.sensor.mode == "mesh" or c.extractor.params):
        target = extractor_target(c.extractor.name)
        if isinstance(target, type):
            check_params(target, c.extractor.params, "extractor.params")


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
