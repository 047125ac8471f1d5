"""Subcommands of ``gbmsim`` for the test protocols (ucs, tension, brazilian, biaxial, calibrate).

``sim.cli`` calls :func:`register` with its argparse subparsers object.
"""


def register(subparsers):
    """Add the protocol subcommands to ``subparsers`` (filled in by the lab-test work)."""
    return subparsers
