"""What a scene switches on against the arc (issue 38, docs/arc.md), resolved from its keys into
the objects the stages take: the camera's band-pass filter and exposure control
(``[sensor.camera]`` ``filter_*``, ``exposure_mode``), blob and streak rejection in the peak
detector (``reject*``, :class:`~seamtrack.sensing.peaks.Rejection`) and the seam-point gate
with the tracker's behaviour on an invalid frame (``[gate]``,
:class:`~seamtrack.control.gate.GateSettings`).

The scene's one-word switch ``countermeasures`` sets them together: ``"default"`` what a
careful engineer would ship (a 10 nm band-pass on the laser's line, one fixed short exposure,
rejection on, the gate at the Riftek RF627Weld's factory settings, prediction on invalid
frames), ``"none"`` all off (no filter but the chip's own band, the camera's multiple exposure,
no rejection, no gate, hold). An explicit key overrides the switch. Unset, the switch is
``"default"`` in a scene with an ``[arc]`` and ``"none"`` without, so a scene without the arc
runs exactly as before (the filter acts on the arc's light only).
"""

from __future__ import annotations

from seamtrack.control.gate import (
    RF627WELD_INVALID_SEQUENCE,
    RF627WELD_SEARCH_DISTANCE_MM,
    GateSettings,
)
from seamtrack.sensing.arc.light import BandPass
from seamtrack.sensing.peaks import Rejection
from seamtrack.simulation.config import SceneConfig

#: The switch's values.
COUNTERMEASURES = ("none", "default")
#: The band-pass under ``"default"``: 10 nm FWHM, Gaussian, on the laser's line (a common
#: laser-line interference filter, e.g. Edmund Optics' and Thorlabs' 10 nm FWHM line filters).
DEFAULT_FILTER_FWHM_NM = 10.0
#: No filter (``"none"``): the chip's own band, flat, 400-1100 nm. Silicon absorbs nothing
#: beyond its band gap's 1,107 nm (1.12 eV at 300 K) and a CMOS chip's cover glass and colour-free
#: microlenses little below about 400 nm; its quantum efficiency falls from about 600 nm on, so
#: a flat band over-counts the arc's near-infrared light, by at most the QE's fall (about 2x).
CHIP_BAND_NM = (400.0, 1100.0)


def countermeasures(config: SceneConfig) -> str:
    """The scene's switch: its ``countermeasures``, else ``"default"`` with an ``[arc]``."""
    if config.countermeasures is not None:
        return config.countermeasures
    return "default" if config.arc is not None else "none"


def band_pass(config: SceneConfig, laser_nm: float) -> BandPass:
    """The camera's filter for the arc's light: ``[sensor.camera]`` ``filter_*`` where given,
    else the switch's (:data:`DEFAULT_FILTER_FWHM_NM` on the laser's line, or no filter:
    :data:`CHIP_BAND_NM` as a top-hat)."""
    c = config.sensor.camera
    centre = c.filter_centre_nm if c is not None else None
    width = c.filter_fwhm_nm if c is not None else None
    shape = c.filter_shape if c is not None else None
    if countermeasures(config) == "none" and width is None:
        low, high = CHIP_BAND_NM
        return BandPass(centre_nm=centre or 0.5 * (low + high), fwhm_nm=high - low,
                        shape=shape or "top-hat", peak=1.0)  # fmt: skip
    return BandPass(centre_nm=centre or laser_nm, fwhm_nm=width or DEFAULT_FILTER_FWHM_NM,
                    shape=shape or "gaussian")  # fmt: skip


def exposure_mode(config: SceneConfig) -> str:
    """The camera's exposure control: ``sensor.camera.exposure_mode`` where given, else
    ``"fixed"`` under ``"default"`` (under the arc, ``multi`` takes a column whose pixels the
    arc's glow fills at its shortest exposure, and the stripe falls below the threshold: the
    seam point missed by 1.2 mm in the median at 100 A and 10 mm, docs/arc.md) and the camera's
    own ``"multi"`` under ``"none"``."""
    c = config.sensor.camera
    if c is not None and c.exposure_mode is not None:
        return c.exposure_mode
    return "fixed" if countermeasures(config) == "default" else "multi"


def rejection(config: SceneConfig) -> Rejection | None:
    """The peak detector's :class:`~seamtrack.sensing.peaks.Rejection`, or None (keep every
    run): ``sensor.camera.reject`` (unset: ``"blobs"`` under ``"default"``), each unset bound
    the Rejection's default."""
    camera = config.sensor.camera
    default = "blobs" if countermeasures(config) == "default" else "none"
    if camera is None:
        return Rejection() if default == "blobs" else None
    if (camera.reject or default) == "none":
        return None
    defaults = Rejection()
    return Rejection(
        max_width=camera.reject_max_width or defaults.max_width,
        max_peak=camera.reject_max_peak or defaults.max_peak,
        min_peak=camera.reject_min_peak if camera.reject_min_peak is not None else 0.0,
        stripe_width_px=camera.reject_stripe_width_px,
    )


def gate_settings(config: SceneConfig) -> GateSettings | None:
    """The seam-point gate's settings, or None: no gate (``[gate] enabled``, unset on under
    ``"default"`` or when the table is given), or one that would change nothing (no window)."""
    switch = countermeasures(config)
    g = config.gate
    enabled = (
        g.enabled
        if g is not None and g.enabled is not None
        else (switch == "default" or g is not None)
    )
    if not enabled:
        return None
    window = RF627WELD_SEARCH_DISTANCE_MM if g is None or g.window_mm is None else g.window_mm
    reacquire = g.reacquire_frames if g is not None and g.reacquire_frames else None
    on_invalid = g.on_invalid if g is not None and g.on_invalid else None
    on_invalid = on_invalid or ("predict" if switch == "default" else "hold")
    if window == 0:
        return None
    return GateSettings(
        window_mm=window or None,
        reacquire_frames=reacquire or RF627WELD_INVALID_SEQUENCE,
        on_invalid=on_invalid,
    )


def describe(config: SceneConfig) -> str:
    """One line for ``seamtrack check``: the switch and what it resolved to."""
    reject, gate = rejection(config), gate_settings(config)
    parts = []
    if reject is not None:
        parts.append(f"reject blobs (width <= {reject.max_width:g}x, height <= "
                     f"{reject.max_peak:g}x the stripe's)")  # fmt: skip
    if gate is not None:
        parts.append(f"gate {gate.window_mm:g} mm, re-acquire after {gate.reacquire_frames} "
                     f"frames, {gate.on_invalid} on a refused frame")  # fmt: skip
    return f"{countermeasures(config)}: " + ("; ".join(parts) or "off")
