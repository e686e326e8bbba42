"""What a scene switches on against the arc (issue 38, docs/arc.md): blob and streak rejection
in the peak detector (``[sensor.camera]`` ``reject*``), resolved here from the scene's keys
into the objects the sensing stage takes.
"""

from __future__ import annotations

from seamtrack.sensing.peaks import Rejection
from seamtrack.simulation.config import SceneConfig


def rejection(config: SceneConfig) -> Rejection | None:
    """The peak detector's :class:`~seamtrack.sensing.peaks.Rejection`, or None (keep every
    run): ``sensor.camera.reject``, each unset bound the Rejection's default."""
    camera = config.sensor.camera
    if camera is None or (camera.reject or "none") == "none":
        return None
    defaults = Rejection()
    return Rejection(
        max_width=camera.reject_max_width or defaults.max_width,
        max_peak=camera.reject_max_peak or defaults.max_peak,
        min_peak=camera.reject_min_peak if camera.reject_min_peak is not None else 0.0,
        stripe_width_px=camera.reject_stripe_width_px,
    )
