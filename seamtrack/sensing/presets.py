"""Data sheets of real laser profile sensors, as presets (``preset("gocator-2330")``).

Each :class:`DataSheet` holds the published figures and names the document they come from; a
figure the sources do not give is listed in ``assumed`` with the reason. The figures were read
from the sources as quoted (their URLs are in ``source``); where we could only read a public
transcription of a data sheet, ``source`` says so. Nothing here imports the sensor model:
:func:`seamtrack.sensing.sensor.preset` solves the geometry from these specs.

Two modelling choices apply to all of them (stated in ``assumed``):

- The paper's model (Eq. 1-8) needs the triangulation angle, which these data sheets do not
  give. It is derived instead: the angle at which the near end of the measuring range lies at
  the data sheet's clearance distance from the emitter (the emitter taken at the window).
  ``seamtrack.sensing.sensor.angle_for_standoff`` solves it; a test checks each value.
- R_D = D / N_H is a pixel step in Eq. 7, not the sub-pixel "Z resolution" of a data sheet; we
  take N_H = 1024 camera rows across the range.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

#: Camera rows assumed across the measuring range (R_D = D / ASSUMED_ROWS).
ASSUMED_ROWS = 1024

_LMI_2300 = (
    "LMI Technologies, Gocator 2300 Series data sheet (DATASHEET_Gocator_2300_US_WEB.pdf, "
    "lmi3d.com), p. 2: clearance distance CD, measurement range MR, field of view near/far "
    "(read as transcribed in two independent public hardware catalogues); standard laser "
    "660 nm (LMI's Gocator 2300 Series specification page)"
)
_LMI_2300_NOTE = (
    "; X resolution, Z repeatability and scan rate as quoted from the same data sheet "
    "(lakewoodautomation.com/support/manuals/LMI/DATASHEET_Gocator_2300_US_WEB.pdf) in a "
    "public engineering note"
)
_KEYENCE_LJX = (
    "Keyence LJ-X8000 Series specifications (keyence.com/products/measure/laser-2d/lj-x8000/"
    "specs/): reference distance 380 mm, +-60 mm, X range 180-240 mm, repeatability 5 um, "
    "16 kHz, as quoted in a public engineering note; 405 nm (blue) throughout the series"
)
_COGNEX_DS900 = (
    "Cognex, DS900 Series Displacement Sensors Reference (copyright 2015, revision "
    "02/06/2017), its specifications tables 'DS910B - Measurement Specifications' and "
    "'DS925B - Measurement Specifications' (near and far field of view, clearance distance "
    "CD, measurement range MR, resolution X and Z), 'Sensor Specifications' (scan rate up to "
    "1.2 kHz, 405 nm laser) and 'Series Technical Data' (1280 points/profile); read as a "
    "Markdown transcription of the manual in a public GitHub repository (our code index "
    "returned the file, not its repository name)"
)
_LMI_2600 = (
    "LMI Technologies, Gocator 2600 Series data sheet DATASHEET_Gocator_2600_US-1.4 (2023; "
    "ftp.stemmer-imaging.com/webdavs/docmanager/166909-DATASHEET_Gocator_2600.pdf): 2690 "
    "clearance distance, measurement range, field of view, data points/profile, scan rate, "
    "repeatability Z, 660 nm; read as transcribed in a public engineering note"
)
_SICK_TRISPECTOR = (
    "SICK TriSpector1000 data sheet, part 1060428 (V3T13S-MR62A8; sick.com/media/pdf/5/45/145/"
    "dataSheet_V3T13S-MR62A8_1060428_en.pdf): working range 291-1091 mm, field of view "
    "'540 x 200 mm', X resolution 0.43 mm/px, 5 kHz; as quoted in a public engineering note "
    "(the one the Gocator 2350/2380 and LJ-X8400 figures come from)"
)
_DS900_ROWS = (
    "not given: 1024 camera rows across the measuring range (the DS900 image matrix has "
    "1280 x 1024 pixels; its rows are assumed to span the range)"
)
_ANGLE = "derived: the near end of the range at the clearance distance from the emitter"
_ROWS = f"not given: {ASSUMED_ROWS} camera rows across the measuring range"


@dataclass(frozen=True)
class DataSheet:
    """Published figures of one sensor model (mm, Hz, nm).

    Attributes
    ----------
    make, model, source : str
    clearance_mm : float
        From the sensor's front to the near end of the measuring range.
    range_mm : float
        The measuring range (depth of field) D.
    fov_near_mm, fov_far_mm : float
        Width of the laser line's measured field at the near and far ends.
    angle_deg : float
        Triangulation angle (derived where the data sheet gives none; see ``assumed``).
    depth_resolution_mm, lateral_resolution_mm : float
        R_D and R_L of Eq. 7-8 (average step per camera row / column).
    points_per_profile : int or None
    profile_rate_hz : float or None
        The highest profile rate published.
    repeatability_z_mm : float or None
    resolution_z_mm : float or None
        The sheet's Z resolution (not Eq. 7's R_D), where it gives one.
    wavelength_nm : float or None
    assumed : dict of str to str
        Field -> why it is not the data sheet's figure.
    """

    make: str
    model: str
    source: str
    clearance_mm: float
    range_mm: float
    fov_near_mm: float
    fov_far_mm: float
    angle_deg: float
    depth_resolution_mm: float
    lateral_resolution_mm: float
    points_per_profile: int | None = None
    profile_rate_hz: float | None = None
    repeatability_z_mm: float | None = None
    resolution_z_mm: float | None = None
    wavelength_nm: float | None = None
    assumed: dict[str, str] = field(default_factory=dict)

    def specs(self) -> dict[str, float]:
        """The specs ``LaserLineSensor.from_specs`` takes (and the stand-off)."""
        return {
            "standoff_mm": self.clearance_mm,
            "depth_of_field_mm": self.range_mm,
            "fov_near_mm": self.fov_near_mm,
            "fov_far_mm": self.fov_far_mm,
            "angle_deg": self.angle_deg,
            "depth_resolution_mm": self.depth_resolution_mm,
            "lateral_resolution_mm": self.lateral_resolution_mm,
        }


def _sheet(
    make: str,
    model: str,
    source: str,
    geometry: tuple[float, float, float, float, float],
    *,
    points: int | None = None,
    lateral_mm: float | None = None,
    rows: str = _ROWS,
    notes: dict[str, str] | None = None,
    **published: float | None,
) -> DataSheet:
    """A data sheet from its geometry ``(clearance, range, fov near, fov far, derived angle)``
    with the two modelling choices of the module docstring: R_D is the range over
    :data:`ASSUMED_ROWS` camera rows (``rows`` says why), and R_L, where the sheet gives no mean
    step ``lateral_mm``, is the near and far field's mean over ``points`` per profile.
    ``notes``: the other figures that are not the sheet's, and why; they and the two choices
    are listed in the order of the sheet's fields."""
    clearance, range_mm, near, far, angle = geometry
    if lateral_mm is None:
        if points is None:
            raise ValueError(f"{model}: give the points per profile or the mean step")
        lateral_mm = (near + far) / (2 * points)
    assumed = {"angle_deg": _ANGLE, "depth_resolution_mm": rows, **(notes or {})}
    order = [f.name for f in fields(DataSheet)]
    return DataSheet(
        make=make, model=model, source=source, clearance_mm=clearance, range_mm=range_mm,
        fov_near_mm=near, fov_far_mm=far, angle_deg=angle,
        depth_resolution_mm=range_mm / ASSUMED_ROWS, lateral_resolution_mm=lateral_mm,
        points_per_profile=points, assumed=dict(sorted(assumed.items(), key=lambda kv:
                                                       order.index(kv[0]))),
        **published,
    )  # fmt: skip


def _gocator(model: str, cd: float, mr: float, near: float, far: float, angle: float,
             x_res: tuple[float, float] | None = None, rate_hz: float | None = None,
             repeat_um: float | None = None) -> DataSheet:  # fmt: skip
    notes: dict[str, str] | None = None
    if x_res is None:
        points, lateral = 1280, None
        notes = {"lateral_resolution_mm": "not read: 1280 points per profile assumed",
                 "points_per_profile": "not read: 1280 assumed"}  # fmt: skip
    else:
        points, lateral = None, 0.5 * (x_res[0] + x_res[1])
    return _sheet(
        "LMI Technologies", f"Gocator {model}", _LMI_2300 + (_LMI_2300_NOTE if x_res else ""),
        (cd, mr, near, far, angle), points=points, lateral_mm=lateral, notes=notes,
        profile_rate_hz=rate_hz, wavelength_nm=660.0,
        repeatability_z_mm=None if repeat_um is None else repeat_um * 1e-3,
    )  # fmt: skip


def _cognex_ds900(model: str, cd: float, mr: float, near: float, far: float, angle: float,
                  res_x: tuple[float, float], res_z_mm: float) -> DataSheet:  # fmt: skip
    return _sheet(
        "Cognex", model, _COGNEX_DS900, (cd, mr, near, far, angle), points=1280,
        rows=_DS900_ROWS, profile_rate_hz=1200.0, resolution_z_mm=res_z_mm, wavelength_nm=405.0,
        notes={"lateral_resolution_mm": f"the 1280 points' mean step over the near and far "
               f"field (the sheet's Resolution X: {res_x[0]:g}-{res_x[1]:g} mm)"},
    )  # fmt: skip


#: The built-in real sensors (``seamtrack sensor --list``).
DATA_SHEETS: dict[str, DataSheet] = {
    "gocator-2320": _gocator("2320", 40.0, 25.0, 18.0, 26.0, 29.631),
    "gocator-2330": _gocator("2330", 90.0, 80.0, 47.0, 85.0, 15.366),
    "gocator-2340": _gocator("2340", 190.0, 210.0, 96.0, 194.0, 13.824),
    "gocator-2350": _gocator("2350", 300.0, 400.0, 158.0, 365.0, 6.411, x_res=(0.150, 0.300),
                             rate_hz=5000.0, repeat_um=2.0),
    "gocator-2380": _gocator("2380", 350.0, 800.0, 390.0, 1260.0, 7.207, x_res=(0.375, 1.100),
                             rate_hz=5000.0, repeat_um=12.0),
    "gocator-2690": _sheet(
        "LMI Technologies", "Gocator 2690", _LMI_2600, (325.0, 1550.0, 385.0, 2000.0, 15.544),
        points=3700, profile_rate_hz=10_000.0, repeatability_z_mm=0.012, wavelength_nm=660.0,
        notes={
            "lateral_resolution_mm": "the 3700 points' mean step over the near and far field "
            "(the sheet's Resolution X: 0.124-0.550 mm)",
            "profile_rate_hz": "10 kHz needs a reduced field and range; 900 Hz over the full "
            "field (the sheet's range 900-10000 Hz)",
        },
    ),
    "cognex-ds910b": _cognex_ds900("DS910B", 53.0, 8.0, 9.4, 10.7, 16.291,
                                   res_x=(0.0073, 0.0084), res_z_mm=0.001),
    "cognex-ds925b": _cognex_ds900("DS925B", 53.5, 25.0, 23.4, 29.1, 41.082,
                                   res_x=(0.0183, 0.0227), res_z_mm=0.002),
    "sick-trispector1060": _sheet(
        "SICK", "TriSpector1060", _SICK_TRISPECTOR, (291.0, 1091.0 - 291.0, 200.0, 540.0, 30.754),
        lateral_mm=0.43, profile_rate_hz=5000.0,
        notes={
            "fov_near_mm": "the note gives the field of view as '540 x 200 mm' without saying "
            "which width is where; read as 200 mm at the near end of the working range",
            "fov_far_mm": "read as 540 mm at the far end (see fov_near_mm)",
            "lateral_resolution_mm": "the sheet's 0.43 mm/px taken as the mean step over the "
            "field (861 points)",
        },
    ),
    "keyence-lj-x8400": _sheet(
        "Keyence", "LJ-X8400", _KEYENCE_LJX, (320.0, 120.0, 180.0, 240.0, 18.168), points=3200,
        profile_rate_hz=16_000.0, repeatability_z_mm=0.005, wavelength_nm=405.0,
        notes={
            "clearance_mm": "reference distance 380 mm minus half the +-60 mm range",
            "points_per_profile": "3200, the profile data count published for the LJ-X8020/"
            "8060/8080 heads of the series; not read for the 8400",
            "lateral_resolution_mm": "from the 3200 points per profile",
        },
    ),
}  # fmt: skip
