"""The camera image of the laser stripe, rendered by light tracing on the part's Embree scene.

Light goes the way it goes in the sensor: from the emitter to the part, from the part into the
camera's pupil, onto the chip.

1. **The laser sheet.** A fan of rays in the plane x_L = 0 (1.25 per sub-pixel column) is cast
   with the mesh-mode kernels of :func:`seamtrack.sensing.scan.stripe_hits` (Embree packets,
   float64 refinement, shadow rays to the camera centre). Each ray carries the power of its
   angle of the fan. Across its plane the sheet is Gaussian, of standard deviation
   sigma(d) = W(d) / 4 at a distance d (:meth:`Camera.line_sigma_mm`); on the locally plane
   surface that thickness covers the line P + alpha t, t = e_x - (n.e_x)/(n.d) d, whose image is
   a short segment across the stripe: each ray lays a Gaussian of that width on the chip, over
   the stretch of stripe between it and its neighbours (following the stripe's slope).
2. **Reflection.** The lit point sends I = Phi (rho_d cos(theta_v) / pi + rho_s G(beta)) per
   steradian towards the camera (:mod:`seamtrack.sensing.materials`); the pupil (diameter
   lambda / N) collects I * A_pupil * cos(theta_axis) / r^2. This light tracing needs no area
   element: grazing incidence spreads the same power over a wider stripe.
3. **The first specular bounce.** Each lit point also reflects rho_s of its power into the
   mirror direction, traced to the first point it lights (Embree); if the camera sees that
   point, it gets a stripe of its own (the groove's false stripe), widened by the lobe.
4. **Image formation** on a grid of s x s sub-pixels: the Gaussians integrated exactly over
   sub-pixel rows, shared by length between sub-pixel columns; then either the diffraction blur
   (a Gaussian fit of the Airy disc, 0.42 lambda N: added to each Gaussian across the stripe,
   :func:`scipy.ndimage.gaussian_filter1d` along it) or, with speckle, the coherent
   field: amplitude sqrt(I) times a circular Gaussian random phasor per sub-pixel (the rough
   surface), filtered by the circular pupil (cut-off 1 / (2 lambda N) on the chip), squared; so
   the speckle grain and its statistics follow from lambda and N alone. Sub-pixels are summed
   into pixels (pixel integration). Only bands around the stripes are processed, block by block
   (overlap-save along the columns).
5. **The chip.** Ambient light, shot noise (Poisson), read noise, saturation at the full well,
   quantization to the bit depth; every draw from the one seeded Generator.
6. **Exposure** (:attr:`Camera.exposure_mode`): the signal is linear in the exposure, so a frame
   is rendered once and read out at its exposure (``fixed``; ``auto``: the exposure the run's
   loop passes in, :meth:`Camera.next_exposure`), or at each exposure of the set (``multi``:
   the same speckle, independent noise), merged column by column from the longest exposure
   that does not saturate the column.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack.sensing import formation
from seamtrack.sensing.arc.image import ArcFrame, ArcView, arc_electrons
from seamtrack.sensing.camera import BLOCK_COLUMNS, RANGES, Camera, StripeImage
from seamtrack.sensing.materials import DEFAULT_MATERIAL, Material, material
from seamtrack.sensing.profiles import Reason
from seamtrack.sensing.scan import laser_fan, ray_caster, stripe_hits

if TYPE_CHECKING:
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.sensor_geometry import SensorGeometry

FloatArray = NDArray[np.float64]

#: Fan rays per sub-pixel column (at least one per sub-pixel column everywhere in the field: the
#: fan spans the near end's angle, the widest).
RAYS_PER_SUBCOLUMN = 1.25
#: A false stripe counts (StripeImage.reflection) above this share of a white plane's column.
REFLECTION_LEVEL = 0.01
#: Stripe pieces adding less than this share of the full well to any pixel are not drawn.
MIN_SIGNAL = 1e-4
#: Smallest |cos| of incidence used for a footprint (grazing rays would spread to infinity).
MIN_COS_INCIDENCE = 1e-3


def render_image(
    sensor: SensorGeometry,
    part: Any,
    T_world_sensor: ArrayLike,
    *,
    camera: Camera | None = None,
    material_name: str | Material | None = None,
    seed: int | np.random.Generator | None = None,
    t_s: float = float("nan"),
    exposure: float | None = None,
    arc: ArcFrame | None = None,
) -> StripeImage:
    """The camera image of the stripe on a part at a pose (see the module docstring).

    Parameters
    ----------
    sensor : SensorGeometry
    part : trimesh.Trimesh, object with ``.mesh``, or RayCaster
        The part in the world frame (its Embree scene is cached, shared with ``scan``).
    T_world_sensor : (4, 4) float
    camera : Camera, optional
        Default ``Camera()``.
    material_name : str or Material, optional
        Default the part's ``material`` attribute, else "mill-scale steel".
    seed : int or numpy.random.Generator, optional
        Every random draw (speckle, shot and read noise) comes from it.
    t_s : float
        Capture time.
    exposure : float, optional
        This frame's exposure (auto-exposure's state, kept by the caller); default the
        camera's ``exposure``.
    arc : ArcFrame, optional
        The welding arc in this frame (:mod:`seamtrack.sensing.arc.image`): its light, the
        plate it lights and heats, fume and spatter are added to the stripe's electrons before
        the chip reads them out. None (default): no arc, and nothing is drawn for it.

    Returns
    -------
    StripeImage
    """
    cam = camera if camera is not None else Camera()
    if exposure is not None and exposure != cam.exposure:
        cam = dataclasses.replace(cam, exposure=exposure)  # checks its range
    mat = material(material_name or getattr(part, "material", None) or DEFAULT_MATERIAL)
    cam.check(sensor)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    T = np.asarray(T_world_sensor, dtype=np.float64)
    if T.shape != (4, 4):
        raise ValueError(f"T_world_sensor must be (4, 4), got {T.shape}")
    imaging = cam.imaging_sensor(sensor)
    window = cam.window(imaging)
    s = cam.supersampling(imaging)
    caster = ray_caster(part)
    rays = min(constants.MAX_RAYS, math.ceil(RAYS_PER_SUBCOLUMN * s * imaging.pixels_v))
    hits = stripe_hits(imaging, caster, T, rays, refine=True, quantize=False)
    optics = _Optics(imaging, cam, window, s, sensor.range_center_mm)
    fan = laser_fan(imaging, rays)
    tan_phi = fan.directions[:, 1] / fan.directions[:, 2]
    power = np.abs(np.gradient(np.arctan(tan_phi))) if rays > 1 else np.ones(1)
    direct = _direct_splats(optics, caster, hits, fan.directions, power, T, mat)
    bounce = _bounce_splats(optics, caster, hits, fan.directions, power, T, mat)
    grid = formation.Optics(
        rows=optics.rows, columns=optics.columns, supersample=s,
        cell_mm=(optics.pitch_h / s, optics.pitch_v / s), blur_sigma_mm=cam.blur_sigma_mm,
        speckle_size_mm=cam.speckle_size_mm, speckle=cam.speckle,
        speckle_contrast=mat.speckle_contrast, block_columns=BLOCK_COLUMNS,
    )  # fmt: skip
    u, w, half, slope, sigma, signal = (
        np.concatenate([a, b]) for a, b in zip(direct.arrays(), bounce.arrays(), strict=True)
    )
    # A piece whose light (with its neighbours') adds less than MIN_SIGNAL of the full well to
    # any pixel is a glow below a tenth of a grey level: left out (a rough surface's lobe
    # scatters its bounce over hundreds of pixels).
    peak = signal / (math.sqrt(2 * math.pi) * np.maximum(sigma, 0.5) * np.maximum(2 * half, 1.0))
    seen = peak >= MIN_SIGNAL * cam.full_well_e
    electrons = formation.form_image(u[seen], w[seen], half[seen], slope[seen], sigma[seen],
                                     signal[seen], grid, rng)  # fmt: skip
    if arc is not None:
        electrons += arc_electrons(  # in place: form_image's array is this frame's own
            arc.light, optics.arc_view(T, arc.light.laser_power_w), caster, mat, arc.arc_mm,
            arc.up, t_s if math.isfinite(t_s) else 0.0, rng, arc.travel,
        )  # fmt: skip
    spacing = hits.distance_mm[direct.ray] * power[direct.ray]
    truth = formation.stripe_rows(direct.u, direct.w, direct.ray, direct.points, spacing,
                                  optics.columns)  # fmt: skip
    bounce_total, reflection_row = formation.column_mean_rows(
        bounce.u, bounce.w, bounce.half_width, bounce.electrons, optics.columns
    )
    reflection = bounce_total > REFLECTION_LEVEL * optics.column_reference
    reflection_row = np.where(reflection, reflection_row, np.nan)
    # Shot noise by inverting the Poisson CDF below a mean of 30 electrons (exactly Poisson;
    # 1.7x faster than NumPy's generator on a speckle frame's 40,000 lit pixels, most of them
    # dim; with the arc, fume and glow light most of the chip with a few electrons a pixel)
    pixels, column_exposure = _read_out(electrons, cam, rng, dim_by_inversion=True)
    return StripeImage(
        pixels=pixels, camera=cam, sensor=imaging, material=mat, window=window,
        truth_row=truth, reflection=reflection, reflection_row=reflection_row,
        T_world_sensor=T, t_s=t_s, exposure=cam.exposure, column_exposure=column_exposure,
    )  # fmt: skip


def _read_out(
    electrons: FloatArray, cam: Camera, rng: np.random.Generator, dim_by_inversion: bool = False
) -> tuple[NDArray[np.float32], FloatArray | None]:
    """The chip's readout at the camera's exposure, or (``multi``) at each exposure of its set,
    merged: each column from the longest exposure whose pixels stay below full scale there, the
    shortest that shows the column where every one saturates; and the exposure of each column.
    An exposure of the set below the shutter's shortest (:data:`RANGES`) is taken at that."""
    factors: tuple[float, ...] = (1.0,)
    if cam.exposure_mode == "multi":  # the shutter's shortest exposure bounds the set
        shortest = RANGES["exposure"].lo / cam.exposure
        factors = tuple(
            sorted({max(f, min(1.0, shortest)) for f in cam.exposure_set}, reverse=True)
        )
    chosen: NDArray[np.float32] | None = None
    exposure = np.full(electrons.shape[1], cam.exposure)
    open_ = np.ones(electrons.shape[1], dtype=bool)  # columns still saturated in every exposure
    for i, factor in enumerate(factors):
        frame = formation.chip_readout(
            electrons * factor if factor != 1.0 else electrons, rng, full_well_e=cam.full_well_e,
            ambient=cam.ambient, shot_noise=cam.shot_noise, read_noise_e=cam.read_noise_e,
            bit_depth=cam.bit_depth, dim_by_inversion=dim_by_inversion,
        )  # fmt: skip
        if chosen is None:
            chosen = frame
        else:
            # A column keeps the longer exposure where this one shows nothing (a 1-bit chip).
            take = open_ & (frame.max(axis=0) > 0.0)
            chosen[:, take] = frame[:, take]
            exposure[take] = cam.exposure * factor
        if i + 1 < len(factors):
            open_ &= frame.max(axis=0) >= 1.0
            if not open_.any():
                break
    assert chosen is not None
    return chosen, (exposure if cam.exposure_mode == "multi" else None)


# --------------------------------------------------------------------------- geometry
class _Optics:
    """The imaging geometry in one place: projection, pupil, grid, exposure scale."""

    def __init__(
        self, imaging: SensorGeometry, cam: Camera, window: tuple[int, int, int, int], s: int,
        waist_default_mm: float,
    ) -> None:  # fmt: skip
        self.imaging, self.cam, self.window, self.s = imaging, cam, window, s
        self.b = imaging.baseline_mm
        self.lam = imaging.focal_length_mm
        self.sin, self.cos = math.sin(imaging.angle_rad), math.cos(imaging.angle_rad)
        self.pitch_h, self.pitch_v = imaging.pixel_pitch_mm
        self.camera_center = np.array([self.b, 0.0, 0.0])
        self.axis = np.array([-self.sin, 0.0, self.cos])
        pupil = self.lam / cam.f_number
        self.pupil_area = math.pi * 0.25 * pupil**2
        self.waist = cam.waist_range_mm or waist_default_mm
        self.rows = window[1] - window[0]
        self.columns = window[3] - window[2]
        self.electrons_per_power, self.column_reference = self._exposure_scale()

    def project(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(n, 3) laser-frame points (x_L may be off the plane) to chip (x_c, z_c)."""
        x, y, z = points[:, 0], points[:, 1], points[:, 2]
        depth = (self.b - x) * self.sin + z * self.cos
        return self.lam * ((self.b - x) * self.cos - z * self.sin) / depth, self.lam * y / depth

    def grid(self, x_c: FloatArray, z_c: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Chip mm to pixel coordinates of the window, edge-based (pixel i spans [i, i+1))."""
        u = (x_c + 0.5 * self.imaging.chip_h_mm) / self.pitch_h - self.window[0]
        w = (z_c + 0.5 * self.imaging.chip_v_mm) / self.pitch_v - self.window[2]
        return u, w

    def footprint_sigma_px(
        self, points: FloatArray, across: FloatArray, sigma_mm: FloatArray
    ) -> FloatArray:
        """Row-direction standard deviation (pixels) of the image of a Gaussian of
        ``sigma_mm`` laid along ``across`` (n, 3) at ``points`` (n, 3)."""
        h = 1e-4
        hi, _ = self.project(points + h * across)
        lo, _ = self.project(points - h * across)
        return np.asarray(sigma_mm * np.abs(hi - lo) / (2 * h) / self.pitch_h)

    def collected(self, points: FloatArray, normals: FloatArray, incoming: FloatArray,
                  mat: Material) -> FloatArray:  # fmt: skip
        """Share of a beam's power lit at ``points`` that enters the pupil: (rho_d cos / pi +
        rho_s G) * A_pupil * cos(theta_axis) / r^2, per point (arrays (n, 3), unit vectors)."""
        to_camera = self.camera_center - points
        r = np.linalg.norm(to_camera, axis=1)
        view = to_camera / r[:, None]
        cos_view = np.clip(np.einsum("ij,ij->i", normals, view), 0.0, 1.0)
        radiant = mat.diffuse_albedo * cos_view / math.pi
        if mat.specular_reflectance > 0:
            mirror = incoming - 2.0 * np.einsum("ij,ij->i", incoming, normals)[:, None] * normals
            beta = np.arccos(np.clip(np.einsum("ij,ij->i", mirror, view), -1.0, 1.0))
            lobe = mat.lobe_rad
            radiant = radiant + mat.specular_reflectance * np.exp(-0.5 * (beta / lobe) ** 2) / (
                2.0 * math.pi * lobe**2
            )
        cos_axis = np.clip(-view @ self.axis, 0.0, 1.0)
        return np.asarray(radiant * self.pupil_area * cos_axis / r**2)

    def arc_view(self, T: FloatArray, laser_power_w: float) -> ArcView:
        """The camera for the arc model (:class:`ArcView`), world frame at the pose ``T``:
        pixel rays (the inverse of :meth:`project`), the projection, and the electrons per
        watt: the laser's ``laser_power_w`` over its fan gives the exposure scale's power."""
        R, t = T[:3, :3], T[:3, 3]
        center = R @ self.camera_center + t
        z0 = self.imaging.range_center_mm
        fan = 2.0 * math.atan(float(self.imaging.half_width_mm(z0)) / z0)

        def rays(u: FloatArray, w: FloatArray) -> FloatArray:
            x_c = (u + self.window[0]) * self.pitch_h - 0.5 * self.imaging.chip_h_mm
            z_c = (w + self.window[2]) * self.pitch_v - 0.5 * self.imaging.chip_v_mm
            a = self.sin + x_c / self.lam * self.cos
            d = np.stack([-a, z_c / self.lam, self.cos - x_c / self.lam * self.sin], axis=1)
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            return np.asarray(d @ R.T)

        def project(points: FloatArray) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
            local = (points - t) @ R
            depth = (self.b - local[:, 0]) * self.sin + local[:, 2] * self.cos
            front = depth > 1e-6
            safe = np.where(front[:, None], local, [0.0, 0.0, self.imaging.range_center_mm])
            u, w = self.grid(*self.project(safe))
            return u, w, front

        return ArcView(
            center=center, rays=rays, project=project, rows=self.rows, columns=self.columns,
            pupil_area_mm2=self.pupil_area, pixel_sr=self.pitch_h * self.pitch_v / self.lam**2,
            electrons_per_w=self.electrons_per_power * fan / laser_power_w,
            full_well_e=self.cam.full_well_e,
        )  # fmt: skip

    def _exposure_scale(self) -> tuple[float, float]:
        """Electrons per unit fan power (radian) that make a white Lambertian plane across the
        laser at the range centre peak at ``exposure`` of the full well; and the electrons that
        plane puts into one column."""
        z0 = self.imaging.range_center_mm
        point = np.array([[0.0, 0.0, z0]])
        white = Material("white", diffuse_albedo=1.0)
        share = float(self.collected(point, np.array([[0.0, 0.0, -1.0]]),
                                     np.array([[0.0, 0.0, 1.0]]), white)[0])  # fmt: skip
        depth = self.b * self.sin + z0 * self.cos
        power = self.pitch_v * depth / self.lam / z0  # fan angle seen by one column
        sigma = self.footprint_sigma_px(point, np.array([[1.0, 0.0, 0.0]]),
                                        self.cam.line_sigma_mm([z0], self.waist))[0]  # fmt: skip
        total = math.hypot(float(sigma), self.cam.blur_sigma_mm / self.pitch_h)
        peak_share = math.erf(0.5 / (math.sqrt(2.0) * total))
        column = power * share
        scale = self.cam.exposure * self.cam.full_well_e / (column * peak_share)
        return scale, scale * column


class _Splats:
    """Gaussian stripe pieces on the chip, in window pixel coordinates (edge-based)."""

    def __init__(self, u: FloatArray, w: FloatArray, sigma: FloatArray, electrons: FloatArray,
                 points: FloatArray, ray: NDArray[np.int64]) -> None:  # fmt: skip
        self.u, self.w, self.sigma, self.electrons = u, w, sigma, electrons
        self.points, self.ray = points, ray
        self.half_width, self.slope = _lateral(u, w, ray)

    def arrays(
        self,
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        return self.u, self.w, self.half_width, self.slope, self.sigma, self.electrons

    @classmethod
    def empty(cls) -> _Splats:
        z = np.empty(0)
        return cls(z, z, z, z, np.empty((0, 3)), np.empty(0, dtype=np.int64))

    def __len__(self) -> int:
        return len(self.u)


def _lateral(u: FloatArray, w: FloatArray, ray: NDArray[np.int64]) -> tuple[FloatArray, FloatArray]:
    """Half the stretch of the stripe each ray stands for, along the columns (half the mean gap
    to its neighbours in the fan, pixels), and the stripe's slope du/dw there. A neighbour
    counts when it is the next ray of the fan and less than two columns away."""
    n = len(u)
    half = np.full(n, 0.5)
    slope = np.zeros(n)
    if n < 2:
        return half, slope
    gap_w = np.diff(w)
    linked = (np.diff(ray) == 1) & (np.abs(gap_w) < 2.0)
    gap_u = np.diff(u)
    left_ok = np.concatenate([[False], linked])
    right_ok = np.concatenate([linked, [False]])
    left_w = np.concatenate([[0.0], np.abs(gap_w)])
    right_w = np.concatenate([np.abs(gap_w), [0.0]])
    count = left_ok.astype(float) + right_ok
    half = np.where(count > 0, 0.5 * (left_w * left_ok + right_w * right_ok) / np.maximum(count, 1),
                    0.5)  # fmt: skip
    du = np.concatenate([[0.0], gap_u]) * left_ok + np.concatenate([gap_u, [0.0]]) * right_ok
    dw = np.concatenate([[0.0], gap_w]) * left_ok + np.concatenate([gap_w, [0.0]]) * right_ok
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.where(np.abs(dw) > 1e-9, du / dw, 0.0)
    return half, np.clip(slope, -50.0, 50.0)


def _facing(normals: FloatArray, incoming: FloatArray) -> FloatArray:
    """Unit normals turned against the incoming direction."""
    flip = np.einsum("ij,ij->i", normals, incoming) > 0
    return np.where(flip[:, None], -normals, normals)


def _across(normals: FloatArray, along: FloatArray, thickness_dir: FloatArray) -> FloatArray:
    """Direction on the surface that the sheet's thickness covers: thickness_dir projected
    onto the tangent plane along the beam, t = e - (n.e)/(n.d) d."""
    n_dot_d = np.einsum("ij,ij->i", normals, along)
    n_dot_d = np.where(np.abs(n_dot_d) < MIN_COS_INCIDENCE,
                       np.copysign(MIN_COS_INCIDENCE, n_dot_d), n_dot_d)  # fmt: skip
    n_dot_e = np.einsum("ij,ij->i", normals, thickness_dir)
    return np.asarray(thickness_dir - (n_dot_e / n_dot_d)[:, None] * along)


def _direct_splats(optics: _Optics, caster: RayCaster, hits: Any, directions: FloatArray,
                   power: FloatArray, T: FloatArray, mat: Material) -> _Splats:  # fmt: skip
    """The stripe the camera sees where the sheet lights the part (visible lit points)."""
    idx = np.flatnonzero(hits.reason == Reason.VALID)
    if len(idx) == 0:
        return _Splats.empty()
    d = directions[idx]
    points = np.column_stack([np.zeros(len(idx)), hits.points_laser[idx]])
    normals = _facing(caster.face_normals[hits.face[idx]] @ T[:3, :3], d)
    share = optics.collected(points, normals, d, mat)
    e_x = np.broadcast_to(np.array([1.0, 0.0, 0.0]), d.shape)
    sigma_mm = optics.cam.line_sigma_mm(hits.distance_mm[idx], optics.waist)
    sigma = optics.footprint_sigma_px(points, _across(normals, d, e_x), sigma_mm)
    u, w = optics.grid(*optics.project(points))
    return _Splats(u, w, sigma, optics.electrons_per_power * power[idx] * share, points, idx)


def _bounce_splats(optics: _Optics, caster: RayCaster, hits: Any, directions: FloatArray,
                   power: FloatArray, T: FloatArray, mat: Material) -> _Splats:  # fmt: skip
    """The false stripe: each lit point's specular share traced to the point it lights."""
    idx = np.flatnonzero(hits.face >= 0)
    if mat.specular_reflectance <= 0 or len(idx) == 0:
        return _Splats.empty()
    R, origin = T[:3, :3], T[:3, 3]
    d = directions[idx]
    n1 = _facing(caster.face_normals[hits.face[idx]] @ R, d)
    mirror = d - 2.0 * np.einsum("ij,ij->i", d, n1)[:, None] * n1
    lit = np.column_stack([np.zeros(len(idx)), hits.points_laser[idx]])
    offset = constants.SHADOW_RAY_OFFSET_MM
    start_world = (lit + offset * mirror) @ R.T + origin
    second = caster.first_hit(start_world, mirror @ R.T)
    camera_world = R @ optics.camera_center + origin
    p2_world = second.points
    ok = second.hit & (np.einsum("ij,ij->i", second.normals, camera_world - p2_world) > 0)
    rows = np.flatnonzero(ok)
    if len(rows):
        rows = rows[~caster.line_of_sight_blocked(p2_world[rows], camera_world)]
    if len(rows) == 0:
        return _Splats.empty()
    p2 = (p2_world[rows] - origin) @ R
    n2 = second.normals[rows] @ R
    incoming = mirror[rows]
    share = optics.collected(p2, n2, incoming, mat)
    e_x = np.array([1.0, 0.0, 0.0])
    thickness_dir = e_x - 2.0 * (n1[rows] @ e_x)[:, None] * n1[rows]
    travel = second.distance_mm[rows] + offset
    sigma_mm = np.hypot(optics.cam.line_sigma_mm(hits.distance_mm[idx[rows]], optics.waist),
                        mat.lobe_rad * travel)  # fmt: skip
    sigma = optics.footprint_sigma_px(p2, _across(n2, incoming, thickness_dir), sigma_mm)
    u, w = optics.grid(*optics.project(p2))
    electrons = optics.electrons_per_power * power[idx[rows]] * mat.specular_reflectance * share
    return _Splats(u, w, sigma, electrons, p2, idx[rows])
