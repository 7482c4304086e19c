from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import helpers  # noqa: E402


@pytest.fixture(scope="session")
def checker():
    """The independent trajectory checker from ../shared/tools (skipped where absent)."""
    if not helpers.CHECKER.is_file():
        pytest.skip(helpers.SHARED_MISSING)
    pytest.importorskip("fcl", reason="the checker needs python-fcl (pip install python-fcl)")
    return helpers.load_checker()


@pytest.fixture(scope="session")
def hand():
    """The paper's hand: 5 fingers x 5 links of 2 cm, link radius 4 mm, palm radius 3 cm."""
    import hugger

    return hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)


@pytest.fixture(scope="session")
def sphere():
    """A 4 cm sphere of 1280 triangles (test files may override it)."""
    import hugger

    return hugger.objects.sphere(radius=0.04, subdivisions=3)


@pytest.fixture(scope="session")
def fine_sphere():
    """A 4 cm sphere of 5120 triangles: the finer mesh of the API tests of the world, planner and files."""
    import hugger

    return hugger.objects.sphere(radius=0.04, subdivisions=4)
