"""The camera of the laser-line sensor: its optics and chip (:class:`Camera`) and the image it
takes (:class:`StripeImage`), rendered by :func:`seamtrack.sensing.render.render_image`.

Image axes follow the chip of Eq. 1-3: image **rows** run along x_c (which encodes range; row 0
at x_c = -H/2, the far end of the depth of field) and image **columns** along z_c (lateral; column
0 at z_c = -V/2, y_L < 0). A row coordinate r is continuous with pixel i covering
[i - 0.5, i + 0.5], so x_c = (row0 + r + 0.5) * H / N_H - H / 2 in the full chip.

The pinhole model of Eq. 1-3 takes the camera constant lambda (``focal_length_mm``) as the
distance from the projection centre to the chip; the laser plane is in focus everywhere (a
Scheimpflug camera, as triangulation sensors are built), so the lens blurs only by diffraction
at its aperture. ``f_number`` is the working (image-side) f-number: the pupil diameter is
lambda / f_number.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import SensorGeometryError
from seamtrack.sensing.materials import Material
from seamtrack.sensing.profiles import Profile

if TYPE_CHECKING:
    from seamtrack.sensing.sensor_geometry import SensorGeometry

FloatArray = NDArray[np.float64]

#: Supersampling is capped here: finer speckle than the cap resolves is averaged on the pixel.
MAX_SUPERSAMPLE = 8


def _fail(key: str, message: str, fix: str) -> SensorGeometryError:
    return SensorGeometryError(message, field=f"sensor.camera.{key}", fix=fix)


def _number(x: float) -> str:
    return f"{x:,.0f}" if x == int(x) and abs(x) < 1e7 else f"{x:g}"


@dataclass(frozen=True)
class Bound:
    """The physical range of one camera field: ``lo <= value <= hi`` in ``unit``; ``real`` says
    what real lenses, lasers and chips have (the fix of an error)."""

    lo: float
    hi: float
    unit: str
    real: str

    def complaint(self, value: float) -> str | None:
        """What is wrong with ``value`` (None: it lies in the range)."""
        if math.isfinite(value) and self.lo <= value <= self.hi:
            return None
        unit = f" {self.unit}" if self.unit else ""
        return f"{value:g}{unit} is outside {_number(self.lo)}-{_number(self.hi)}{unit}"


#: The physical range of every camera field, the one definition: :class:`Camera` checks its
#: fields against it (so a scene's ``[sensor.camera]`` and any later exposure mode do), and a
#: dataset spec's ``[camera]`` ranges must lie within it. Keys are the scene's.
RANGES: dict[str, Bound] = {
    # Area-scan CMOS chips of machine vision are 480 to ~14,000 pixels a side (Sony IMX411:
    # 14,192 x 10,640); line-scan chips reach 16,384. A peak needs 3 rows. (How many pixels a
    # run may hold in memory is a separate bound: MAX_IMAGE_BYTES.)
    "rows": Bound(3, 16_384, "pixels", "real chips have up to 16384 pixels a side"),
    "columns": Bound(3, 16_384, "pixels", "real chips have up to 16384 pixels a side"),
    # Machine-vision lenses: M12 board lenses from about 1.5 mm, C-mount and F-mount lenses to
    # about 300 mm (the chip scales with the lens here, so the field of view stays the sensor's).
    "focal_length_mm": Bound(1.0, 500.0, "mm", "machine-vision lenses have 1.5-300 mm"),
    # Working (image-side) f-number N (1 + m): the fastest machine-vision lenses open to f/0.95,
    # the smallest stop is f/32, doubled at 1:1 magnification.
    "f_number": Bound(
        0.95,
        64.0,
        "",
        "lenses open to f/0.95 and stop down to f/32, a working f-number of 64 "
        "at 1:1 magnification; triangulation sensors work at f/4-f/16",
    ),
    # UV diode lasers (a silicon chip with UV coating) to SWIR (InGaAs chips end near 1700 nm,
    # thulium lasers at 2000 nm).
    "wavelength_nm": Bound(200.0, 2000.0, "nm", "line lasers emit 405, 450, 635-690 or 808 nm"),
    # Line generators: micro-line optics focus to 5-10 um, wide lines reach a few mm.
    "line_thickness_mm": Bound(
        0.005, 5.0, "mm", "the 1/e^2 thickness of the line at its waist, typically 0.02-1 mm"
    ),
    # Full-angle divergence of the sheet's thickness: a Gaussian beam of a 5 um waist at 2000 nm
    # diverges by 4 lambda / (pi W0) = 0.5 rad.
    "line_divergence_mrad": Bound(
        0.0, 500.0, "mrad", "the full-angle divergence of the line's thickness"
    ),
    # The focusing optics of a line laser put the waist within a few metres of the emitter.
    "waist_range_mm": Bound(1.0, 10_000.0, "mm", "the distance from the emitter to the waist"),
    # Exposure control (1 us to 10 ms shutter, gain) spans 10^4 about its nominal level; 100 full
    # wells on white saturates a 1 % reflector, 1e-4 leaves dark steel at a few electrons.
    "exposure": Bound(
        1e-4, 100.0, "", "the peak of a white plane as a fraction of the full well (0.5: half)"
    ),
    # CMOS full-well capacities: about 1,000 e- (1 um pixels) to 500,000 e- (large-pixel sCMOS,
    # CCDs).
    "full_well_e": Bound(
        1_000.0, 1_000_000.0, "e-", "CMOS pixels hold typically 5000-30000 electrons"
    ),
    # Read noise: below 1 e- (sCMOS) to some 50 e- (old CCDs, high-speed readout).
    "read_noise_e": Bound(0.0, 100.0, "e-", "electrons RMS, typically 2-20"),
    # ADCs of machine-vision chips: 8-12 bits, scientific ones 16.
    "bit_depth": Bound(1, 16, "bits", "machine-vision ADCs have 8-12 (0 in a scene: none)"),
    # Light beyond the full well on every pixel saturates the whole chip.
    "ambient": Bound(0.0, 1.0, "", "ambient light as a fraction of the full well on every pixel"),
    "supersample": Bound(
        1, MAX_SUPERSAMPLE, "", "sub-pixels per pixel and axis, or leave it out (from the optics)"
    ),
    # Auto-exposure aims the stripe's brightest pixel below saturation and well above the noise
    # (profilers aim at 50-90 % of full scale).
    "target_peak": Bound(
        0.05, 0.98, "", "auto-exposure's aim for the brightest pixel, a fraction of full scale"
    ),
    # Multiple exposure (Gocator, Keyence HDR): 2-5 exposures, each a factor of `exposure`
    # down to 1e-4 (the shutter's span), the longest first.
    "exposure_factor": Bound(
        1e-4, 1.0, "", "each exposure of the set as a factor of `exposure` (1: the longest)"
    ),
    "exposure_count": Bound(1, 8, "exposures", "multiple-exposure modes merge 2-5 exposures"),
}

#: Exposure control (:attr:`Camera.exposure_mode`): ``fixed`` (``exposure`` every frame),
#: ``auto`` (each frame's exposure from the previous frame's peak, :meth:`Camera.next_exposure`),
#: ``multi`` (every frame taken at each exposure of ``exposure_set``, merged column by column).
EXPOSURE_MODES = ("fixed", "auto", "multi")


#: Pixel columns per block of the renderer's band processing (:mod:`seamtrack.sensing.render`).
BLOCK_COLUMNS = 32
#: Bytes a rendered image costs per pixel at its peak. Measured (peak RSS of ``seamtrack render
#: v-groove-camera``, less the 0.37 GB of a 512 x 1024 image): 52 B a pixel at 1024 x 2048 and
#: supersample 4, 66 B at 2048 x 4096 and 73 B at 4096 x 8192 (supersample 1): the float64
#: electrons, the chip readout's float32 stages, the peak detector and the PNG's colour mapping.
BYTES_PER_PIXEL = 80
#: Bytes per sub-pixel cell of one block's box (speckle: float64 cells, two float32 noise planes,
#: the complex64 field, its padded spectrum and inverse, the float32 intensity and its float64
#: copy).
BYTES_PER_CELL = 100
#: What the image may take: the rest of a run (Python, CadQuery, the mesh, Embree, the ray fan
#: of at most MAX_RAYS) holds about 0.4 GB, so a run stays under 2 GB.
MAX_IMAGE_BYTES = 1408 * 2**20


def image_bytes(rows: int, columns: int, s: int, apron_cells: int) -> int:
    """Peak bytes of rendering a ``rows`` x ``columns`` image at ``s`` sub-pixels per pixel and
    axis: the pixels, and one block's box of cells with its apron, as tall as the image (a stripe
    that crosses every row within one block)."""
    box = (rows * s + 2 * apron_cells) * (BLOCK_COLUMNS * s + 2 * apron_cells)
    return BYTES_PER_PIXEL * rows * columns + BYTES_PER_CELL * box


def range_error(key: str, value: float, field: str | None = None) -> SensorGeometryError | None:
    """The error for camera field ``key`` set to ``value`` outside :data:`RANGES` (None: in
    range); ``field`` names it (default ``sensor.camera.<key>``)."""
    bound = RANGES[key]
    message = bound.complaint(float(value))
    if message is None:
        return None
    unit = f" {bound.unit}" if bound.unit else ""
    fix = f"give {_number(bound.lo)}-{_number(bound.hi)}{unit}: {bound.real}"
    return SensorGeometryError(message, field=field or f"sensor.camera.{key}", fix=fix)


@dataclass(frozen=True)
class Camera:
    """Optics, laser line and chip of a laser-line sensor's camera.

    Every field must lie within its physical range (:data:`RANGES`: real lenses, lasers and
    chips); :meth:`check` also bounds the image's memory (:data:`MAX_IMAGE_BYTES`).

    Parameters
    ----------
    rows, columns : int, optional
        The chip's pixel grid along x_c (range) and z_c (lateral); default the sensor's N_H and
        N_V. The chip keeps its size (the sensor's H and V), so these set the pixel pitch.
    roi : (row0, row1, col0, col1), optional
        A region of interest of that grid, half-open; the image holds only these pixels.
    focal_length_mm : float, optional
        The lens (camera constant lambda); default the sensor's. The chip scales with it, so
        the field of view stays the sensor's (only H / lambda, V / lambda matter in Eq. 1-8).
    f_number : float
        Working f-number N: pupil diameter lambda / N; diffraction blur and speckle follow.
    wavelength_nm : float
        Laser wavelength, 200-2000 nm.
    line_thickness_mm : float
        Full 1/e^2 width of the laser sheet across its plane (along x_L) at the waist.
    line_divergence_rad : float, optional
        Full-angle 1/e^2 divergence of that thickness; default the diffraction limit of a
        Gaussian beam of that waist, 4 lambda / (pi * thickness).
    waist_range_mm : float, optional
        Distance from the emitter to the waist along the laser; default the range centre.
    exposure : float
        Peak signal, as a fraction of the full well, that a white Lambertian plane across the
        laser at the range centre gives (the level a sensor's exposure control aims at).
    full_well_e : float
        Electrons a pixel holds before it saturates.
    read_noise_e : float
        RMS read noise, electrons.
    bit_depth : int, optional
        ADC bits; None: no quantization.
    ambient : float
        Ambient or arc light, as a fraction of the full well added to every pixel.
    speckle : bool
        Laser speckle: the surface's coherent field imaged through the pupil.
    shot_noise : bool
        Poisson statistics of the collected electrons.
    supersample : int, optional
        Sub-pixels per pixel and axis for the speckle field; default from lambda N and the
        pixel pitch (2 per speckle grain, at most :data:`MAX_SUPERSAMPLE`).
    exposure_mode : {"multi", "auto", "fixed"}
        Exposure control (:data:`EXPOSURE_MODES`). ``fixed``: every frame at ``exposure``.
        ``auto``: a frame at ``exposure`` first, then each frame's exposure set so that the
        previous frame's brightest pixel lands at ``target_peak`` (the run keeps that state).
        ``multi`` (default): every frame taken at ``exposure`` times each factor of
        ``exposure_set`` (one speckle pattern, independent noise) and merged column by column:
        each column from the longest exposure that does not saturate it (the shortest where all
        do), as the multiple-exposure (HDR) modes of Gocator and Keyence profilers.
    target_peak : float
        Auto-exposure's aim for the brightest pixel, a fraction of full scale.
    exposure_set : tuple of float
        The multiple exposure's factors of ``exposure``, the longest (1.0) first, decreasing;
        an exposure below the shortest (:data:`RANGES`) is taken at the shortest.
    """

    rows: int | None = None
    columns: int | None = None
    roi: tuple[int, int, int, int] | None = None
    focal_length_mm: float | None = None
    f_number: float = 8.0
    wavelength_nm: float = 660.0
    line_thickness_mm: float = 0.2
    line_divergence_rad: float | None = None
    waist_range_mm: float | None = None
    exposure: float = 0.5
    full_well_e: float = 10_000.0
    read_noise_e: float = 5.0
    bit_depth: int | None = 10
    ambient: float = 0.0
    speckle: bool = True
    shot_noise: bool = True
    supersample: int | None = None
    exposure_mode: str = "multi"
    target_peak: float = 0.7
    exposure_set: tuple[float, ...] = (1.0, 1 / 8, 1 / 64, 1 / 512)

    def __post_init__(self) -> None:
        self._check_whole_numbers()
        self._check_optics()
        self._check_roi()
        self._check_exposure_control()

    def _check_whole_numbers(self) -> None:
        """The chip's size, its supersampling and bit depth: whole numbers in their ranges."""
        for key in ("rows", "columns", "supersample", "bit_depth"):
            value = getattr(self, key)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int):
                raise _fail(key, f"{value!r} is not a whole number", RANGES[key].real)
            if error := range_error(key, value):
                raise error

    def _check_optics(self) -> None:
        """The lens, the laser line and the chip's electrons within their physical ranges."""
        for key in (
            "focal_length_mm",
            "f_number",
            "wavelength_nm",
            "line_thickness_mm",
            "waist_range_mm",
            "exposure",
            "full_well_e",
            "read_noise_e",
            "ambient",
        ):
            value = getattr(self, key)
            if value is not None and (error := range_error(key, value)):
                raise error
        div = self.line_divergence_rad
        if div is not None and (error := range_error("line_divergence_mrad", 1e3 * div)):
            raise error

    def _check_roi(self) -> None:
        """A region of interest of at least 3 rows and 1 column, from row and column 0 on."""
        if self.roi is not None:
            r0, r1, c0, c1 = self.roi
            if not (0 <= r0 and r1 - r0 >= 3 and 0 <= c0 and c1 - c0 >= 1):
                raise _fail(
                    "roi", f"{list(self.roi)} is empty or negative",
                    "give [row0, row1, col0, col1] with row1 >= row0 + 3 and col1 > col0",
                )  # fmt: skip

    def _check_exposure_control(self) -> None:
        """A known exposure mode, its target peak, and the multiple exposure's factors: numbers
        from 1 down, each in range."""
        if self.exposure_mode not in EXPOSURE_MODES:
            raise _fail("exposure_mode", f"{self.exposure_mode!r} is not an exposure mode",
                        f"give one of {', '.join(repr(m) for m in EXPOSURE_MODES)}")  # fmt: skip
        if error := range_error("target_peak", self.target_peak):
            raise error
        factors = tuple(self.exposure_set)
        if error := range_error("exposure_count", len(factors), "sensor.camera.exposure_set"):
            raise error
        for factor in factors:
            if isinstance(factor, bool) or not isinstance(factor, (int, float)):
                raise _fail("exposure_set", f"{factor!r} is not a number",
                            RANGES["exposure_factor"].real)  # fmt: skip
            if error := range_error("exposure_factor", factor, "sensor.camera.exposure_set"):
                raise error
        if factors[0] != 1.0 or any(b >= a for a, b in itertools.pairwise(factors)):
            raise _fail("exposure_set", f"{list(factors)} does not start at 1 and decrease",
                        "give the factors longest first, e.g. [1, 0.125, 0.015625]")  # fmt: skip

    # ------------------------------------------------------------------ variants
    @classmethod
    def ideal(cls, **fields: Any) -> Camera:
        """The optics (line width, diffraction blur, pixel integration) with every noise source
        off: no speckle, shot or read noise, quantization or ambient light."""
        return cls(**{**_NOISELESS, **fields})

    def without_noise(self) -> Camera:
        """This camera with every noise source off (as :meth:`ideal`)."""
        return dataclasses.replace(self, **_NOISELESS)

    @property
    def is_ideal(self) -> bool:
        """No noise source is on."""
        return all(getattr(self, k) == v for k, v in _NOISELESS.items())

    # ------------------------------------------------------------------ derived optics
    @property
    def wavelength_mm(self) -> float:
        return self.wavelength_nm * 1e-6

    @property
    def speckle_size_mm(self) -> float:
        """lambda * N on the chip: the diameter scale of a speckle grain (the Airy radius is
        1.22 lambda N)."""
        return self.wavelength_mm * self.f_number

    @property
    def blur_sigma_mm(self) -> float:
        """Standard deviation of the Gaussian that fits the Airy disc, 0.42 lambda N, on the
        chip (used for the blur when speckle is off; with speckle the pupil itself blurs)."""
        return 0.42 * self.speckle_size_mm

    def divergence_rad(self) -> float:
        """Full-angle divergence of the line thickness (the Gaussian-beam value by default)."""
        if self.line_divergence_rad is not None:
            return self.line_divergence_rad
        return 4.0 * self.wavelength_mm / (math.pi * self.line_thickness_mm)

    def line_sigma_mm(self, distance_mm: Any, waist_mm: float) -> FloatArray:
        """Standard deviation of the sheet's intensity across its plane at a distance from the
        emitter: a quarter of the 1/e^2 width sqrt(W0^2 + (Theta (d - d_waist))^2)."""
        d = np.asarray(distance_mm, dtype=np.float64)
        width = np.hypot(self.line_thickness_mm, self.divergence_rad() * (d - waist_mm))
        return np.asarray(0.25 * width)

    def imaging_sensor(self, sensor: SensorGeometry) -> SensorGeometry:
        """The sensor geometry this camera images with: its pixel grid and lens, the same field
        of view, every point measured (no incidence limit, no pixel snapping)."""
        f = self.focal_length_mm or sensor.focal_length_mm
        scale = f / sensor.focal_length_mm
        return dataclasses.replace(
            sensor,
            focal_length_mm=f,
            chip_h_mm=sensor.chip_h_mm * scale,
            chip_v_mm=sensor.chip_v_mm * scale,
            pixels_h=self.rows or sensor.pixels_h,
            pixels_v=self.columns or sensor.pixels_v,
            quantize=False,
            max_incidence_rad=math.pi / 2,
        )

    def window(self, imaging: SensorGeometry) -> tuple[int, int, int, int]:
        """(row0, row1, col0, col1) of the image in the full chip grid."""
        if self.roi is None:
            return 0, imaging.pixels_h, 0, imaging.pixels_v
        return self.roi

    def supersampling(self, imaging: SensorGeometry) -> int:
        """Sub-pixels per pixel and axis: 1 without speckle; with speckle, two per lambda N on
        the chip (the intensity's band limit), at most :data:`MAX_SUPERSAMPLE`."""
        if self.supersample is not None:
            return self.supersample
        if not self.speckle:
            return 1
        pitch = max(imaging.pixel_pitch_mm)
        return int(min(MAX_SUPERSAMPLE, max(1, math.ceil(2.0 * pitch / self.speckle_size_mm))))

    def next_exposure(self, exposure: float, peak: float) -> float:
        """Auto-exposure: the exposure of the next frame, from this frame's ``exposure`` and its
        brightest pixel ``peak`` (fraction of full scale). The signal is linear in exposure, so
        exposure * target_peak / peak lands the peak on target; a saturated frame (whose peak
        understates the light) steps down 8 times; nothing seen opens up 4 times; a step is at
        most 16 times; within :data:`RANGES`' exposure range."""
        bound = RANGES["exposure"]
        if not math.isfinite(peak) or peak <= 0.0:
            return float(min(bound.hi, 4.0 * exposure))  # nothing seen: open up
        factor = 0.125 if peak >= 1.0 else min(max(self.target_peak / peak, 1.0 / 16.0), 16.0)
        return float(min(bound.hi, max(bound.lo, exposure * factor)))

    def check(self, sensor: SensorGeometry) -> None:
        """Refuse what cannot work with this sensor: a region of interest off the chip, a laser
        line thicker than the field of view or the depth of field."""
        imaging = self.imaging_sensor(sensor)
        if self.roi is not None:
            _, r1, _, c1 = self.roi
            if r1 > imaging.pixels_h or c1 > imaging.pixels_v:
                raise _fail("roi", f"{list(self.roi)} reaches beyond the {imaging.pixels_h} x "
                            f"{imaging.pixels_v} pixel chip",
                            "keep row1 <= rows and col1 <= columns")  # fmt: skip
        self._check_memory(imaging)
        waist = self.waist_range_mm or sensor.range_center_mm
        widest = 4.0 * float(
            np.max(self.line_sigma_mm([sensor.range_near_mm, sensor.range_far_mm], waist))
        )
        field = min(sensor.fov_near_mm, sensor.depth_of_field_mm)
        if widest >= field:
            raise _fail("line_thickness_mm", f"the laser line is {widest:.4g} mm thick in the "
                        f"depth of field, wider than the field ({field:.4g} mm)",
                        "give the 1/e^2 thickness of the line, typically 0.02-1 mm")  # fmt: skip

    def apron_cells(self, imaging: SensorGeometry, s: int) -> int:
        """Cells the renderer adds around each box: 4 blur sigmas, or 4 lambda N with speckle;
        a whole number of pixels (as :meth:`seamtrack.sensing.formation.Optics.apron_cells`)."""
        reach = 4.0 * (self.speckle_size_mm if self.speckle else self.blur_sigma_mm)
        cells = math.ceil(reach / (min(imaging.pixel_pitch_mm) / s)) + 1
        return s * math.ceil(cells / s)

    def _check_memory(self, imaging: SensorGeometry) -> None:
        """Refuse an image whose rendering would take more than :data:`MAX_IMAGE_BYTES`: name
        the supersampling when less of it fits, else the chip size."""
        r0, r1, c0, c1 = self.window(imaging)
        rows, columns = r1 - r0, c1 - c0
        s = self.supersampling(imaging)
        need = image_bytes(rows, columns, s, self.apron_cells(imaging, s))
        if need <= MAX_IMAGE_BYTES:
            return
        size = f"{rows} x {columns} pixels at supersample {s}"
        message = (
            f"{size} need about {need / 2**30:.3g} GB to render, more than the "
            f"{MAX_IMAGE_BYTES / 2**30:.3g} GB an image may take (a run stays under 2 GB)"
        )
        fits = [
            k
            for k in range(1, s)
            if image_bytes(rows, columns, k, self.apron_cells(imaging, k)) <= MAX_IMAGE_BYTES
        ]
        if fits:
            raise _fail("supersample", message, f"give supersample = {max(fits)} or less, or "
                        "fewer rows and columns")  # fmt: skip
        most = MAX_IMAGE_BYTES // BYTES_PER_PIXEL
        key = "roi" if self.roi is not None else "rows" if rows >= columns else "columns"
        fix = f"give rows x columns (or a roi) of at most {most / 1e6:.3g} million pixels, e.g. "
        raise _fail(key, message, fix + "2048 x 4096, at supersample 1")


_NOISELESS: dict[str, Any] = {
    "speckle": False,
    "shot_noise": False,
    "read_noise_e": 0.0,
    "bit_depth": None,
    "ambient": 0.0,
}


# =========================================================================== the image
@dataclass(frozen=True, eq=False)
class StripeImage:
    """A camera image of the laser stripe, with the truth it was rendered from.

    Attributes
    ----------
    pixels : (rows, columns) float32
        Signal as a fraction of full scale (1.0: saturated), quantized to the bit depth.
    camera : Camera
    sensor : SensorGeometry
        The imaging geometry (:meth:`Camera.imaging_sensor`): triangulates the measured rows.
    material : Material
    window : (row0, row1, col0, col1)
        Where the image lies in the full chip grid.
    truth_row : (columns,) float
        Per column, the sub-pixel row where the ideal stripe (laser plane x_L = 0 on the part,
        lit and seen) images; NaN where the column sees none. Where a column sees the stripe
        twice (a step), the nearer one.
    reflection : (columns,) bool
        The column shows a false stripe (the laser's first specular bounce lighting the part
        elsewhere) brighter than 1 % of the exposure level.
    reflection_row : (columns,) float
        Sub-pixel row of that false stripe's centre (its intensity-weighted mean); NaN where none.
    T_world_sensor : (4, 4) float or None
    t_s : float
        Capture time.
    exposure : float
        The exposure this frame was taken at (multiple exposure: the longest of the set).
    column_exposure : (columns,) float or None
        Multiple exposure: the exposure each column's pixels come from; None otherwise.
    """

    pixels: NDArray[np.float32]
    camera: Camera
    sensor: SensorGeometry
    material: Material
    window: tuple[int, int, int, int]
    truth_row: FloatArray
    reflection: NDArray[np.bool_]
    reflection_row: FloatArray
    T_world_sensor: FloatArray | None = None
    t_s: float = float("nan")
    exposure: float = float("nan")
    column_exposure: FloatArray | None = None

    @property
    def peak(self) -> float:
        """The brightest pixel, a fraction of full scale (what auto-exposure reads)."""
        return float(self.pixels.max()) if self.pixels.size else 0.0

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns)."""
        return int(self.pixels.shape[0]), int(self.pixels.shape[1])

    def chip_coordinates(self, rows: Any, columns: Any) -> tuple[FloatArray, FloatArray]:
        """(x_c, z_c) in mm of sub-pixel image coordinates (arrays broadcast)."""
        r0, _, c0, _ = self.window
        pitch_h, pitch_v = self.sensor.pixel_pitch_mm
        half_h, half_v = 0.5 * self.sensor.chip_h_mm, 0.5 * self.sensor.chip_v_mm
        x_c = (r0 + np.asarray(rows, dtype=np.float64) + 0.5) * pitch_h - half_h
        z_c = (c0 + np.asarray(columns, dtype=np.float64) + 0.5) * pitch_v - half_v
        return x_c, z_c

    def triangulate_rows(self, rows: Any) -> FloatArray:
        """(columns, 2) (y_L, z_L) of one sub-pixel row per column (NaN stays NaN)."""
        r = np.asarray(rows, dtype=np.float64)
        x_c, z_c = self.chip_coordinates(r, np.arange(len(r)))
        y, z = self.sensor.triangulate(x_c, z_c)
        return np.column_stack([y, z])

    @property
    def truth_laser(self) -> FloatArray:
        """(columns, 2) the ideal stripe points (y_L, z_L) per column; NaN where none."""
        return self.triangulate_rows(self.truth_row)

    def profile(self, method: str = "centroid", **detector: Any) -> Profile:
        """The stripe profile measured from the pixels, as ``scan()`` gives it: the rows
        :func:`seamtrack.sensing.peaks.detect` finds (``method`` and the other ``detector``
        keywords as it takes them: ``threshold``, ``choose``, ``sigma_px``, ``relative``,
        ``noise_sigmas``, ``reject``) through :meth:`profile_from_rows`.

        Returns
        -------
        Profile
            One point (y_L, z_L) per image column, in column order (y_L increasing); columns
            without a peak are invalid with ``Reason.DROPOUT``.
        """
        from seamtrack.sensing.peaks import detect

        return self.profile_from_rows(detect(self.pixels, method=method, **detector))

    def profile_from_rows(self, rows: FloatArray) -> Profile:
        """A :class:`Profile` of one sub-pixel row per column (NaN: no peak there)."""
        from seamtrack.sensing.profiles import Reason

        points = self.triangulate_rows(rows)
        found = np.isfinite(points[:, 0]) & np.isfinite(points[:, 1])
        reason = np.where(found, Reason.VALID, Reason.DROPOUT).astype(np.uint8)
        return Profile._trusted(points, reason, self.T_world_sensor, self.t_s)
