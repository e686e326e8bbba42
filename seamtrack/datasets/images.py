"""Camera images of dataset samples (``seamtrack dataset --images``).

The image of a sample is rendered as image mode renders a frame
(:func:`seamtrack.sensing.render.render_image`: the laser sheet, reflectance, the first specular
bounce, diffraction, speckle, the chip), on the sample's joint, and measured by the spec's peak
detector (:meth:`~seamtrack.sensing.camera.StripeImage.profile`) as the sensor's firmware would.

Why a mesh per sample: the renderer casts the sheet, the shadow rays and the bounce rays on an
Embree scene. The drawn section, extruded along the seam
(:func:`~seamtrack.datasets.joints.extruded_mesh`), is 2 triangles a segment (12 for a V-groove,
60 with a tack), so its scene builds in a third of a millisecond, against 13-90 ms for a
1024 x 512 image (``seamtrack bench dataset`` measures both): a cache per drawn shape would save
nothing, as no two samples draw the same shape.
The mesh is the exact extrusion (flat faces, straight edges), so the rendered stripe and the
geometric profile see the same part.

Each sample's camera draws come from its own generator, a child of the sample's
(``SeedSequence(seed, spawn_key=(index, 0))``): the geometric part of a sample is the same
with or without images, and the image depends on the spec, the seed and the index only.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.datasets import joints
from seamtrack.datasets.spec import DatasetSpec

FloatArray = NDArray[np.float64]

#: Camera ranges drawn per sample, in draw order (after the two coins of :data:`COINS`).
CAMERA_RANGES = ("f_number", "wavelength_nm", "line_thickness_mm", "exposure", "full_well_e",
                 "read_noise_e", "ambient")  # fmt: skip
#: The noise sources switched per sample, each by a coin against its probability.
COINS = ("speckle", "shot_noise")
#: Stored per sample in ``camera_params``: the drawn ranges, then the coins (1.0 on, 0.0 off).
CAMERA_PARAM_NAMES = (*CAMERA_RANGES, *COINS)
#: The arc's ranges drawn per sample (after its coin and its process), in draw order.
ARC_RANGES = ("current_a", "look_ahead_mm", "filter_fwhm_nm")
#: Stored per sample in ``arc_params`` (a spec whose arc can be on): the coin (1.0 on, 0.0
#: off), the process's index in ``spec.arc.processes``, then the ranges (NaN when off).
ARC_PARAM_NAMES = ("arc", "process", *ARC_RANGES)


def image_generator(seed: int, index: int) -> np.random.Generator:
    """The generator of sample ``index``'s image: the first child of the sample's seed."""
    sequence = np.random.SeedSequence(seed, spawn_key=(index, 0))
    return np.random.Generator(np.random.PCG64(sequence))


def arc_generator(seed: int, index: int) -> np.random.Generator:
    """The generator of sample ``index``'s arc draws: the sample's second child, so a spec
    without the arc draws its cameras and images as before."""
    sequence = np.random.SeedSequence(seed, spawn_key=(index, 1))
    return np.random.Generator(np.random.PCG64(sequence))


def empty_images(spec: DatasetSpec, count: int) -> dict[str, np.ndarray]:
    """The image arrays of ``count`` samples (zero / NaN filled)."""
    rows, columns = spec.camera.rows, spec.camera.columns
    arc = {"arc_params": np.full((count, len(ARC_PARAM_NAMES)), np.nan)} if spec.arc.on else {}
    return arc | {
        "image": np.zeros((count, rows, columns), dtype=np.uint16),
        "image_truth_row": np.full((count, columns), np.nan),
        "image_truth_laser": np.full((count, columns, 2), np.nan),
        "image_reflection": np.zeros((count, columns), dtype=bool),
        "image_reflection_row": np.full((count, columns), np.nan),
        "image_points_laser": np.full((count, columns, 2), np.nan),
        "image_valid": np.zeros((count, columns), dtype=bool),
        "camera_params": np.full((count, len(CAMERA_PARAM_NAMES)), np.nan),
    }


def draw_camera(spec: DatasetSpec, rng: np.random.Generator) -> tuple[Any, FloatArray]:
    """The camera of one sample and its ``camera_params`` row (two coins, then the ranges)."""
    from seamtrack.sensing.camera import Camera

    c = spec.camera
    u = rng.random(len(COINS) + len(CAMERA_RANGES))
    # A coin is on with the probability drawn from its range: u < lo + u' (hi - lo) for two
    # uniforms is P = the range's mean, so one uniform against the mean is the same draw.
    chances = (sum(c.speckle_probability) / 2, sum(c.shot_noise_probability) / 2)
    coins = [bool(u[i] < p) for i, p in enumerate(chances)]
    values = [_draw(getattr(c, key), u[len(COINS) + i]) for i, key in enumerate(CAMERA_RANGES)]
    f_number, wavelength, thickness, exposure, full_well, read_noise, ambient = values
    camera = Camera(
        rows=c.rows, columns=c.columns, bit_depth=c.bit_depth, f_number=f_number,
        wavelength_nm=wavelength, line_thickness_mm=thickness, exposure=exposure,
        full_well_e=full_well, read_noise_e=read_noise, ambient=ambient, speckle=coins[0],
        shot_noise=coins[1],
    )  # fmt: skip
    return camera, np.array([*values, *(float(x) for x in coins)])


def draw_arc(spec: DatasetSpec, index: int, wavelength_nm: float) -> tuple[Any, FloatArray]:
    """Sample ``index``'s arc (:class:`~seamtrack.sensing.arc.image.ArcFrame` in the seam frame,
    or None: off) and its ``arc_params`` row, from :func:`arc_generator`. The arc stands on the
    seam (y = z = 0) ``look_ahead_mm`` behind the laser plane x = 0, the torch travelling
    along +x; the plate's outward normal is -z (the seam frame's z points into the part)."""
    from seamtrack.sensing.arc.image import ArcFrame, ArcLight
    from seamtrack.sensing.arc.light import BandPass

    a = spec.arc
    u = arc_generator(spec.seed, index).random(2 + len(ARC_RANGES))
    on = bool(u[0] < sum(a.probability) / 2)  # a coin at the range's mean (as the camera's)
    if not on:
        return None, np.array([0.0, *([np.nan] * (1 + len(ARC_RANGES)))])
    process = min(int(u[1] * len(a.processes)), len(a.processes) - 1)
    values = [_draw(getattr(a, key), u[2 + i]) for i, key in enumerate(ARC_RANGES)]
    current, look_ahead, fwhm = values
    band = BandPass(centre_nm=wavelength_nm, fwhm_nm=fwhm, shape="gaussian")
    light = ArcLight(a.processes[process], current, band, spatter=a.spatter, fume=a.fume,
                     glow=a.glow)  # fmt: skip
    frame = ArcFrame(light, np.array([-look_ahead, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]),
                     np.array([1.0, 0.0, 0.0]))  # fmt: skip
    return frame, np.array([1.0, float(process), *values])


def _draw(bounds: tuple[float, float], u: float) -> float:
    lo, hi = bounds
    return lo + u * (hi - lo)


def fill_image(
    spec: DatasetSpec,
    index: int,
    sensor: Any,
    material_name: str,
    segs: FloatArray,
    T_seam_sensor: FloatArray,
    out: dict[str, np.ndarray],
    row: int,
) -> None:
    """Render sample ``index``'s image of the section ``segs`` (k, 4) (seam frame) seen from
    ``T_seam_sensor`` and write it, its truth and its measured profile into row ``row``."""
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.render import render_image

    rng = image_generator(spec.seed, index)
    camera, params = draw_camera(spec, rng)
    arc = None
    if spec.arc.on:
        arc, out["arc_params"][row] = draw_arc(spec, index, camera.wavelength_nm)
    vertices, faces = joints.extruded_mesh(segs)
    caster = RayCaster(vertices, faces)
    # The part is in the seam frame, so the seam frame stands for the world here.
    image = render_image(sensor, caster, T_seam_sensor, camera=camera, material_name=material_name,
                         seed=rng, arc=arc)  # fmt: skip
    full_scale = np.float32(levels(spec.camera.bit_depth))
    out["image"][row] = np.rint(image.pixels * full_scale).astype(np.uint16)
    out["image_truth_row"][row] = image.truth_row
    out["image_truth_laser"][row] = image.truth_laser
    out["image_reflection"][row] = image.reflection
    out["image_reflection_row"][row] = image.reflection_row
    c = spec.camera
    profile = image.profile(c.method, threshold=c.threshold, choose=c.choose)
    out["image_points_laser"][row] = profile.points_laser
    out["image_valid"][row] = profile.valid
    out["camera_params"][row] = params


def levels(bit_depth: int) -> int:
    """Grey levels above 0 of a ``bit_depth`` image (full scale)."""
    return int(2**bit_depth - 1)
