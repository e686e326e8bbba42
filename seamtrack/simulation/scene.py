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
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ValidationError

from seamtrack.errors import SceneError
from seamtrack.sensing.camera import Camera
from seamtrack.sensing.materials import material
from seamtrack.sensing.peaks import Rejection, detect
from seamtrack.sensing.sensor import LaserLineSensor, data_sheet, preset
from seamtrack.simulation.checks import (
    check_arc,
    check_plugin_params,
    check_sizes,
    union_errors,
)
from seamtrack.simulation.config import (  # the types live there; imported by name here too
    CameraConfig,
    Scene,
    SceneConfig,
    SensorConfig,
)
from seamtrack.simulation.countermeasures import exposure_mode
from seamtrack.simulation.process import check_passes
from seamtrack.simulation.robots import check_robot, is_arm
from seamtrack.simulation.templates import builtin_scenes


# --------------------------------------------------------------------------- loading
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
            # utf-8-sig: a byte-order mark (Windows Notepad writes one) is not TOML, so drop it.
            text = path.read_text(encoding="utf-8-sig")
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
        scene_camera(c).check(sensor)
    if c.workpiece is not None and c.workpiece.material is not None:
        material(c.workpiece.material)
    check_arc(c)
    check_passes(c)  # a job's sections, before the plugins they name are loaded
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


def make_camera(
    cfg: CameraConfig | None, sensor_preset: str = "paper", exposure_mode: str | None = None
) -> Camera:
    """The camera of ``[sensor.camera]`` (all defaults when the table is absent); the laser's
    wavelength defaults to the preset's data sheet, else 660 nm. ``exposure_mode``: the
    scene's resolved one (:func:`scene_camera`), else the table's, else ``"multi"``."""
    c = cfg if cfg is not None else CameraConfig()
    sheet = data_sheet(sensor_preset)
    wavelength = c.wavelength_nm or (sheet.wavelength_nm if sheet else None) or 660.0
    same = ("rows", "columns", "roi", "focal_length_mm", "f_number",
            "line_thickness_mm", "waist_range_mm", "exposure", "full_well_e", "read_noise_e",
            "ambient", "speckle", "shot_noise", "supersample", "target_peak")  # fmt: skip
    divergence = None if c.line_divergence_mrad is None else 1e-3 * c.line_divergence_mrad
    camera = Camera(**{k: getattr(c, k) for k in same}, bit_depth=c.bit_depth or None,
                    line_divergence_rad=divergence, wavelength_nm=wavelength,
                    exposure_set=tuple(c.exposure_set),
                    exposure_mode=exposure_mode or c.exposure_mode or "multi")  # fmt: skip
    return camera.without_noise() if c.ideal else camera


def scene_camera(config: SceneConfig) -> Camera:
    """The scene's camera, its exposure control resolved with the scene's
    ``countermeasures`` (:func:`seamtrack.simulation.countermeasures.exposure_mode`)."""
    mode = exposure_mode(config)
    return make_camera(config.sensor.camera, config.sensor.preset, mode)


def detect_rows(
    pixels: NDArray[np.floating], detector: CameraConfig, reject: Rejection | None
) -> NDArray[np.float64]:
    """The stripe row per column of an image (NaN: none) through the scene's detector: the
    ``[sensor.camera]`` settings ``detector`` and the countermeasures' ``reject``
    (:func:`seamtrack.simulation.countermeasures.rejection`)."""
    return detect(pixels, method=detector.method, threshold=detector.threshold,
                  choose=detector.choose, relative=detector.relative,
                  noise_sigmas=detector.noise_sigmas, reject=reject)  # fmt: skip


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
