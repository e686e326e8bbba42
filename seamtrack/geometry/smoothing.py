"""Smoothing along a seam's stations: a running median over a window of stations, the robust
smoother for measurements taken station by station (a multi-pass job's measured grooves, a
planner's offsets), where one bad frame must not pull its neighbours."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def station_median(values: Any, half_window: int = 4, cut_ends: bool = False) -> FloatArray:
    """A running median along the stations (axis 0) over 2 * half_window + 1 of them; at the
    ends over the end station repeated, or with ``cut_ends`` over the stations there are."""
    v = np.asarray(values, dtype=float)
    pad = ((half_window, half_window),) + ((0, 0),) * (v.ndim - 1)
    if cut_ends:
        padded = np.pad(v, pad, constant_values=np.nan)
    else:
        padded = np.pad(v, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half_window + 1, axis=0)
    return np.asarray((np.nanmedian if cut_ends else np.median)(windows, axis=-1))
