"""The scene's validated form: one frozen pydantic model per section of a scene file
(``[simulation]``, ``[seam]``, ``[sensor]`` ...), :class:`SceneConfig` holding them, and
:class:`Scene` (a config, its name and the folder it came from).

Types only, no loading and no checks: :mod:`seamtrack.simulation.scene` reads and validates
scene files into these, and the checks it runs (:mod:`~seamtrack.simulation.checks`,
:mod:`~seamtrack.simulation.robots`) take them, importing this module and not the loader.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

# Strict: a number is never a boolean or a string, a boolean never "yes" or 1.
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False, strict=True)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False, strict=True)]
Finite = Annotated[float, Field(allow_inf_nan=False, strict=True)]
Flag = Annotated[bool, Field(strict=True)]
NonNegativeInt = Annotated[int, Field(ge=0, strict=True)]
Vec3 = tuple[Finite, Finite, Finite]
PositiveVec3 = tuple[Positive, Positive, Positive]
#: An angle within a turn (deg): far beyond, a value is a typo (1e308 deg is accepted by
#: ``sin`` but means nothing).
Turn = Annotated[float, Field(ge=-360, le=360, allow_inf_nan=False, strict=True)]
TurnVec3 = tuple[Turn, Turn, Turn]
#: The welding travel speed (mm/s): the fastest processes (laser welding of thin sheet,
#: high-speed GMAW) travel at some 10-20 m/min, 167-333 mm/s; 1000 mm/s (60 m/min) bounds them
#: with room to spare, and a weld at 1e6 mm/s is a typo.
WeldSpeed = Annotated[float, Field(gt=0, le=1_000, allow_inf_nan=False, strict=True)]
#: A laser profiler's frame rate (Hz): the fastest sample at tens of kHz (Keyence LJ-X8000: up
#: to 16 kHz; LMI Gocator 2500: 10 kHz; Keyence LJ-V7000 at a cut window: 64 kHz).
FrameRate = Annotated[float, Field(gt=0, le=100_000, allow_inf_nan=False, strict=True)]


#: A bound of the peak detector's rejection, times the frame's stripe: above 1 (the stripe itself
#: passes), and 1000 is far beyond any stripe.
RejectFactor = Annotated[float, Field(gt=1, le=1000, allow_inf_nan=False, strict=True)]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SimulationConfig(_Section):
    welding_speed_mm_s: WeldSpeed = 5.0
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
    rotation_deg: TurnVec3 = (0.0, 0.0, 0.0)


class CameraConfig(_Section):
    """``[sensor.camera]``: the camera of image mode (:class:`seamtrack.sensing.camera.Camera`)
    and the peak detector that measures each image. The types are checked here, the physical
    ranges by the camera itself (:data:`seamtrack.sensing.camera.RANGES`, one definition)."""

    rows: Annotated[int, Field(strict=True)] | None = None
    columns: Annotated[int, Field(strict=True)] | None = None
    roi: tuple[NonNegativeInt, NonNegativeInt, NonNegativeInt, NonNegativeInt] | None = None
    focal_length_mm: Positive | None = None
    f_number: Positive = 8.0
    # Default: the preset's data sheet, else 660 nm.
    wavelength_nm: Positive | None = None
    line_thickness_mm: Positive = 0.2
    # The band-pass filter in front of the lens (issue 38): centre (default the laser's
    # wavelength), full width at half maximum (>= 0.1 nm; 10 nm: a common laser-line filter)
    # and shape. Only the arc's light (``[arc]``) is filtered; the laser passes at the centre.
    # Unset width and shape: the scene's ``countermeasures`` (seamtrack.simulation.
    # countermeasures.band_pass: 10 nm Gaussian under "default", no filter under "none").
    filter_centre_nm: (
        Annotated[float, Field(ge=200, le=2000, allow_inf_nan=False, strict=True)] | None
    ) = None
    filter_fwhm_nm: (
        Annotated[float, Field(ge=0.1, le=1000, allow_inf_nan=False, strict=True)] | None
    ) = None
    filter_shape: Literal["gaussian", "top-hat"] | None = None
    # The laser's power (W) against the arc's light (issue 38): the stripe keeps its level
    # (`exposure`), so the arc's light on the chip falls as 1 / power. Unset: 0.1 W
    # (seamtrack.sensing.arc.image.ArcLight). Line lasers of seam trackers are class 3R-3B, tens
    # to hundreds of mW; 10 W bounds them with room.
    laser_power_w: Annotated[float, Field(gt=0, le=10, allow_inf_nan=False, strict=True)] | None = (
        None
    )
    line_divergence_mrad: NonNegative | None = None
    waist_range_mm: Positive | None = None
    exposure: Positive = 0.5
    full_well_e: Positive = 10_000.0
    read_noise_e: NonNegative = 5.0
    bit_depth: Annotated[int, Field(strict=True)] = 10  # 0: no quantization
    ambient: NonNegative = 0.0
    speckle: Flag = True
    shot_noise: Flag = True
    supersample: Annotated[int, Field(strict=True)] | None = None
    ideal: Flag = False  # every noise source off (Camera.ideal)
    # Unset: the scene's ``countermeasures`` ("fixed" under "default", else "multi").
    exposure_mode: Literal["multi", "auto", "fixed"] | None = None
    target_peak: Finite = 0.7
    exposure_set: list[Finite] = [1.0, 0.125, 0.015625, 0.001953125]
    method: Literal["centroid", "gaussian", "steger"] = "centroid"
    # None: each column's own threshold, max(noise_sigmas * noise, relative * column peak).
    threshold: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False, strict=True)] | None = None
    relative: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False, strict=True)] = 0.5
    noise_sigmas: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False, strict=True)] = 6.0
    choose: Literal["strongest", "first", "widest"] = "strongest"
    # Blob and streak rejection (issue 38, seamtrack.sensing.peaks.Rejection): "blobs" drops
    # candidate runs not shaped like the stripe before choosing. Default (None): from the
    # scene's `countermeasures`. The bounds are times the frame's own stripe (its median
    # equivalent width and height); None: the Rejection defaults.
    reject: Literal["none", "blobs"] | None = None
    reject_max_width: RejectFactor | None = None
    reject_max_peak: RejectFactor | None = None
    reject_min_peak: (
        Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False, strict=True)] | None
    ) = None
    reject_stripe_width_px: (
        Annotated[float, Field(gt=0, le=1000, allow_inf_nan=False, strict=True)] | None
    ) = None


class SensorConfig(_Section):
    preset: str = "paper"
    mode: Literal["seam", "mesh"] = "seam"
    source: Literal["geometry", "image"] = "geometry"
    camera: CameraConfig | None = None
    frame_rate_hz: FrameRate = 1.0
    latency_s: NonNegative = 0.0
    look_ahead_mm: NonNegative = 10.0
    range_mm: Positive | None = None
    mount_rotation_deg: TurnVec3 | None = None
    quantize: Flag = True
    noise_range_mm: NonNegative = 0.0
    noise_lateral_mm: NonNegative = 0.0
    rays: Annotated[int, Field(ge=2, strict=True)] | None = None
    refine_float64: Flag = True
    # How the laser fan is cast in mesh mode (seamtrack.sensing.scan.FANS).
    fan: Literal["embree", "section", "auto"] = "auto"
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
    velocity_max_mm_s: tuple[Speed, Speed, Speed] = (20.0, 10.0, 10.0)
    acceleration_max_mm_s2: tuple[Accel, Accel, Accel] = (30.0, 15.0, 15.0)
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
    rotation_deg: TurnVec3 = (0.0, 0.0, 0.0)
    obstacles: list[Box] = Field(default_factory=list)
    material: str | None = None  # a name of seamtrack.sensing.materials.MATERIALS (image mode)


Fraction = Annotated[float, Field(gt=0, le=1, allow_inf_nan=False, strict=True)]


class BeadShapeConfig(_Section):
    """``[process.bead]``: the bead's cross-section model (:class:`seamtrack.workpiece.beads.
    BeadShape`): ``arc`` (circular segment), ``parabola`` or ``cosine`` (Ding et al. 2015), with
    its width-to-height ratio on a flat plate, or (``arc`` only) its wetting angle."""

    model: Literal["arc", "parabola", "cosine"] = "parabola"
    width_to_height: Annotated[float, Field(gt=1, le=20, allow_inf_nan=False, strict=True)] = 3.0
    wetting_angle_deg: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False, strict=True)] | (
        None
    ) = None


#: GMAW electrode wire: 0.5-3.2 mm across (0.020-1/8 in; the usual 0.8-1.6 mm), fed at
#: 100-800 in/min, 2.5-20 m/min (arctech.com.tr, "Solid Wire Electrodes for GMAW"); the window
#: is that with room either side (wire feeders reach about 1.3 m/min at their slowest). Outside
#: it mass conservation gives no bead a torch lays (1e-300 m/min: an infinite travel speed).
WireDiameter = Annotated[float, Field(ge=0.5, le=3.2, allow_inf_nan=False, strict=True)]
WireFeed = Annotated[float, Field(ge=1.0, le=30, allow_inf_nan=False, strict=True)]


class ProcessConfig(_Section):
    """``[process]``: the welding process (GMAW). The bead's area follows from mass
    conservation, ``deposition_efficiency * pi * (d/2)^2 * v_wire / v_travel``, at the torch's
    actual travel speed; heat input (kJ/mm) is ``thermal_efficiency * U * I / v_travel * 1e-3``.
    The travel speed window bounds what a planner may command."""

    wire_diameter_mm: WireDiameter = 1.2
    wire_feed_m_min: WireFeed = 8.0
    deposition_efficiency: Fraction = 0.97
    voltage_v: Annotated[float, Field(gt=0, le=100, allow_inf_nan=False, strict=True)] = 28.0
    current_a: Annotated[float, Field(gt=0, le=2000, allow_inf_nan=False, strict=True)] = 250.0
    thermal_efficiency: Fraction = 0.8  # MIG/MAG
    ctwd_mm: Annotated[float, Field(gt=0, le=100, allow_inf_nan=False, strict=True)] = 15.0
    travel_speed_min_mm_s: Positive = 2.0
    travel_speed_max_mm_s: Positive = 15.0
    bead: BeadShapeConfig = Field(default_factory=BeadShapeConfig)


class PassOverride(_Section):
    """One entry of ``[[passes.overrides]]``: values that replace the planner's for pass
    ``number`` (1-based, the scan-only pass not counted)."""

    number: Annotated[int, Field(ge=1, strict=True)]
    reference: Literal["left", "right", "centre", "left_top", "right_top"] | None = None
    offset_mm: Finite | None = None
    work_angle_deg: Angle | None = None
    travel_speed_mm_s: Positive | None = None
    wire_feed_m_min: WireFeed | None = None


class PassesConfig(_Section):
    """``[passes]``: a multi-pass job (``seamtrack run`` runs every pass as a closed loop on the
    part with the beads laid so far). ``count``: the number of passes, or ``"auto"`` (the
    planner decides); ``scan_first``: a scan-only pass (torch off) measures the empty groove
    before the first pass (else the first pass plans from the CAD groove's nominal area);
    ``reinforcement_mm``: the cap's target height over the plates' top; stations whose sidewall
    fusion margin (how far the wall bead's toe reaches into the wall, mm) is below
    ``fusion_margin_min_mm`` are flagged."""

    count: int | str = "auto"
    scan_first: Flag = True
    reinforcement_mm: Annotated[float, Field(ge=0, le=10, allow_inf_nan=False, strict=True)] = 2.0
    fusion_margin_min_mm: Finite = 0.0
    overrides: list[PassOverride] = Field(default_factory=list)

    @field_validator("count", mode="before")
    @classmethod
    def _count(cls, value: Any) -> Any:
        if value == "auto":
            return value
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 200:
            raise ValueError('give a number of passes from 1 to 200, or "auto"')
        return value


class PlannerConfig(_Section):
    """``[planner]``: the fill planner of a multi-pass job: ``adaptive`` (equal-area layers,
    speed scaled to the measured groove), ``fixed`` (the same beads at constant speed), or a
    user's ``package.module:Class``; ``params`` go to its constructor."""

    name: str = "adaptive"
    params: dict[str, Any] = Field(default_factory=dict)


class ArcConfig(_Section):
    """The welding arc in the sensor's view: its light, the plate it lights and heats, spatter
    and fume (issue 38, docs/arc.md). A scene without ``[arc]`` has no arc and runs as before.

    ``model`` names how the arc reaches the profile: ``"image"`` draws it into the camera's
    image (``sensor.source = "image"``), ``"profile"`` applies a statistical model of false
    points and drop-outs along the stripe, measured from the image model by ``seamtrack bench
    arc``; ``"auto"`` is the image model when the sensor forms images, else the profile model.
    """

    process: Literal["mag-short", "mag-spray", "tig"] = "mag-spray"
    #: The welding current (A); it sets the arc's radiance, the spatter and the fume.
    current_a: Annotated[float, Field(gt=0, le=1000, allow_inf_nan=False, strict=True)] = 250.0
    model: Literal["auto", "image", "profile"] = "auto"
    spatter: Flag = True
    fume: Flag = True
    glow: Flag = True


class GateConfig(_Section):
    """``[gate]``: the seam-point gate in time between the extractor and the tracker (issue
    38, :mod:`seamtrack.control.gate`). Unset keys come from the scene's ``countermeasures``:
    ``enabled`` is on with ``"default"`` (or when the table is given), ``on_invalid`` is
    ``"predict"`` with ``"default"`` and ``"hold"`` with ``"none"``."""

    enabled: Flag | None = None
    #: The search window's radius about the predicted seam point (mm); 0: no gate. Default
    #: 15 mm, the Riftek RF627Weld's search distance (manual rev. 1.1.1, 2020, p. 30).
    window_mm: NonNegative | None = None
    #: Invalid frames in a row after which the next point found is taken. Default 20, the
    #: RF627Weld's invalid sequence (same page).
    reacquire_frames: Annotated[int, Field(ge=1, le=100_000, strict=True)] | None = None
    on_invalid: Literal["hold", "predict"] | None = None


class TackConfig(_Section):
    """A tack weld across the joint (``[[distortion.tacks]]``), ``position_mm`` along the seam."""

    position_mm: Finite
    length_mm: Positive = 10.0
    throat_mm: Positive = 2.0


class ClampConfig(_Section):
    """A clamp across the joint (``[[distortion.clamps]]``): it holds whatever the force."""

    position_mm: Finite


class DistortionConfig(_Section):
    """``[distortion]``: the butt joint moving while it is welded (issue 39,
    :mod:`seamtrack.heat.motion`). The heat comes from ``[process]`` at the welding speed. The
    permanent angle's peak and where it peaks (``Q / h^2``, J/mm^3) are a fit to your process:
    no default. A scene without ``[distortion]`` runs as before."""

    material: Literal["carbon_steel", "stainless_steel", "aluminium"] = "carbon_steel"
    thickness_mm: Positive
    plate_width_mm: Positive
    angle_peak_deg: Annotated[float, Field(ge=0, le=45, allow_inf_nan=False, strict=True)]
    angle_peak_q_per_h2_j_mm3: Positive
    shrinkage_coefficient: Positive = 1.0  # Okerblom's A: 1 keeps the whole free expansion
    gap_rotation_deg: Annotated[float, Field(ge=-10, le=10, allow_inf_nan=False, strict=True)] = 0.0
    fixed_plate: Literal["left", "right", "none"] = "left"
    #: ~600 degC for mild steel: the "mechanical melting temperature" (Radaj, Heat Effects of
    #: Welding, Springer 1992).
    stiff_below_c: Positive = 600.0
    transient: Flag = True
    tacks: list[TackConfig] = Field(default_factory=list)
    clamps: list[ClampConfig] = Field(default_factory=list)


class SceneConfig(_Section):
    name: str = ""
    description: str = ""
    #: One switch for the countermeasures against the arc (issue 38): "default" turns on blob
    #: rejection in the peak detector, the seam-point gate and prediction on invalid frames;
    #: "none" turns them off. Explicit keys override it. Unset: "default" with an [arc], else
    #: "none" (a scene without the arc runs as before).
    countermeasures: Literal["none", "default"] | None = None
    simulation: SimulationConfig = Field(default_factory=SimulationConfig)
    seam: SeamConfig = Field(default_factory=SeamConfig)
    sensor: SensorConfig = Field(default_factory=SensorConfig)
    robot: RobotConfig = Field(default_factory=RobotConfig)
    torch: TorchConfig = Field(default_factory=TorchConfig)
    tracker: TrackerConfig = Field(default_factory=TrackerConfig)
    extractor: ExtractorConfig = Field(default_factory=ExtractorConfig)
    workpiece: WorkpieceConfig | None = None
    process: ProcessConfig | None = None
    passes: PassesConfig | None = None
    planner: PlannerConfig | None = None
    arc: ArcConfig | None = None
    gate: GateConfig | None = None
    distortion: DistortionConfig | None = None


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
