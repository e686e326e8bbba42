"""Real sensor presets from data sheets: the geometry solved from each reproduces the sheet's
range and field through Eq. 4-8, the derived angle meets its stated condition, every figure
that is not the sheet's says so, and the command line lists them with their sources."""

from __future__ import annotations

import dataclasses
import json

import pytest
from cli_helpers import run_cli

from seamtrack.sensing.presets import DATA_SHEETS, DataSheet
from seamtrack.sensing.sensor import PRESET_SPECS, angle_for_standoff, preset, preset_source
from seamtrack.simulation.scene import load_scene, make_camera

SHEETS = sorted(DATA_SHEETS)


def test_at_least_six_real_sensors_each_naming_its_document() -> None:
    assert len({(s.make, s.model) for s in DATA_SHEETS.values()}) >= 6
    for name, sheet in DATA_SHEETS.items():
        assert name in PRESET_SPECS
        assert "data sheet" in sheet.source or "specifications" in sheet.source
        assert preset_source(name) == sheet.source


@pytest.mark.parametrize("name", SHEETS)
def test_eq4_to_eq8_reproduce_the_data_sheet(name: str) -> None:
    sheet, sensor = DATA_SHEETS[name], preset(name)
    assert sensor.depth_of_field_mm == pytest.approx(sheet.range_mm, rel=1e-9)
    assert sensor.fov_near_mm == pytest.approx(sheet.fov_near_mm, rel=1e-9)
    assert sensor.fov_far_mm == pytest.approx(sheet.fov_far_mm, rel=1e-9)
    assert sensor.standoff_mm == sheet.clearance_mm
    if sheet.points_per_profile is not None:
        assert sensor.pixels_v == sheet.points_per_profile


#: The documents' own figures, typed in from the text we read (not from DATA_SHEETS): clearance
#: (start of the range) CD, range MR, field near and far, points per profile, rate, wavelength.
SHEET_ORACLE = {
    # Cognex DS900 Series Displacement Sensors Reference, "DS910B/DS925B - Measurement
    # Specifications", "Sensor Specifications" (up to 1.2 kHz, 405 nm), "Technical Data" (1280).
    "cognex-ds910b": (53.0, 8.0, 9.4, 10.7, 1280, 1200.0, 405.0),
    "cognex-ds925b": (53.5, 25.0, 23.4, 29.1, 1280, 1200.0, 405.0),
    # LMI DATASHEET_Gocator_2600_US-1.4: 2690 CD 325, MR 1550, FOV 385-2000, 3700 points,
    # 900-10000 Hz, 660 nm.
    "gocator-2690": (325.0, 1550.0, 385.0, 2000.0, 3700, 10_000.0, 660.0),
    # SICK TriSpector1000 data sheet part 1060428, as quoted: working range 291-1091 mm, field
    # "540 x 200 mm" (read near 200, far 540), 0.43 mm/px (so 861 points), 5 kHz, no wavelength.
    "sick-trispector1060": (291.0, 800.0, 200.0, 540.0, 861, 5000.0, None),
}


@pytest.mark.parametrize("name", sorted(SHEET_ORACLE))
def test_solved_geometry_reproduces_the_documents_figures(name: str) -> None:
    cd, mr, near, far, points, rate, wavelength = SHEET_ORACLE[name]
    sensor, sheet = preset(name), DATA_SHEETS[name]
    assert sensor.range_near_mm == pytest.approx(cd, abs=0.01)
    assert sensor.range_far_mm - sensor.range_near_mm == pytest.approx(mr, rel=1e-9)
    assert sensor.depth_of_field_mm == pytest.approx(mr, rel=1e-9)
    assert sensor.fov_near_mm == pytest.approx(near, rel=1e-9)
    assert sensor.fov_far_mm == pytest.approx(far, rel=1e-9)
    assert sensor.pixels_v == points
    assert (sheet.profile_rate_hz, sheet.wavelength_nm) == (rate, wavelength)


def test_cognex_resolution_x_brackets_the_mean_point_step() -> None:
    """The lateral step is derived from the 1280 points; it must lie in the sheet's range."""
    for name, (lo, hi) in {"cognex-ds910b": (0.0073, 0.0084),
                           "cognex-ds925b": (0.0183, 0.0227)}.items():  # fmt: skip
        step = DATA_SHEETS[name].lateral_resolution_mm
        assert lo <= step <= hi
        assert "lateral_resolution_mm" in DATA_SHEETS[name].assumed


def test_trispector_field_reading_is_marked_assumed() -> None:
    """The quoted "540 x 200 mm" does not say which width is near: both are flagged."""
    assumed = DATA_SHEETS["sick-trispector1060"].assumed
    assert {"fov_near_mm", "fov_far_mm"} <= set(assumed)
    assert DATA_SHEETS["sick-trispector1060"].wavelength_nm is None


@pytest.mark.parametrize("name", SHEETS)
def test_derived_angle_puts_the_range_at_the_clearance(name: str) -> None:
    """The one derived geometric figure: solved again here, and its condition checked."""
    sheet = DATA_SHEETS[name]
    assert "angle_deg" in sheet.assumed
    angle = angle_for_standoff(sheet.range_mm, sheet.fov_near_mm, sheet.fov_far_mm,
                               sheet.clearance_mm)  # fmt: skip
    assert angle == pytest.approx(sheet.angle_deg, abs=1e-3)
    assert preset(name).range_near_mm == pytest.approx(sheet.clearance_mm, abs=0.01)


def test_assumed_figures_name_real_fields() -> None:
    fields = {f.name for f in dataclasses.fields(DataSheet)}
    for sheet in DATA_SHEETS.values():
        assert set(sheet.assumed) <= fields and all(sheet.assumed.values())


def test_image_mode_takes_the_lasers_wavelength_from_the_data_sheet() -> None:
    assert make_camera(None, "keyence-lj-x8400").wavelength_nm == 405.0
    assert make_camera(None, "gocator-2330").wavelength_nm == 660.0
    scene = load_scene("paper-verification", {"sensor.preset": "gocator-2330"})
    assert scene.config.sensor.preset == "gocator-2330"


def test_cli_lists_the_presets_with_their_sources() -> None:
    listing = run_cli("sensor", "--list").stdout
    for name, sheet in DATA_SHEETS.items():
        assert name in listing and sheet.model in listing
    assert listing.count("source: ") == len(DATA_SHEETS)
    res = run_cli("sensor", "--preset", "keyence-lj-x8400", "--json")
    data = json.loads(res.stdout)
    assert "keyence.com" in data["source"] and "angle_deg" in data["assumed"]
    text = run_cli("sensor", "--preset", "gocator-2350").stdout
    assert "assumed or derived" in text and "angle_deg*" in text and "source: LMI" in text
    text = run_cli("sensor", "--preset", "cognex-ds925b").stdout
    assert "source: Cognex, DS900 Series" in text and "resolution_z_mm" in text
    assert "cognex-ds910b" in listing and "Cognex DS910B" in listing
