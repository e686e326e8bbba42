"""The laser vision sensor of the paper (Sec. 2.2, Eq. 1-8), as a frozen dataclass.

Laser frame {L} (paper Fig. 2): origin at the laser emitter; the laser plane is x_L = 0; z_L is
range along the central laser ray; y_L is lateral along the stripe. The camera's projection
centre sits at x_L = b on the baseline and its optical axis meets the laser axis at the angle
theta_s, at the range b / tan(theta_s). The chip has size H along x_c (which encodes range) and V
along z_c (which encodes the lateral position), with N_H and N_V pixels; lambda is the focal
length. Only the ratios H / lambda and V / lambda and the baseline b change what the sensor sees.

Derived here, beyond the paper: the inverse of Eq. 2-3 (``project``), the range limits, and the
local resolutions dz/dx_c and dy/dz_c at each range (the paper's R_D and R_L are averages).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack.errors import SensorGeometryError
from seamtrack.sensing.presets import DATA_SHEETS, DataSheet
from seamtrack.sensing.scan import scan_mesh

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LaserLineSensor:
    """Geometry of a laser-line triangulation sensor.

    Parameters
    ----------
    baseline_mm : float
        b, laser emitter to camera centre.
    angle_rad : float
        theta_s, between the laser axis and the camera's optical axis, in (0, pi/2).
    focal_length_mm : float
        lambda.
    chip_h_mm, chip_v_mm : float
        H (along x_c, range direction) and V (along z_c, lateral direction).
    pixels_h, pixels_v : int
        N_H and N_V.
    standoff_mm : float
        Table 3's stand-off A: from the sensor housing's front to the near end of the depth of
        field (a data-sheet figure that Eq. 1-8 do not involve; used to draw the housing).
    quantize : bool
        Snap measurements to pixel centres (True: a real chip; False: the ideal sensor).
    max_incidence_rad : float
        Stripe points seen at a larger angle between the laser ray and the surface normal are
        too dim to measure (mesh mode).
    name : str
    """

    baseline_mm: float
    angle_rad: float
    focal_length_mm: float
    chip_h_mm: float
    chip_v_mm: float
    pixels_h: int
    pixels_v: int
    standoff_mm: float = float("nan")
    quantize: bool = True
    max_incidence_rad: float = math.radians(80.0)
    name: str = "custom"

    def __post_init__(self) -> None:
        for key in ("baseline_mm", "focal_length_mm", "chip_h_mm", "chip_v_mm"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise SensorGeometryError(
                    f"must be a positive length, got {value}",
                    field=f"sensor.{key}",
                    fix="give a length > 0 in mm",
                )
        for key in ("pixels_h", "pixels_v"):
            if int(getattr(self, key)) < 1:
                raise SensorGeometryError(
                    "needs at least one pixel", field=f"sensor.{key}", fix="give a pixel count >= 1"
                )
        if not 0.0 < self.angle_rad < math.pi / 2:
            raise SensorGeometryError(
                f"laser angle {math.degrees(self.angle_rad):.6g} deg is outside (0, 90) deg",
                field="sensor.angle_deg",
                fix="a triangulation sensor needs a camera angle strictly between 0 and 90 deg",
            )
        half_h = 0.5 * self.chip_h_mm
        limit = self.focal_length_mm * math.tan(self.angle_rad)
        if half_h >= limit:
            raise SensorGeometryError(
                f"H/2 = {half_h:.6g} mm >= lambda tan(theta_s) = {limit:.6g} mm: the chip's far "
                "edge looks parallel to the laser, so the depth of field (Eq. 4) is infinite or "
                "negative",
                field="sensor.chip_h_mm",
                fix="use a smaller chip, a longer focal length or a larger laser angle",
            )
        if not 0.0 < self.max_incidence_rad <= math.pi / 2:
            raise SensorGeometryError(
                "must lie in (0, 90] deg",
                field="sensor.max_incidence_deg",
                fix="give the largest incidence angle the sensor measures",
            )

    # ----------------------------------------------------------------- Eq. 4-8
    @property
    def _s(self) -> float:
        return math.sin(self.angle_rad)

    @property
    def _c(self) -> float:
        return math.cos(self.angle_rad)

    @property
    def depth_of_field_mm(self) -> float:
        """D, Eq. (4)."""
        b, lam, H = self.baseline_mm, self.focal_length_mm, self.chip_h_mm
        return 4 * b * lam * H / (4 * lam**2 * self._s**2 - H**2 * self._c**2)

    @property
    def fov_far_mm(self) -> float:
        """F_max, Eq. (5): lateral field of view at the far end of the range."""
        b, lam, H, V = self.baseline_mm, self.focal_length_mm, self.chip_h_mm, self.chip_v_mm
        return 2 * b * V / (2 * lam * self._s - H * self._c)

    @property
    def fov_near_mm(self) -> float:
        """F_min, Eq. (6): lateral field of view at the near end of the range."""
        b, lam, H, V = self.baseline_mm, self.focal_length_mm, self.chip_h_mm, self.chip_v_mm
        return 2 * b * V / (2 * lam * self._s + H * self._c)

    @property
    def depth_resolution_mm(self) -> float:
        """R_D, Eq. (7): the average depth resolution D / N_H."""
        return self.depth_of_field_mm / self.pixels_h

    @property
    def lateral_resolution_range_mm(self) -> tuple[float, float]:
        """Eq. (8): (F_min / N_V, F_max / N_V), the bounds of the lateral resolution."""
        return self.fov_near_mm / self.pixels_v, self.fov_far_mm / self.pixels_v

    @property
    def lateral_resolution_mm(self) -> float:
        """Average lateral resolution, the mean of Eq. (8)'s bounds."""
        return 0.5 * sum(self.lateral_resolution_range_mm)

    @property
    def range_near_mm(self) -> float:
        """z_L at the chip edge x_c = +H/2 (near end of the depth of field)."""
        return float(self.triangulate(0.5 * self.chip_h_mm, 0.0)[1])

    @property
    def range_far_mm(self) -> float:
        """z_L at the chip edge x_c = -H/2 (far end of the depth of field)."""
        return float(self.triangulate(-0.5 * self.chip_h_mm, 0.0)[1])

    @property
    def range_center_mm(self) -> float:
        """z_L where the optical axis crosses the laser axis, b / tan(theta_s) (x_c = 0)."""
        return self.baseline_mm / math.tan(self.angle_rad)

    @property
    def camera_center_laser(self) -> FloatArray:
        """(3,) camera projection centre in the laser frame (x_L, y_L, z_L)."""
        return np.array([self.baseline_mm, 0.0, 0.0])

    @property
    def pixel_pitch_mm(self) -> tuple[float, float]:
        """(H / N_H, V / N_V)."""
        return self.chip_h_mm / self.pixels_h, self.chip_v_mm / self.pixels_v

    def local_depth_resolution_mm(self, z_L: ArrayLike) -> FloatArray:
        """|dz_L/dx_c| times the pixel pitch: the depth step of one pixel at range z_L."""
        z = np.asarray(z_L, dtype=np.float64)
        depth_along_axis = z * self._c + self.baseline_mm * self._s
        return (
            self.pixel_pitch_mm[0] * depth_along_axis**2 / (self.baseline_mm * self.focal_length_mm)
        )

    def local_lateral_resolution_mm(self, z_L: ArrayLike) -> FloatArray:
        """|dy_L/dz_c| times the pixel pitch: the lateral step of one pixel at range z_L."""
        z = np.asarray(z_L, dtype=np.float64)
        depth_along_axis = z * self._c + self.baseline_mm * self._s
        return self.pixel_pitch_mm[1] * depth_along_axis / self.focal_length_mm

    def half_width_mm(self, z_L: ArrayLike) -> FloatArray:
        """Half the lateral field of view at range z_L (the trapezoid's side at that range)."""
        z = np.asarray(z_L, dtype=np.float64)
        return (
            0.5
            * self.chip_v_mm
            * (z * self._c + self.baseline_mm * self._s)
            / (self.focal_length_mm)
        )

    # ----------------------------------------------------------------- Eq. 1-3
    def triangulate(self, x_c: ArrayLike, z_c: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Chip coordinates (mm) to the laser frame, Eq. (2)-(3); x_L = 0 (Eq. 1).

        Returns
        -------
        y_L, z_L : float arrays broadcast from the inputs
        """
        xc = np.asarray(x_c, dtype=np.float64)
        zc = np.asarray(z_c, dtype=np.float64)
        b, lam = self.baseline_mm, self.focal_length_mm
        denominator = xc * self._c + lam * self._s
        return b * zc / denominator, b * (lam * self._c - xc * self._s) / denominator

    def project(self, y_L: ArrayLike, z_L: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Laser-plane point to chip coordinates (mm): the inverse of Eq. (2)-(3).

        Derived from Eq. (3): x_c = lambda (b cos - z sin) / (z cos + b sin), and then
        z_c = lambda y / (z cos + b sin), where z cos + b sin is the depth along the optical axis.
        """
        y = np.asarray(y_L, dtype=np.float64)
        z = np.asarray(z_L, dtype=np.float64)
        b, lam = self.baseline_mm, self.focal_length_mm
        depth_along_axis = z * self._c + b * self._s
        return lam * (b * self._c - z * self._s) / depth_along_axis, lam * y / depth_along_axis

    def in_field_of_view(self, y_L: ArrayLike, z_L: ArrayLike) -> NDArray[np.bool_]:
        """True where a laser-plane point images onto the chip (the trapezoid of Fig. 2)."""
        y = np.asarray(y_L, dtype=np.float64)
        z = np.asarray(z_L, dtype=np.float64)
        with np.errstate(invalid="ignore", divide="ignore"):
            x_c, z_c = self.project(y, z)
            slack = 1.0 + constants.CHIP_EDGE_RTOL
            inside = (
                (z * self._c + self.baseline_mm * self._s > 0)
                & (np.abs(x_c) <= 0.5 * self.chip_h_mm * slack)
                & (np.abs(z_c) <= 0.5 * self.chip_v_mm * slack)
            )
        return np.asarray(inside & np.isfinite(y) & np.isfinite(z))

    def pixel_centers(self, x_c: ArrayLike, z_c: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Snap chip coordinates to the centre of the pixel they fall in (edges clamp inwards)."""
        pitch_h, pitch_v = self.pixel_pitch_mm
        ih = np.clip(
            np.floor((np.asarray(x_c) + 0.5 * self.chip_h_mm) / pitch_h), 0, self.pixels_h - 1
        )
        iv = np.clip(
            np.floor((np.asarray(z_c) + 0.5 * self.chip_v_mm) / pitch_v), 0, self.pixels_v - 1
        )
        return (ih + 0.5) * pitch_h - 0.5 * self.chip_h_mm, (iv + 0.5) * pitch_v - 0.5 * (
            self.chip_v_mm
        )

    def measure(self, y_L: ArrayLike, z_L: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """What the sensor reports for true laser-plane points: the pixel-quantized point when
        ``quantize`` is on (project, snap to the pixel centre, triangulate back), else the point.
        Points outside the field of view come back unchanged; test them with
        :meth:`in_field_of_view`.
        """
        y = np.asarray(y_L, dtype=np.float64)
        z = np.asarray(z_L, dtype=np.float64)
        if not self.quantize:
            return y.copy(), z.copy()
        with np.errstate(invalid="ignore", divide="ignore"):
            x_c, z_c = self.pixel_centers(*self.project(y, z))
            y_q, z_q = self.triangulate(x_c, z_c)
        inside = self.in_field_of_view(y, z)
        return np.where(inside, y_q, y), np.where(inside, z_q, z)

    # ----------------------------------------------------------------- inverse design
    @classmethod
    def from_specs(
        cls,
        *,
        depth_of_field_mm: float,
        fov_near_mm: float,
        fov_far_mm: float,
        angle_deg: float,
        depth_resolution_mm: float,
        lateral_resolution_mm: float,
        focal_length_mm: float = 16.0,
        standoff_mm: float = float("nan"),
        name: str = "custom",
        **kwargs: Any,
    ) -> LaserLineSensor:
        """Solve the geometry from a data sheet's specs (Eq. 4-8 inverted).

        With h = H / (2 lambda) and v = V / (2 lambda), Eq. (5)/(6) give
        F_max / F_min = (sin + h cos) / (sin - h cos), hence h = tan(theta) (r - 1) / (r + 1);
        Eq. (4) then gives b = D (sin^2 - h^2 cos^2) / (2 h), and Eq. (6) v = F_min
        (sin + h cos) / (2 b). The focal length only scales the chip (choose your lens).
        N_H = D / R_D and N_V = (F_min + F_max) / (2 R_L) (the average of Eq. 8), rounded to
        whole pixels: to the nearest when within 1e-6 of one, else up (never coarser than asked).
        """
        specs = {
            "depth_of_field_mm": depth_of_field_mm,
            "fov_near_mm": fov_near_mm,
            "fov_far_mm": fov_far_mm,
            "depth_resolution_mm": depth_resolution_mm,
            "lateral_resolution_mm": lateral_resolution_mm,
            "focal_length_mm": focal_length_mm,
        }
        for key, value in specs.items():
            if not (math.isfinite(value) and value > 0):
                raise SensorGeometryError(
                    f"must be > 0, got {value}",
                    field=f"sensor.{key}",
                    fix="give a positive length in mm",
                )
        if not 0.0 < angle_deg < 90.0:
            raise SensorGeometryError(
                f"{angle_deg} deg is outside (0, 90)",
                field="sensor.angle_deg",
                fix="give the laser/camera angle in degrees, e.g. 16.17",
            )
        if not fov_far_mm > fov_near_mm:
            raise SensorGeometryError(
                f"fov_far_mm = {fov_far_mm} must exceed fov_near_mm = {fov_near_mm}: a "
                "triangulation sensor's lateral field widens with range (Eq. 5-6)",
                field="sensor.fov_far_mm",
                fix="swap the two values or correct the data sheet figures",
            )
        theta = math.radians(angle_deg)
        s, c = math.sin(theta), math.cos(theta)
        r = fov_far_mm / fov_near_mm
        h = math.tan(theta) * (r - 1.0) / (r + 1.0)
        baseline = depth_of_field_mm * (s**2 - h**2 * c**2) / (2.0 * h)
        v = fov_near_mm * (s + h * c) / (2.0 * baseline)
        pixels_h = _whole_pixels(depth_of_field_mm / depth_resolution_mm)
        pixels_v = _whole_pixels((fov_near_mm + fov_far_mm) / (2.0 * lateral_resolution_mm))
        return cls(
            baseline_mm=baseline,
            angle_rad=theta,
            focal_length_mm=focal_length_mm,
            chip_h_mm=2.0 * h * focal_length_mm,
            chip_v_mm=2.0 * v * focal_length_mm,
            pixels_h=pixels_h,
            pixels_v=pixels_v,
            standoff_mm=standoff_mm,
            name=name,
            **kwargs,
        )

    def specs(self) -> dict[str, float]:
        """The data-sheet view of this geometry (Table 3's rows), all derived through Eq. 4-8."""
        near, far = self.lateral_resolution_range_mm
        return {
            "standoff_mm": self.standoff_mm,
            "depth_of_field_mm": self.depth_of_field_mm,
            "fov_near_mm": self.fov_near_mm,
            "fov_far_mm": self.fov_far_mm,
            "depth_resolution_mm": self.depth_resolution_mm,
            "lateral_resolution_mm": self.lateral_resolution_mm,
            "lateral_resolution_near_mm": near,
            "lateral_resolution_far_mm": far,
            "angle_deg": math.degrees(self.angle_rad),
            "range_near_mm": self.range_near_mm,
            "range_center_mm": self.range_center_mm,
            "range_far_mm": self.range_far_mm,
        }

    def geometry(self) -> dict[str, float]:
        """The design view: b, lambda, theta_s, H, V, N_H, N_V."""
        return {
            "baseline_mm": self.baseline_mm,
            "focal_length_mm": self.focal_length_mm,
            "angle_deg": math.degrees(self.angle_rad),
            "chip_h_mm": self.chip_h_mm,
            "chip_v_mm": self.chip_v_mm,
            "pixels_h": float(self.pixels_h),
            "pixels_v": float(self.pixels_v),
        }

    def scan(self, part: Any, T_world_sensor: ArrayLike, **kwargs: Any) -> Any:
        """The stripe profile this sensor sees on a mesh at a pose (mesh mode).

        A thin delegate to :func:`seamtrack.sensing.scan.scan_mesh` (which imports ray casting on
        first use); ``part`` is a workpiece, a
        ``trimesh.Trimesh`` or a prepared ``RayCaster``.
        """
        return scan_mesh(self, part, T_world_sensor, **kwargs)

    def render(
        self,
        part: Any,
        T_world_sensor: ArrayLike,
        *,
        camera: Any = None,
        seed: Any = None,
        material: Any = None,
        t_s: float = float("nan"),
        exposure: float | None = None,
        arc: Any = None,
    ) -> Any:
        """The camera image of the stripe on a mesh at a pose (a :class:`StripeImage`).

        A thin delegate to :func:`seamtrack.sensing.render.render_image`: ``camera`` a
        :class:`~seamtrack.sensing.camera.Camera` (default ``Camera()``), ``seed`` an int or a
        numpy Generator, ``material`` a name (``"bright aluminium"``) or a
        :class:`~seamtrack.sensing.materials.Material`, ``exposure`` this frame's (auto-exposure's
        state; default the camera's), ``arc`` the welding arc in this frame (an
        :class:`~seamtrack.sensing.arc.image.ArcFrame`, default none). ``image.profile(method=...)``
        measures the profile from its pixels.
        """
        from seamtrack.sensing.render import render_image

        return render_image(self, part, T_world_sensor, camera=camera, material_name=material,
                            seed=seed, t_s=t_s, exposure=exposure, arc=arc)  # fmt: skip


def _whole_pixels(count: float) -> int:
    nearest = round(count)
    if abs(count - nearest) <= 1e-6 * max(1.0, count):
        return max(1, int(nearest))
    return max(1, math.ceil(count))


#: Data-sheet specs of the built-in sensors; ``preset(name)`` turns them into a sensor.
PRESET_SPECS: dict[str, dict[str, float]] = {
    # The paper's Table 3.
    "paper": {
        "standoff_mm": 46.0,
        "depth_of_field_mm": 60.0,
        "fov_near_mm": 18.0,
        "fov_far_mm": 32.0,
        "angle_deg": 16.17,
        "depth_resolution_mm": 0.01,
        "lateral_resolution_mm": 0.01,
    },
    # A wider, coarser seam-tracking head of the kind sold for arc welding (illustrative specs).
    "wide": {
        "standoff_mm": 60.0,
        "depth_of_field_mm": 100.0,
        "fov_near_mm": 40.0,
        "fov_far_mm": 80.0,
        "angle_deg": 25.0,
        "depth_resolution_mm": 0.05,
        "lateral_resolution_mm": 0.05,
    },
    # Real sensors from their data sheets (seamtrack.sensing.presets names the sources).
    **{name: sheet.specs() for name, sheet in DATA_SHEETS.items()},
}


def preset_source(name: str) -> str:
    """Where a preset's figures come from (one line)."""
    if name == "paper":
        return "Jung, Sung and Rhee, Table 3 (the paper)"
    if name == "wide":
        return "illustrative specs of a wide seam-tracking head (not a product)"
    sheet = DATA_SHEETS.get(name)
    if sheet is None:
        raise SensorGeometryError(f"unknown preset {name!r}", field="sensor.preset",
                                  fix=f"use one of {', '.join(sorted(PRESET_SPECS))}")  # fmt: skip
    return sheet.source


def data_sheet(name: str) -> DataSheet | None:
    """The :class:`~seamtrack.sensing.presets.DataSheet` of a real sensor preset, else None."""
    return DATA_SHEETS.get(name)


def angle_for_standoff(
    depth_of_field_mm: float, fov_near_mm: float, fov_far_mm: float, standoff_mm: float
) -> float:
    """The triangulation angle (deg) at which the near end of the range lies ``standoff_mm``
    from the emitter, for a data sheet that gives the range and field but no angle.

    With D and F_max / F_min fixed, the near range falls monotonically as the angle grows
    (``from_specs``), so it is found by bisection in (0.5, 60) deg.
    """

    def near(angle_deg: float) -> float:
        return LaserLineSensor.from_specs(
            depth_of_field_mm=depth_of_field_mm, fov_near_mm=fov_near_mm, fov_far_mm=fov_far_mm,
            angle_deg=angle_deg, depth_resolution_mm=1.0, lateral_resolution_mm=1.0,
        ).range_near_mm  # fmt: skip

    lo, hi = 0.5, 60.0
    if not near(hi) <= standoff_mm <= near(lo):
        raise SensorGeometryError(
            f"no angle in (0.5, 60) deg puts the range's near end at {standoff_mm} mm",
            field="sensor.standoff_mm",
            fix="check the data sheet's clearance, range and field of view",
        )
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if near(mid) > standoff_mm else (lo, mid)
    return 0.5 * (lo + hi)


def preset(name: str, **overrides: Any) -> LaserLineSensor:
    """A built-in sensor by name (``seamtrack sensor --list`` names them).

    ``overrides`` replace data-sheet specs (``fov_far_mm=...``) or sensor fields
    (``quantize=False``).
    """
    if name not in PRESET_SPECS:
        raise SensorGeometryError(
            f"unknown preset {name!r}",
            field="sensor.preset",
            fix=f"use one of {', '.join(sorted(PRESET_SPECS))}",
        )
    specs = dict(PRESET_SPECS[name])
    spec_keys = {k: v for k, v in overrides.items() if k in specs}
    field_keys = {k: v for k, v in overrides.items() if k not in specs}
    specs.update(spec_keys)
    return LaserLineSensor.from_specs(name=name, **specs, **field_keys)
