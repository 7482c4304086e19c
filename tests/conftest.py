from __future__ import annotations

import signal
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

# A suite started with SIGINT ignored (`make test &` from a script, nohup) would keep it ignored
# here and in every child process, where Python then installs no handler of its own: the Ctrl-C
# tests need SIGINT as a terminal delivers it. (A handler set here is reset to the default in a
# child at exec, so the children get Python's own again.)
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

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


@pytest.fixture(scope="session")
def sphere_plan(hand, sphere):
    """The paper's hand around ``sphere`` from 20 cm above (helpers.start()), done: palm and many
    links touch, a cage."""
    return helpers.sphere_grasp(hand, sphere)


@pytest.fixture(scope="session")
def fine_sphere_plan(hand, fine_sphere):
    """The same grasp of ``fine_sphere``: the reference plan of the analysis tests."""
    return helpers.sphere_grasp(hand, fine_sphere)
