"""A bounded memory of recent model predictions, so that a fit never runs the same model twice.

A diagnosis runs its models thousands of times, and one in eight or nine of those runs repeats one made
shortly before with the very same parameters (measured on the benchmark's recordings: a stiffness scan
that revisits its grid points, a timing refinement that scores its centre again, a fit's final prediction
at the optimum its solver already evaluated).  A prediction is a deterministic function of the model, the
step and the parameters, so the repeat can return the earlier arrays: the same bits, without the run.

The memory holds the most recent predictions up to a size in bytes (least recently used dropped first);
the arrays it returns are read-only, shared with every caller that asked for the same run.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict

import numpy as np

__all__ = ["PredictionMemo", "parameters_key"]


def parameters_key(theta: dict):
    """A hashable key of a parameter dict that tells apart every value the model could see differently
    (-0.0 from 0.0); None when some value cannot be a key (the run is then not remembered)."""
    items = []
    for name, value in theta.items():
        if isinstance(value, (float, np.floating)):
            value = float(value)
            items.append((name, value, math.copysign(1.0, value)))
        elif isinstance(value, (int, str, bool, np.integer)):
            items.append((name, value, type(value).__name__))
        else:
            return None
    return frozenset(items)


class PredictionMemo:
    """Recent predictions by key, at most `max_bytes` of arrays and `max_entries` entries.

    Parameters
    ----------
    max_bytes : int
        Largest total size of the remembered arrays, bytes.
    max_entries : int
        Largest number of remembered predictions.
    """

    def __init__(self, max_bytes: int = 32 * 2 ** 20, max_entries: int = 256):
        if max_bytes < 0 or max_entries < 0:
            raise ValueError("max_bytes and max_entries must be >= 0")
        self.max_bytes, self.max_entries = int(max_bytes), int(max_entries)
        self._items: OrderedDict = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self.hits = self.misses = 0

    def get(self, key) -> dict | None:
        """The prediction remembered under `key` (a new dict of the shared read-only arrays), or None."""
        if key is None:
            return None
        with self._lock:
            found = self._items.get(key)
            if found is None:
                self.misses += 1
                return None
            self._items.move_to_end(key)
            self.hits += 1
            return dict(found[0])

    def put(self, key, prediction: dict) -> dict:
        """Remember `prediction` under `key`; returns it with its arrays made read-only."""
        for array in prediction.values():
            array.setflags(write=False)
        if key is None:
            return prediction
        size = sum(int(a.nbytes) for a in prediction.values())
        if size > self.max_bytes or self.max_entries == 0:
            return prediction
        with self._lock:
            old = self._items.pop(key, None)
            if old is not None:
                self._bytes -= old[1]
            self._items[key] = (dict(prediction), size)
            self._bytes += size
            while self._items and (self._bytes > self.max_bytes or len(self._items) > self.max_entries):
                _, (_, dropped) = self._items.popitem(last=False)
                self._bytes -= dropped
        return prediction

    def clear(self) -> None:
        """Forget every prediction."""
        with self._lock:
            self._items.clear()
            self._bytes = 0

    def __len__(self) -> int:
        return len(self._items)

    @property
    def nbytes(self) -> int:
        """Total size of the remembered arrays, bytes."""
        return self._bytes
