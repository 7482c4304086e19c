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
