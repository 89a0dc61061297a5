"""How long a block spent compiling the model's code (numba's compile events), so that run times can be
told apart from the once-per-install compilation (:func:`compile_seconds`)."""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["compile_seconds"]


class _Clock:
    seconds = 0.0


@contextmanager
def compile_seconds():
    """Measure the compilation inside the block: ``with compile_seconds() as c: ...; c.seconds``.

    Only numba's outermost compile events count (a function compiled while compiling another is inside
    its time).  Loading compiled code from numba's on-disk cache is not compilation and counts 0; so does
    everything without numba.
    """
    clock = _Clock()
    try:
        from numba.core import event
    except ImportError:   # pragma: no cover - without numba nothing is compiled
        yield clock
        return
    with event.install_recorder("numba:compile") as recorder:
        try:
            yield clock
        finally:
            depth, start = 0, 0.0
            for stamp, ev in recorder.buffer:
                if ev.is_start:
                    if depth == 0:
                        start = stamp
                    depth += 1
                elif depth:
                    depth -= 1
                    if depth == 0:
                        clock.seconds += stamp - start
