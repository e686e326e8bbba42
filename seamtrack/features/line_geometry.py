"""The laser plane's geometry, once for every extractor: a point (:class:`Point`).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

from typing import NamedTuple


class Point(NamedTuple):
    """A point in the laser plane (y, z; mm)."""

    y: float
    z: float
