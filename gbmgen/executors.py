"""Where the runs of a sweep are computed: this process, a local process pool, or an existing
Dask distributed cluster.

Each executor takes run payloads (plain data) and yields outcomes of
:func:`gbmgen.sweep_run.execute_run` as they finish, in any order. An outcome that the
executor itself lost (a worker process killed, a cluster connection dropped) comes back as
``{"lost": run_id, "error": text}``: the run is not recorded and is computed again on the
next start. :meth:`abort` stops at once (Ctrl-C): queued runs are cancelled and the running
ones ended, so that nothing more is written.
"""
from __future__ import annotations

import os
import signal

from .errors import InputError
from .sweep_run import execute_run

__all__ = ["InlineExecutor", "PoolExecutor", "DaskExecutor", "make_executor", "default_workers"]


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:           # pragma: no cover (not Linux)
        return os.cpu_count() or 1


class InlineExecutor:
    """Runs one after the other in this process (``--workers 0``: debugging, profiling)."""

    name = "inline"

    def run(self, payloads):
        for p in payloads:
            yield execute_run(p)

    def abort(self):
        pass

    def close(self):
        pass


def _worker_init():
    """Pool workers leave Ctrl-C to the sweep (which ends them) and use one numba thread."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")


class PoolExecutor:
    """A pool of ``workers`` fresh processes (spawned, so nothing of this process is shared)."""

    name = "process pool"

    def __init__(self, workers: int):
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor
        self.workers = int(workers)
        self._before = set(mp.active_children())
        self._pool = ProcessPoolExecutor(self.workers, mp_context=mp.get_context("spawn"),
                                         initializer=_worker_init)

    def run(self, payloads):
        from concurrent.futures import as_completed
        futures = {self._pool.submit(execute_run, p): p["run_id"] for p in payloads}
        for fut in as_completed(futures):
            try:
                yield fut.result()
            except Exception as exc:             # a worker died: BrokenProcessPool
                yield {"lost": futures[fut], "error": f"{type(exc).__name__}: {exc}"}

    def abort(self):
        import multiprocessing as mp
        self._pool.shutdown(wait=False, cancel_futures=True)
        for p in set(mp.active_children()) - self._before:   # our workers only
            p.terminate()
        self._pool.shutdown(wait=True)

    def close(self):
        self._pool.shutdown(wait=True)


class DaskExecutor:
    """The workers of an existing Dask distributed cluster at ``address`` (tcp://HOST:PORT).

    A worker needs only this package installed (no shared folder: files travel back as
    bytes). Start workers with ``--nthreads 1`` for one run per process.
    """

    name = "dask"

    def __init__(self, address: str, *, timeout: float = 30.0):
        try:
            from distributed import Client
        except ImportError:
            raise InputError("--scheduler: needs dask distributed (pip install "
                             "'rockkit[sweep]')") from None
        try:
            self._client = Client(address, timeout=timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"--scheduler {address}: cannot connect "
                             f"({' '.join(str(exc).split())})") from None
        self._futures = {}

    def run(self, payloads):
        import uuid

        from distributed import as_completed
        tag = uuid.uuid4().hex[:8]
        self._futures = {self._client.submit(execute_run, p, pure=False,
                                             key=f"rockkit-run-{p['run_id']}-{tag}"):
                         p["run_id"] for p in payloads}
        for fut in as_completed(list(self._futures)):
            try:
                yield fut.result()
            except Exception as exc:             # KilledWorker, lost connection
                yield {"lost": self._futures[fut], "error": f"{type(exc).__name__}: {exc}"}
            fut.release()

    def abort(self):
        try:
            self._client.cancel(list(self._futures), force=True)
        finally:
            self._client.close()

    def close(self):
        self._client.close()


def make_executor(*, workers=None, scheduler=None):
    """The executor for ``--workers N`` (default all cores; 0: in this process) or
    ``--scheduler tcp://HOST:PORT``."""
    if scheduler:
        return DaskExecutor(scheduler)
    n = default_workers() if workers is None else int(workers)
    if n < 0:
        raise InputError(f"--workers {n}: expected a whole number >= 0")
    return InlineExecutor() if n == 0 else PoolExecutor(n)
