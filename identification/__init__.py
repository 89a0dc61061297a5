"""cleatfmu: tire stiffness and damping from cleat tests, exported as FMI 2.0 FMUs.

One folder per stage, data flowing one way (each imports only the ones above it), SI units inside:

* :mod:`~identification.recording` - read and check a cleat run, condition it, find its window;
* :mod:`~identification.model`     - the one physics model: body, tire law, acquisition, stepping;
* :mod:`~identification.identify`  - the paper's k and c, the waveform fit, the static test;
* :mod:`~identification.fmu`       - tire FMUs and property files, the one master over FMUs, SSP;
* :mod:`~identification.diagnose`  - what the point-contact model misses, extended and measured;
* :mod:`~identification.comfort`   - ISO 8608 roads, ISO 2631-1, rides;
* :mod:`~identification.report`    - a day of runs in one HTML report;
* :mod:`~identification.cli`       - one thin module per command over this API.

:mod:`~identification.rig` is the virtual test rig (regression tests only; the pipeline never imports it).
"""

__version__ = "0.1.0"

from .errors import InputError  # noqa: E402
from .recording import Recording, read_recording, write_recording  # noqa: E402
from .recording.preprocess import preprocess  # noqa: E402
from .identify.paper import PaperResult, identify_paper  # noqa: E402

__all__ = ["InputError", "Recording", "read_recording", "write_recording", "preprocess",
           "PaperResult", "identify_paper", "__version__"]
