"""Shared fixtures: the paper's sensor and seam, and a CLI runner."""

from __future__ import annotations

import os

import pytest

import seamtrack as st
from seamtrack.sensing.sensor import preset

# The first-compile notice off for the whole suite (and the commands it starts): which test
# compiles a kernel first depends on the order the workers take them, and many check stderr.
# tests/test_compiling_notice.py turns it back on where it tests it.
os.environ["SEAMTRACK_COMPILE_NOTICE"] = "0"
# No warming child (seamtrack.features.warm) either: pytest-xdist's workers keep both cores busy,
# so a child compiling the extractor beside its worker has no free core and only doubles the
# work while the cache is cold. tests/test_warm.py tests the child itself.
os.environ["SEAMTRACK_PARALLEL_COMPILE"] = "0"


@pytest.fixture(scope="session")
def paper_sensor() -> st.LaserLineSensor:
    return preset("paper")


@pytest.fixture(scope="session")
def paper_seam() -> st.Seam:
    return st.Seam.from_paper()
