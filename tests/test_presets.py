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
