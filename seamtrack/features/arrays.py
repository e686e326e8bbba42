"""The array types the feature extractors annotate with, defined once for all of ``features/``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Coordinates, fits, any float data.
FloatArray = NDArray[np.float64]
#: Integers the compiled kernels write (int64).
IntArray = NDArray[np.int64]
#: Positions into arrays (numpy's index type, ``np.intp``).
IndexArray = NDArray[np.intp]
