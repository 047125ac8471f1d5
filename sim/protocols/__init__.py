"""Laboratory test protocols built on :class:`sim.simulation.Simulation` (issue #6).

Modules (imported lazily by their users; importing this package does nothing):

- :mod:`~sim.protocols.ucs`, :mod:`~sim.protocols.tension`, :mod:`~sim.protocols.brazilian`,
  :mod:`~sim.protocols.biaxial`: ``run_ucs``, ``run_tension``, ``run_brazilian``,
  ``run_biaxial`` -> :class:`~sim.protocols.report.TestResult`;
- :mod:`~sim.protocols.loading`: platens, gauges, crack tallies, the loading loop, defaults;
- :mod:`~sim.protocols.resume`: continue an interrupted test from its results directory;
- :mod:`~sim.protocols.ensemble`: ``run_ensemble``, N perturbed runs of one test, mean ± sd;
- :mod:`~sim.protocols.outputs`: summary.json, history.csv, cracks.csv, figures (atomic);
- :mod:`~sim.protocols.parameters`: micro-parameter YAML files;
- :mod:`~sim.protocols.calibration`: the DEM black box of :func:`sim.calibrate.calibrate`;
- :mod:`~sim.protocols.cli`: ``register(subparsers)`` for ``gbmsim``.

See ``docs/labtests.md``.
"""
