"""Recordings: read and check a cleat run, condition it, find its window.

* :mod:`~identification.recording.record` - the ``cleat-recording/1`` format (CSV + JSON sidecar): read,
  validate, write (its API is re-exported here);
* :mod:`~identification.recording.csv_reader` - the CSV in bounded memory and its time column;
* :mod:`~identification.recording.plausibility` - the physical range of every quantity;
* :mod:`~identification.recording.condition` - what a field acquisition adds (offsets, drift, flipped
  sensors, engine lines, speed);
* :mod:`~identification.recording.preprocess` - the paper's preprocessing (low-pass, impacts, peaks);
* :mod:`~identification.recording.window` - the window of a long recording that holds the impacts;
* :mod:`~identification.recording.examples` - the embedded test day.
"""

from .record import *  # noqa: F401,F403
from .record import __all__  # noqa: F401
