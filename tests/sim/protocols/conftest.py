"""Fixtures of the protocol tests."""
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))
from _specimens import random_specimen  # noqa: E402


@pytest.fixture(scope="module")
def rock():
    """~200-particle random bonded packing, 5 x 10 mm, breakable bonds."""
    return random_specimen(0.005, 0.010, 0.25e-3, seed=1)


@pytest.fixture
def gbmsim_parser():
    """The ``gbmsim`` argument parser with the protocol subcommands (as ``sim.cli`` builds it)."""
    import argparse

    from sim.protocols import cli
    parser = argparse.ArgumentParser(prog="gbmsim")
    cli.register(parser.add_subparsers(dest="command", required=True))
    return parser
