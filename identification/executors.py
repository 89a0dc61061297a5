"""Where a batch's jobs run: this machine's process pool or a Dask distributed cluster, behind one interface.

An executor is a context manager with ``map_unordered(fn, jobs)``, which yields
``fn(job)`` for every job as the results come in (in any order).  A job and its
result must be picklable; on a cluster, the recordings and the output folder
must be reachable under the same paths from every worker (a shared file
system), as the jobs read the recording and write the FMUs themselves.
"""

from __future__ import annotations

import threading

from .errors import InputError

__all__ = ["LocalExecutor", "DaskExecutor", "executor_for", "ProgressBar", "one_at_a_time"]


class LocalExecutor:
    """`workers` processes on this machine (:func:`identification.workers.process_pool`), or this process
    alone for one worker."""

    def __init__(self, workers: int):
        self.workers = max(1, int(workers))
        self._pool = None

    def __enter__(self):
        from .workers import process_pool
        self._pool = process_pool(self.workers)
        return self

    def __exit__(self, exc_type, exc, tb):
        from .workers import stop_pool
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown()
            else:                         # interrupted: stop the workers now, not after their jobs
                stop_pool(self._pool)
        self._pool = None
        return False

    def map_unordered(self, fn, jobs):
        if self._pool is None:
            yield from map(fn, jobs)
            return
        from concurrent.futures import as_completed
        futures = [self._pool.submit(fn, job) for job in jobs]
        for future in as_completed(futures):
            yield future.result()


_SCHEMES = ("tcp", "tls", "ws", "wss", "inproc", "ucx")


#: Seconds to wait for a Dask scheduler before a run is refused (``--scheduler``).
CONNECT_TIMEOUT_S = 10.0


class DaskExecutor:
    """The workers of a Dask distributed scheduler at `address` (e.g. ``tcp://10.0.0.5:8786``).

    Parameters
    ----------
    address : str
        The scheduler's address.
    timeout_s : float, optional
        Seconds to wait for it (default :data:`CONNECT_TIMEOUT_S`).
    """

    def __init__(self, address: str, *, timeout_s: float | None = None):
        self.address = address
        self.timeout_s = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
        self._client = None

    def __enter__(self):
        try:
            from distributed import Client
        except ImportError:
            raise InputError("--scheduler", "needs the 'distributed' package (pip install 'cleatfmu[cluster]')") \
                from None
        scheme = self.address.split("://", 1)[0] if "://" in self.address else "tcp"
        if scheme not in _SCHEMES or not self.address.strip():
            raise InputError("--scheduler", f"{self.address!r} is not a Dask scheduler address "
                                            f"(e.g. tcp://host:8786; schemes: {', '.join(_SCHEMES)})")
        try:
            self._client = Client(self.address, timeout=self.timeout_s, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError("--scheduler", f"cannot reach the Dask scheduler at {self.address!r}: "
                                            f"{exc.__class__.__name__}: {exc}") from None
        return self

    def __exit__(self, exc_type, exc, tb):
        if self._client is not None:
            self._client.close()
        self._client = None
        return False

    def map_unordered(self, fn, jobs):
        from functools import partial

        from distributed import as_completed
        futures = self._client.map(partial(one_at_a_time, fn), list(jobs), pure=False)
        for future in as_completed(futures, loop=self._client.loop):
            result = future.result()
            future.release()          # the cluster forgets each result once the parent has it
            yield result


_JOB_LOCK = threading.Lock()


def one_at_a_time(fn, job):
    """``fn(job)``, one job at a time in this process whatever the threads of the Dask worker running it.

    The jobs compile and step numba code and draw with matplotlib, which are not safe side by side in the
    threads of one process: on CPython 3.11 a thread parsing source (numba's lowering) while another does
    (matplotlib's or Dask's settings) fails with ``SystemError: AST constructor recursion depth mismatch``
    (seen in CI on a worker of two threads).  The jobs hold the GIL, so the threads gained little; give a
    worker processes (``dask worker --nworkers N --nthreads 1``) to run jobs side by side.
    """
    with _JOB_LOCK:
        return fn(job)


def executor_for(workers: int | None, scheduler: str | None = None):
    """A :class:`DaskExecutor` for `scheduler`, else a :class:`LocalExecutor` of `workers` processes."""
    if scheduler:
        return DaskExecutor(scheduler)
    import os
    return LocalExecutor(workers or os.cpu_count() or 1)


class ProgressBar:
    """A batch's progress bar on stderr (tqdm, on a terminal only), drawn at once and redrawn every `every` s.

    Its elapsed time moves from the first second, before the first result arrives (a recording's diagnosis
    takes several seconds).  Use as ``with ProgressBar(n) as bar: ... bar.update(1)``.

    Parameters
    ----------
    total : int
        Number of jobs.
    enabled : bool
        False: no bar at all.
    every : float
        Redraw interval, s.
    """

    def __init__(self, total: int, *, enabled: bool = True, every: float = 1.0):
        import threading
        from tqdm import tqdm
        self.bar = tqdm(total=total, desc="cleatfmu", unit="job", disable=None if enabled else True)
        self.every = every
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._redraw, name="cleatfmu-progress", daemon=True)

    def _redraw(self) -> None:
        while not self._stop.wait(self.every):
            self.bar.refresh()

    def __enter__(self):
        self._thread.start()
        return self.bar

    def __exit__(self, exc_type, exc, tb) -> bool:
        self._stop.set()
        self._thread.join()
        self.bar.close()
        return False
