"""cleatfmu: tire stiffness and damping from cleat tests, exported as FMI 2.0 FMUs.

Pipeline stages, one module each, SI units throughout:

* :mod:`~identification.recording`  — the ``cleat-recording/1`` format
* :mod:`~identification.preprocess` — low-pass, impacts, free-vibration peaks
* :mod:`~identification.identify`   — the cleat-test paper's k and c
* :mod:`~identification.rig`        — virtual cleat-test rig (recordings with known truth)
"""

__version__ = "0.1.0"

from .errors import InputError  # noqa: E402
from .recording import Recording, read_recording, write_recording  # noqa: E402
from .preprocess import preprocess  # noqa: E402
from .identify import PaperResult, identify  # noqa: E402

__all__ = ["InputError", "Recording", "read_recording", "write_recording", "preprocess",
           "PaperResult", "identify", "__version__"]
