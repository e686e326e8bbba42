"""Shared fixtures: the paper's sensor and seam, and a CLI runner."""

from __future__ import annotations

import pytest

import seamtrack as st
from seamtrack.sensing.sensor import preset


@pytest.fixture(scope="session")
def paper_sensor() -> st.LaserLineSensor:
    return preset("paper")


@pytest.fixture(scope="session")
def paper_seam() -> st.Seam:
    return st.Seam.from_paper()
