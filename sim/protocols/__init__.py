"""Laboratory and field test protocols built on :class:`sim.simulation.Simulation`."""
