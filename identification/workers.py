"""Worker processes: one pool factory for every parallel stage, with workers that end with their parent.

A worker started by :func:`process_pool`

* holds BLAS to one thread (one worker per core: BLAS threads on top
  oversubscribe the cores, and a small matrix product then waits for a busy
  core; seen: 5 ms -> 0.5 s);
* ignores SIGINT: Ctrl-C reaches the whole foreground process group, and the
  parent alone decides (it stops the pool, :func:`stop_pool`, and exits 130);
  SIGTERM ends it (the default action, not the command's handler it was forked with);
* on Linux, is killed when its parent dies, SIGKILL included
  (``PR_SET_PDEATHSIG``), so no worker outlives a killed run.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["process_pool", "worker_init", "stop_pool", "one_blas_thread"]

_PR_SET_PDEATHSIG = 1


def worker_init(parent_pid: int | None = None) -> None:
    """Initializer of a pool's worker process (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)   # the parent's handler (raise where the command is) is not ours
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):   # pragma: no cover - no prctl: workers end with the pool only
            pass
        if parent_pid is not None and os.getppid() != parent_pid:   # the parent died before prctl
            os._exit(1)
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1, user_api="blas")


def one_blas_thread(fn):
    """Decorator: `fn` runs with BLAS held to one thread in this process (then restored).

    The fits multiply small matrices: BLAS threads gain nothing there and spin on the other core (seen:
    a whole-tractor diagnosis with one worker, 18 s of CPU alone and 25 s with two BLAS threads, the
    same wall time), and beside the pool's workers they oversubscribe the cores.
    """
    import functools

    @functools.wraps(fn)
    def held(*args, **kwargs):
        from threadpoolctl import threadpool_limits
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)
    return held


def process_pool(workers: int):
    """A fork-based ``ProcessPoolExecutor`` of `workers` processes started with :func:`worker_init`, or None
    when `workers` <= 1 or processes cannot be started here."""
    if workers <= 1:
        return None
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    try:
        return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"),
                                   initializer=worker_init, initargs=(os.getpid(),))
    except (ValueError, OSError):
        return None


def stop_pool(pool) -> None:
    """Stop a pool at once: pending jobs cancelled, running workers killed (an interrupted run)."""
    if pool is None:
        return
    processes = list(getattr(pool, "_processes", {}).values())   # the executor keeps no public handle
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.kill()
    for proc in processes:
        proc.join(timeout=1.0)
