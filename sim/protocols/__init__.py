"""Laboratory test protocols built on :class:`sim.simulation.Simulation`.

Modules (imported lazily by their users; importing this package does nothing):

- :mod:`~sim.protocols.registry`: ``TESTS`` (test name -> protocol) and ``run_test(name,
  specimen, out=..., **options)``, the one entry point;
- :mod:`~sim.protocols.options`: ``TestOptions``, the options every test shares;
- :mod:`~sim.protocols.skeleton`: the loading skeleton every test plugs into (``Protocol``,
  ``Rig``, ``run_loading``);
- :mod:`~sim.protocols.ucs`, :mod:`~sim.protocols.tension`, :mod:`~sim.protocols.brazilian`,
  :mod:`~sim.protocols.biaxial`: the tests (``run_ucs``, ... -> :class:`~sim.protocols.report
  .TestResult`);
- :mod:`~sim.protocols.speed`: default speeds, strain rate, adaptive platen speed;
- :mod:`~sim.protocols.loop`: the loading loop, stop rule, Ctrl-C and checkpoints;
- :mod:`~sim.protocols.rig`: specimen preparation, platens, engine readings;
- :mod:`~sim.protocols.gauges`, :mod:`~sim.protocols.elastic`: where strain and stress are read,
  E and ν with their validity;
- :mod:`~sim.protocols.representative`: the specimen-size rules;
- :mod:`~sim.protocols.resume`: continue an interrupted test from its results directory;
- :mod:`~sim.protocols.ensemble`: ``run_ensemble``, N perturbed runs of one test, mean ± sd;
- :mod:`~sim.protocols.outputs`, :mod:`~sim.protocols.report`: result files and summary;
- :mod:`~sim.protocols.parameters`: micro-parameter YAML files;
- :mod:`~sim.protocols.calibration`: the DEM black box of :func:`sim.calibrate.calibrate`;
- :mod:`~sim.protocols.cli`: ``register(subparsers)`` for ``gbmsim``.

See ``docs/labtests.md``.
"""
