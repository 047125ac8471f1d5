"""Shared test set-up: the helper modules of tests/sim are importable by name."""
import pathlib
import sys

import numpy as np
import pytest

_SIM_TESTS = str(pathlib.Path(__file__).resolve().parent / "sim")
if _SIM_TESTS not in sys.path:
    sys.path.insert(0, _SIM_TESTS)


@pytest.fixture
def rng():
    """A seeded generator (same seed, same test data)."""
    return np.random.default_rng(12345)
