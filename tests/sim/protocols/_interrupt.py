"""Interrupt a laboratory test the two ways a real run ends early (tests only)."""
from __future__ import annotations


def kill_after_partial_writes(monkeypatch, n):
    """Make the n-th periodic partial write (status running) end the run like SIGKILL: the
    files are written, then SystemExit, so no Ctrl-C handler writes anything more.
    Returns the list of step counts written and the original ``TestResult.write``."""
    from sim.protocols.report import TestResult
    orig, calls = TestResult.write, []

    def write(self, out, **kw):
        files = orig(self, out, **kw)
        if self.summary["status"] == "running":
            calls.append(self.summary["steps"])
            if len(calls) == n:
                raise SystemExit("killed")
        return files

    monkeypatch.setattr(TestResult, "write", write)
    return calls, orig


def ctrl_c_at_step(monkeypatch, step):
    """Make ``Simulation.cycle`` raise KeyboardInterrupt once, before the first chunk that
    starts at or after engine step ``step`` (a Ctrl-C between two records). Returns the list
    of steps at which it fired and the original ``Simulation.cycle``."""
    from sim.simulation import Simulation
    orig, fired = Simulation.cycle, []

    def cycle(self, n, **kw):
        if self.step >= step and not fired:
            fired.append(int(self.step))
            raise KeyboardInterrupt
        return orig(self, n, **kw)

    monkeypatch.setattr(Simulation, "cycle", cycle)
    return fired, orig
