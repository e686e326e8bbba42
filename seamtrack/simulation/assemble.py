"""Assemble a run's parts from a validated scene, building only what the scene asks for.

A seam-mode scene builds a seam, a sensor, a robot and a tracker; only a mesh-mode scene loads
a CAD workpiece (CadQuery, on a cache miss), an Embree scene and a feature extractor.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.gate import GateSettings
from seamtrack.control.registry import tracker, tracker_parameters
from seamtrack.control.tracking import Tracker
from seamtrack.errors import PluginRuntimeError, SceneError, plugin_failed
from seamtrack.geometry import frames
from seamtrack.geometry.seam import Seam
from seamtrack.sensing.profiles import Feature, Profile, SeamHint, laser_to_world
from seamtrack.sensing.scan import SeamNoise, sense_seam
from seamtrack.sensing.sensor import LaserLineSensor
from seamtrack.simulation.checks import (
    check_expect,
    check_seam_scale,
    check_ticks,
    default_time_limit_s,
)
from seamtrack.simulation.countermeasures import (
    band_pass,
    countermeasures,
    gate_settings,
    rejection,
)
from seamtrack.simulation.mount import Mount
from seamtrack.simulation.robots import (
    check_sensor_outside,
    is_arm,
    make_robot,
    plan_arm,
    sensor_mount,
    tool_program,
)
from seamtrack.simulation.scene import (
    CameraConfig,
    Scene,
    detect_rows,
    make_sensor,
    scene_camera,
)

FloatArray = NDArray[np.float64]
SenseFn = Callable[..., Feature]  # (T_world_sensor, t_s, hint=None)
ScanFn = Callable[..., "tuple[Profile, Feature]"]  # (T_world_sensor, t_s, hint=None)


@dataclass(frozen=True)
class LoopSettings:
    """Timing and termination of one run (all from the scene's ``[simulation]``/``[sensor]``)."""

    welding_speed_mm_s: float
    frame_period_s: float
    latency_s: float = 0.0
    end_tolerance_mm: float = 1.0
    stall_time_s: float = 5.0
    time_limit_s: float = 3600.0
    wall_time_limit_s: float = 600.0
    seed: int = 0
    trace_period_s: float = 0.01
    work_angle_rad: float = 0.0
    travel_angle_rad: float = 0.0
    # The seam-point gate between the extractor and the tracker (None: none), from the
    # scene's [gate] and countermeasures (seamtrack.simulation.countermeasures).
    gate: GateSettings | None = None


@dataclass(frozen=True)
class Parts:
    """Everything a run needs, assembled (by :mod:`seamtrack.simulation.scene`) from a scene."""

    seam: Seam
    robot: Any  # CartesianRobot or ArticulatedRobot
    tracker: Tracker
    sense: SenseFn
    tcp_start_world: FloatArray
    settings: LoopSettings
    sensor_resolution_mm: float
    look_ahead_mm: float
    scan: ScanFn | None = None  # mesh mode: the stripe profile and the feature found in it
    sensor: LaserLineSensor | None = None
    mesh: Any = None  # mesh mode: the ray-cast scene (workpiece and obstacles, world frame)
    caster: Any = None  # mesh mode: the RayCaster of ``mesh`` the scan casts on
    tracker_name: str = "tracker"  # as the scene names it, for errors raised in its code
    tool_program: Any = None  # the tool orientations along the nominal seam (ToolProgram)
    start_joints: FloatArray | None = None  # an arm's planned start configuration
    extractor_name: str = "v-groove"  # the scene's, or the one the seam's joint type calls for
    mount: Mount | None = None  # where the sensor sits on the torch, and why
    extract: Any = None  # mesh mode: the extractor instance the scan calls
    # Image mode: the camera image of the last frame scanned (a StripeImage), for observers
    # (seamtrack.bridge.frames); None in other modes.
    last_image: Callable[[], Any] | None = None
    # Whether ``sense`` passes a hint on to its extractor: the loop asks the tracker for one
    # only then (False: the seam model's sensing, an extractor that ignores hints).
    sense_uses_hint: bool = True
    # [distortion]: the seam moving while it is welded (MovingSeam), None when it does not
    moving: Any = None


def make_seam(scene: Scene) -> Seam:
    """The true seam in the world frame (for ``source = "workpiece"`` see :func:`build_parts`)."""
    c = scene.config.seam
    if c.source == "paper":
        seam = Seam.from_paper(c.step_mm, c.length_mm)
    elif c.source == "points":
        seam = Seam.from_points(c.points_mm or [], field="seam.points_mm", name=scene.name)
        check_seam_scale(seam, scene.config.sensor.look_ahead_mm, "seam.points_mm")
    elif c.source == "csv":
        assert c.file is not None
        seam = Seam.from_csv(scene.resolve_path(c.file), field="seam.file")
        check_seam_scale(seam, scene.config.sensor.look_ahead_mm, "seam.file")
    else:
        raise SceneError("make_seam does not build workpiece seams", field="seam.source")
    return seam.transformed(frames.from_xyz_rpy_deg(c.offset_mm, c.rotation_deg))


def make_tracker(scene: Scene) -> Tracker:
    """The scene's tracker. The shared keys ``radius_mm`` and ``tolerance_mm`` go to the trackers
    that take them (so ``--set tracker.name=...`` works on any scene); ``[tracker.params]`` go
    to the tracker as they are, and one it does not take is an error."""
    c = scene.config.tracker
    params = dict(c.params)
    accepted = tracker_parameters(c.name)
    for key in ("radius_mm", "tolerance_mm"):
        value = getattr(c, key)
        if value is not None and key in accepted:
            params.setdefault(key, value)
    return tracker(c.name, **params)


#: The extractor a joint type calls for when the scene names none (``extractor.name`` unset).
JOINT_EXTRACTORS = {
    "fillet": "fillet",
    "lap": "lap",
    "edge": "generic",
}


#: Their parameters in that case: a lap found in a weldment may be a plate of any thickness, so
#: the step between its sheets may exceed the lap extractor's default (3 mm, thin sheet); a
#: fillet's stripe crosses other bodies of the weldment too (a gusset narrowing towards its tip
#: leaves a fillet face of a few mm beside the gusset's far side and the web beyond it), so its
#: two faces explain less of the profile than on a lone T joint (64 % on the bracket's
#: web/gusset fillet 15 mm up), and the web, seen on both sides of the gusset, is one line.
JOINT_EXTRACTOR_PARAMS: dict[str, dict[str, Any]] = {
    "lap": {"max_gap_mm": 25.0},
    "fillet": {"min_explained": 0.5, "arms_from_pieces": True},
}


def joint_extractor(joint: str, opening_rad: float) -> str:
    """The built-in extractor for a joint type and its opening angle (v-groove when unknown)."""
    if joint in JOINT_EXTRACTORS:
        return JOINT_EXTRACTORS[joint]
    if joint == "butt" and abs(opening_rad - math.pi) < math.radians(10):
        return "square-butt"  # no groove: the gap between two plates
    if joint == "outside_corner" and opening_rad > math.pi:
        return "outside-corner"  # a ridge
    return "v-groove"  # a groove, an outside V, or nothing known


@dataclass(frozen=True)
class MeshScan:
    """A loaded workpiece in the world frame: its CAD seam, the per-frame scan, the ray-cast
    mesh and its caster, and the extractor the scan uses."""

    seam: Seam
    scan: ScanFn
    mesh: Any
    caster: Any
    extractor_name: str
    view: FloatArray | None = None  # where a sensor looks from, when not the torch direction
    extract: Any = None  # the extractor instance ``scan`` calls
    last_image: Callable[[], Any] | None = None  # image mode: the last frame's camera image
    hinted: bool = False  # ``scan`` passes the tracker's hint on to an extractor that uses it
    # The part and its obstacles without the extra mesh (a job's beads, an open surface of
    # up to ~0.6 million triangles): the sensor-inside test's solid.
    solid: Any = None
    # Image mode with an ``[arc]``: the sensor-to-torch transform, set once the robot is built
    # (the arc sits at the torch's tip, inv(T_tcp_sensor) from the sensor's pose).
    sensor_to_tcp: list[FloatArray | None] = dataclasses.field(default_factory=lambda: [None])


def uses_hint(find: Callable[..., Any]) -> bool:
    """Whether the scan passes the tracker's hint to an extractor: it takes one
    (:func:`takes_hint`) and does not say that its answer ignores it (``uses_hint`` False:
    the built-in families but the v-groove). The loop asks the tracker for a hint only then."""
    return takes_hint(find) and bool(getattr(find, "uses_hint", True))


def takes_hint(find: Callable[..., Any]) -> bool:
    """Whether an extractor takes the tracker's prior (a ``hint`` keyword, or ``**kwargs``):
    extractors written before the hint (``extractor(profile)``) are called without it."""
    try:
        params = inspect.signature(find).parameters
    except (TypeError, ValueError):  # a builtin without a signature: call it as it was
        return False
    return "hint" in params or any(p.kind is p.VAR_KEYWORD for p in params.values())


def _mesh_scan(
    scene: Scene, sensor: LaserLineSensor, rng: np.random.Generator, extra_mesh: Any = None,
    caster: Any = None,
) -> MeshScan:  # fmt: skip
    """The workpiece's CAD seam (world frame) and the per-frame scan: ray-cast stripe, then the
    scene's feature extractor (by default the one the seam's joint type calls for).
    ``extra_mesh`` (world frame, e.g. the beads of a multi-pass job) is ray-cast with the part;
    the seam is the part's. ``caster``: a caster of this very mesh to cast on (see
    :func:`build_parts`)."""
    from seamtrack.features.warm import start_warming, wait_warmed
    from seamtrack.sensing.raycast import RayCaster

    part, T_world_part = _load_part(scene)
    mesh, solid = _world_meshes(scene, part.mesh, T_world_part, extra_mesh)
    if caster is None:
        caster = RayCaster.from_mesh(mesh)
    elif not _casts(caster, mesh):
        raise ValueError("the caster given is not of the mesh this scene builds")
    seam = part.seam.transformed(T_world_part)
    extractor_name, find = _scene_extractor(scene, part.joint, part.opening_rad)
    warming = [start_warming(find, extractor_name, sensor, scene.config.sensor.rays)]
    hinted = uses_hint(find)  # once, at set-up: a user's extractor may have no ``hint``
    find_hinted: Any = find  # called with ``hint=`` only when it takes one
    offset = np.asarray(scene.config.extractor.offset_mm, dtype=float)
    shift = bool(offset.any())
    tcp: list[FloatArray | None] = [None]  # inv(T_tcp_sensor), once the robot is built
    measure, last_image = _stripe_measure(scene, sensor, caster, rng, tcp)
    measure_arc = with_profile_arc(scene, measure, rng, tcp)

    def scan(
        T_world_sensor: FloatArray, t_s: float, hint: SeamHint | None = None
    ) -> tuple[Profile, Feature]:
        profile = measure_arc(T_world_sensor, t_s)
        if warming[0] is not None:  # the first extraction: its kernels from the child's cache
            wait_warmed(warming[0])
            warming[0] = None
        try:
            if hinted and hint is not None:
                feature = find_hinted(profile, hint=hint)
            else:
                feature = find(profile)
        except Exception as exc:  # the user's extractor may fail in any way
            raise plugin_failed("extractor.name", extractor_name, "__call__", t_s, exc) from exc
        feature = _checked_feature(feature, profile, extractor_name, t_s)
        if feature and shift:
            # The torch target relative to the feature (a TCP calibration): e.g. the root of a
            # square butt joint, a plate thickness below the gap the stripe shows.
            point = feature.point_laser + offset
            feature = dataclasses.replace(
                feature, point_laser=point, point_world=laser_to_world(T_world_sensor, point)
            )
        return profile, feature

    view = None if part.view_normal is None else T_world_part[:3, :3] @ part.view_normal
    return MeshScan(seam, scan, mesh, caster, extractor_name, view, find, last_image, hinted,
                    solid, tcp)  # fmt: skip


def _casts(caster: Any, mesh: Any) -> bool:
    """Whether ``caster`` was built from ``mesh`` (the same triangles and vertices)."""
    faces = np.asarray(mesh.faces)
    if caster.faces.shape != faces.shape or not np.array_equal(caster.faces, faces):
        return False
    vertices = np.asarray(mesh.vertices, dtype=np.float64) - caster.local_origin
    return bool(np.array_equal(caster.vertices_local, vertices))


def _load_part(scene: Scene) -> tuple[Any, FloatArray]:
    """The scene's workpiece (its script or STEP file found beside the scene) and its pose in
    the world, ``T_world_part`` (4, 4)."""
    from seamtrack.workpiece.loader import load_workpiece

    w = scene.config.workpiece
    assert w is not None
    source = w.script if w.script is not None else w.step
    if source is not None:
        path = scene.resolve_path(source)
        source = str(path) if path.exists() else source
    part = load_workpiece(
        source,
        tolerance_mm=w.tolerance_mm,
        angular_tolerance_rad=math.radians(w.angular_tolerance_deg),
        seam=w.seam,
        seam_near_mm=w.seam_near_mm,
        groove=w.groove,
        **w.params,
    )
    return part, frames.from_xyz_rpy_deg(w.offset_mm, w.rotation_deg)


def _world_meshes(
    scene: Scene, part_mesh: Any, T_world_part: FloatArray, extra_mesh: Any
) -> tuple[Any, Any]:
    """(what the sensor ray-casts, what it must stay out of) in the world frame: the part with
    the scene's obstacle boxes, and that with ``extra_mesh`` (a job's beads) added."""
    w = scene.config.workpiece
    assert w is not None
    mesh = part_mesh.copy()
    mesh.apply_transform(T_world_part)
    if w.obstacles:
        import trimesh

        boxes = [trimesh.creation.box(bounds=[b.min_mm, b.max_mm]) for b in w.obstacles]
        mesh = trimesh.util.concatenate([mesh, *boxes])
    solid = mesh  # the part and its obstacles, closed solids: what the sensor must stay out of
    if extra_mesh is not None:
        import trimesh

        mesh = trimesh.util.concatenate([mesh, extra_mesh])
    return mesh, solid


def _scene_extractor(scene: Scene, joint: str, opening_rad: float) -> tuple[str, Any]:
    """(name, instance) of the scene's feature extractor: the one it names, or the one the
    part's joint calls for with that family's parameters; with the scene's ``expect``."""
    from seamtrack.features.extractors import extractor

    config = scene.config.extractor
    params = dict(config.params)
    extractor_name = config.name
    if extractor_name is None:
        extractor_name = joint_extractor(joint, opening_rad)
        params = dict(JOINT_EXTRACTOR_PARAMS.get(extractor_name, {}))
    if config.expect:
        if config.name is None:
            check_expect(extractor_name, config.expect)
        params["expect"] = dict(config.expect)
    return extractor_name, extractor(extractor_name, **params)


def _stripe_measure(
    scene: Scene,
    sensor: LaserLineSensor,
    caster: Any,
    rng: np.random.Generator,
    tcp: list[FloatArray | None],
) -> tuple[Callable[[FloatArray, float], Profile], Callable[[], Any] | None]:
    """The per-frame profile (``measure(T_world_sensor, t_s)``) and, in image mode, the last
    frame's image: the ray-cast stripe with the scene's noise, or every frame rendered by the
    camera and measured from its pixels."""
    from seamtrack.sensing.scan import scan_mesh

    s = scene.config.sensor
    noise = _stripe_noise(s.stripe_noise)
    if s.source == "image":
        return _image_measure(scene, sensor, caster, rng, tcp)

    def measure(T_world_sensor: FloatArray, t_s: float) -> Profile:
        return scan_mesh(sensor, caster, T_world_sensor, rays=s.rays, refine=s.refine_float64,
                         noise=noise, rng=rng, t_s=t_s, fan=s.fan)  # fmt: skip

    return measure, None


def _image_measure(
    scene: Scene,
    sensor: LaserLineSensor,
    caster: Any,
    rng: np.random.Generator,
    tcp: list[FloatArray | None],
) -> tuple[Callable[[FloatArray, float], Profile], Callable[[], Any]]:
    """Image mode's ``measure``: every frame rendered by the scene's camera (with the arc's
    light when the scene has one) and its profile measured from the pixels; and the last
    frame's image."""
    s = scene.config.sensor
    w = scene.config.workpiece
    assert w is not None
    camera, detector = scene_camera(scene.config), s.camera or CameraConfig()
    reject = rejection(scene.config)
    surface = w.material or "mill-scale steel"
    arc_light = scene_arc_light(scene, camera)

    # Auto-exposure's state lives in the run: each frame's exposure from the previous
    # frame's peak (deterministic: the images are drawn from the run's seeded Generator).
    exposure = [camera.exposure]
    images: list[Any] = [None]  # the last frame's image, for an observer

    def measure(T_world_sensor: FloatArray, t_s: float) -> Profile:
        images[0] = None  # let the last image go before the next is rendered (peak memory)
        arc = None if arc_light is None else arc_frame(arc_light, T_world_sensor, tcp)
        image = sensor.render(caster, T_world_sensor, camera=camera, seed=rng,
                              material=surface, t_s=t_s, exposure=exposure[0],
                              **({} if arc is None else {"arc": arc}))  # fmt: skip
        if camera.exposure_mode == "auto":
            exposure[0] = camera.next_exposure(image.exposure, image.peak)
        images[0] = image
        return image.profile_from_rows(detect_rows(image.pixels, detector, reject))

    return measure, lambda: images[0]


def _checked_feature(feature: Any, profile: Profile, extractor_name: str, t_s: float) -> Feature:
    """An extractor's answer, refused unless a :class:`Feature` with a finite point when found;
    a frame without a seam point counts the stripe's valid points when its extractor did not."""
    if not isinstance(feature, Feature):
        raise PluginRuntimeError(
            f"{extractor_name!r} returned {type(feature).__name__} at t = {t_s:.6g} s; "
            "expected a Feature",
            field="extractor.name",
            fix="return seamtrack.Feature(...) (falsy with a reason when nothing is found)",
        )
    found = bool(feature)
    point = feature.point_laser
    if found and not (len(point) == 2 and all(map(math.isfinite, point.tolist()))):
        raise PluginRuntimeError(
            f"{extractor_name!r} returned the seam point {feature.point_laser.tolist()} at "
            f"t = {t_s:.6g} s",
            field="extractor.name",
            fix="return a finite (y_L, z_L) point, or a falsy Feature with a reason",
        )
    if not found and feature.stripe_points < 0:
        # A frame without a seam point says whether the stripe was on the part at all: none
        # of it is where the laser line has left the part (or something hides it whole).
        assert profile.valid is not None
        stripe = int(np.count_nonzero(profile.valid))
        feature = dataclasses.replace(feature, stripe_points=stripe)
    return feature


def scene_arc_light(scene: Scene, camera: Any) -> Any:
    """The arc's settings for image mode (:class:`seamtrack.sensing.arc.image.ArcLight`), or
    None: no ``[arc]``, or its ``model`` is ``profile``. The band-pass from ``[sensor.camera]``'s
    filter keys, centred on the laser's wavelength by default."""
    a = scene.config.arc
    if a is None or a.model == "profile":
        return None
    from seamtrack.sensing.arc.image import ArcLight

    c = scene.config.sensor.camera
    band = band_pass(scene.config, camera.wavelength_nm)
    heat = None
    p, w = scene.config.process, scene.config.workpiece
    if p is not None:  # Rosenthal's field of the scene's heat input, at the welding speed
        from seamtrack.heat.materials import thermal_material
        from seamtrack.heat.rosenthal import process_power_w
        from seamtrack.sensing.arc.light import RosenthalHeat

        steel = thermal_material("stainless_steel" if w and w.material and "stainless" in
                                 w.material else "carbon_steel")  # fmt: skip
        speed = scene.config.simulation.welding_speed_mm_s
        heat = RosenthalHeat(process_power_w(p), speed, steel.conductivity_w_per_mm_k,
                             steel.diffusivity_mm2_per_s)  # fmt: skip
    light = ArcLight(a.process, a.current_a, band, spatter=a.spatter, fume=a.fume, glow=a.glow,
                     heat=heat)  # fmt: skip
    if c is not None and c.laser_power_w is not None:  # the laser against the arc's light
        light = dataclasses.replace(light, laser_power_w=c.laser_power_w)
    return light


def scene_arc_profile(scene: Scene) -> Any:
    """The profile-mode arc model of the scene
    (:class:`seamtrack.sensing.arc.profile_model.ArcProfileModel`), or None: no ``[arc]``, or
    its ``model`` is the image model (``"image"``, or ``"auto"`` when the sensor forms
    images)."""
    a = scene.config.arc
    if a is None or a.model == "image":
        return None
    if a.model == "auto" and scene.config.sensor.source == "image":
        return None
    from seamtrack.sensing.arc.profile_model import ArcProfileModel

    # the model measured under the scene's switch (its camera, filter, exposure, rejection)
    return ArcProfileModel(a.process, a.current_a, countermeasures=countermeasures(scene.config))


def with_profile_arc(
    scene: Scene,
    measure: Callable[[FloatArray, float], Profile],
    rng: np.random.Generator,
    tcp: list[FloatArray | None],
) -> Callable[[FloatArray, float], Profile]:
    """``measure`` with the profile-mode arc model applied to each profile it returns (drawn
    from the run's ``rng``); ``measure`` itself when the scene has none."""
    model = scene_arc_profile(scene)
    if model is None:
        return measure

    def measured(T_world_sensor: FloatArray, t_s: float) -> Profile:
        profile = measure(T_world_sensor, t_s)
        sensor_to_tcp = tcp[0]
        assert sensor_to_tcp is not None, "the robot sets the sensor-to-torch transform"
        assert profile.reason is not None
        points, reason = model.apply(profile.points_laser, profile.reason,
                                     sensor_to_tcp[:3, 3], rng)  # fmt: skip
        return Profile(points, valid=reason == 0, reason=reason,
                       T_world_sensor=profile.T_world_sensor, t_s=profile.t_s)  # fmt: skip

    return measured


def arc_frame(arc_light: Any, T_world_sensor: FloatArray, tcp: list[FloatArray | None]) -> Any:
    """The arc in this frame: at the torch's tip (the TCP, from the sensor's pose), the plate's
    normal taken along the torch's axis, on the side of the sensor."""
    from seamtrack.sensing.arc.image import ArcFrame

    sensor_to_tcp = tcp[0]
    assert sensor_to_tcp is not None, "the robot sets the sensor-to-torch transform"
    T_world_tcp = np.asarray(T_world_sensor) @ sensor_to_tcp
    tip, axis = T_world_tcp[:3, 3].copy(), T_world_tcp[:3, 2]
    up = axis if float(np.dot(np.asarray(T_world_sensor)[:3, 3] - tip, axis)) >= 0 else -axis
    ahead = np.asarray(T_world_sensor)[:3, 3] - tip  # the sensor looks ahead of the arc
    ahead = ahead - np.dot(ahead, up) * up
    norm = float(np.linalg.norm(ahead))
    return ArcFrame(arc_light, tip, up, ahead / norm if norm > 1e-9 else None)


def _stripe_noise(params: dict[str, Any]) -> Any:
    if not params:
        return None
    from seamtrack.sensing import scan

    try:
        return scan.StripeNoise(**params)
    except TypeError as exc:
        raise SceneError(
            str(exc),
            field="sensor.stripe_noise",
            fix="see the README's list of stripe noise parameters",
        ) from None


def build_parts(
    scene: Scene, rng: np.random.Generator | None = None, extra_mesh: Any = None,
    caster: Any = None,
) -> Parts:  # fmt: skip
    """Everything :func:`seamtrack.simulation.loop.run` needs, validated against each other.
    ``extra_mesh``: a mesh in the world frame ray-cast with the workpiece (a multi-pass job's
    beads, :mod:`seamtrack.multipass.job`); mesh mode only. ``caster``: the
    :class:`~seamtrack.sensing.raycast.RayCaster` of an earlier build of the same scene
    (``parts.caster``) to cast on instead of a new one (many runs of one scene side by side
    share one scene in memory: :class:`seamtrack.gym.vector.BatchedVectorEnv`); a caster of
    another mesh is a ``ValueError``."""
    c = scene.config
    rng = rng if rng is not None else np.random.default_rng(c.simulation.seed)
    sensor = make_sensor(c.sensor)
    scan: ScanFn | None = None
    mesh: Any = None
    loaded = None
    if c.sensor.mode == "mesh" or c.seam.source == "workpiece":
        loaded = _mesh_scan(scene, sensor, rng, extra_mesh, caster)
    if c.sensor.mode == "mesh":
        assert loaded is not None
        seam, scan, mesh = loaded.seam, loaded.scan, loaded.mesh
        if c.seam.source != "workpiece":
            seam = make_seam(scene)  # a nominal seam to score against (e.g. a robot program)
        mesh_scan = scan

        def sense(T_world_sensor: FloatArray, t_s: float, hint: SeamHint | None = None) -> Feature:
            return mesh_scan(T_world_sensor, t_s, hint)[1]
    else:
        seam = make_seam(scene) if loaded is None else loaded.seam
        noise = SeamNoise(c.sensor.noise_range_mm, c.sensor.noise_lateral_mm)
        sensed = seam

        def sense(T_world_sensor: FloatArray, t_s: float, hint: SeamHint | None = None) -> Feature:
            return sense_seam(sensed, T_world_sensor, sensor, noise=noise, rng=rng)

    moving = None
    if c.distortion is not None:  # the part moves while it is welded (issue 39)
        from seamtrack.simulation.distorted import moving_seam

        moving = moving_seam(c, seam)
        sense = moving.sense(sense)
    mount = sensor_mount(
        scene,
        sensor,
        None if loaded is None else loaded.seam,
        None if loaded is None else loaded.caster,
        None if loaded is None else loaded.view,
    )
    robot = make_robot(scene, sensor, mount)
    if loaded is not None:
        loaded.sensor_to_tcp[0] = np.linalg.inv(robot.T_tcp_sensor)
    start = seam.points[0] + np.asarray(c.robot.start_offset_mm)
    program = tool_program(scene, seam)
    start_joints = None
    if is_arm(c):
        start_joints = plan_arm(robot, program, start)
    else:
        robot.require_reachable(seam.points, "seam", field="seam")
        robot.require_reachable(start, "start", field="robot.start_offset_mm")
    poses = planned_tcp_poses(seam.length_mm, program, robot, is_arm(c))
    tool = c.robot.tool
    explicit = tool.sensor_xyz_mm is not None or tool.sensor_rpy_deg is not None
    solid = None if mesh is None or loaded is None else loaded.solid
    check_sensor_outside(
        poses, robot.T_tcp_sensor, sensor, seam, solid, explicit, bool(robot.turns_tool)
    )
    check_ticks(c, seam.length_mm)
    frame_period = 1.0 / c.sensor.frame_rate_hz
    v = c.simulation.welding_speed_mm_s
    settings = LoopSettings(
        welding_speed_mm_s=v,
        frame_period_s=frame_period,
        latency_s=c.sensor.latency_s,
        end_tolerance_mm=(
            c.simulation.end_tolerance_mm
            if c.simulation.end_tolerance_mm is not None
            else v * frame_period + 1.0
        ),
        stall_time_s=c.simulation.stall_time_s,
        time_limit_s=(
            c.simulation.time_limit_s
            if c.simulation.time_limit_s is not None
            else default_time_limit_s(seam.length_mm, v)
        ),
        wall_time_limit_s=c.simulation.wall_time_limit_s,
        seed=c.simulation.seed,
        trace_period_s=c.simulation.trace_period_s,
        work_angle_rad=math.radians(c.torch.work_angle_deg),
        travel_angle_rad=math.radians(c.torch.travel_angle_deg),
        gate=gate_settings(c),
    )
    return Parts(
        seam=seam,
        robot=robot,
        tracker=make_tracker(scene),
        tracker_name=c.tracker.name,
        sense=sense,
        tcp_start_world=start,
        settings=settings,
        sensor_resolution_mm=sensor.lateral_resolution_mm,
        look_ahead_mm=c.sensor.look_ahead_mm,
        scan=scan,
        sensor=sensor,
        mesh=mesh,
        caster=None if mesh is None or loaded is None else loaded.caster,
        tool_program=program,
        start_joints=start_joints,
        extractor_name=(
            loaded.extractor_name if loaded is not None else c.extractor.name or "v-groove"
        ),
        mount=mount,
        extract=None if loaded is None else loaded.extract,
        last_image=loaded.last_image if scan is not None and loaded is not None else None,
        sense_uses_hint=scan is not None and loaded is not None and loaded.hinted,
        moving=moving,
    )


def planned_tcp_poses(length_mm: float, program: Any, robot: Any, arm: bool) -> FloatArray:
    """(n, 4, 4) torch poses along the planned path, one every 5 mm of the nominal seam: an
    arm's turn with the tool program, a gantry's keep its base's orientation."""
    check_s = np.linspace(0.0, length_mm, max(2, int(length_mm // 5.0) + 1))
    if arm:
        rotations = program.rotations(check_s)
    else:
        rotations = np.broadcast_to(robot.T_world_base[:3, :3], (len(check_s), 3, 3))
    poses = np.tile(np.eye(4), (len(check_s), 1, 1))
    poses[:, :3, :3] = rotations
    poses[:, :3, 3] = program.frame(check_s)[0]
    return poses


def workpiece_seams(scene: Scene) -> list[Any]:
    """The seams found in the scene's weldment (a STEP file of several bodies or a weldment
    script), as :func:`seamtrack.workpiece.weldment.find_seams` gives them."""
    from seamtrack.workpiece.weldment import find_seams

    w = scene.config.workpiece
    source = None if w is None else (w.step or w.script)
    if w is None or source is None:
        raise SceneError(
            "the scene has no weldment whose seams could be listed",
            field="workpiece.step",
            fix='give workpiece.step = "part.step" (several solids) or a weldment script',
        )
    path = scene.resolve_path(source)
    field = "workpiece.step" if w.step else "workpiece.script"
    return find_seams(
        str(path) if path.exists() else source,
        tolerance_mm=w.tolerance_mm,
        field=field,
        **w.params,
    )
