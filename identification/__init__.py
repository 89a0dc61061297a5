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

import sys as _sys

import _signal   # built in: no import time before Ctrl-C is answered


def _started_as_the_program() -> bool:
    """The process runs ``cleatfmu`` (or ``python -m identification.cli``), not a notebook importing it."""
    first = _sys.argv[0] if _sys.argv else ""
    return first == "-m" or first.replace("\\", "/").rsplit("/", 1)[-1].startswith("cleatfmu")


def _defer_interrupt(signum, frame):
    """Ctrl-C or SIGTERM while the program's modules are still being imported: remembered, and answered by
    the command line's ``main`` with one line and status 130 or 143, not a traceback from an import."""
    global _interrupted
    _interrupted = _interrupted or signum


def _choose_the_temporary_folder() -> None:
    """Set :mod:`tempfile`'s folder as :func:`tempfile.gettempdir` would choose it ($TMPDIR, $TEMP, $TMP,
    then the system's), without the probe file it writes and deletes in each candidate: a run killed
    (SIGKILL) between the two left that 8-character file in $TMPDIR."""
    import os
    import tempfile

    if tempfile.tempdir is not None:
        return
    candidates = [os.environ.get(name) for name in ("TMPDIR", "TEMP", "TMP")]
    candidates += ["/tmp", "/var/tmp", "/usr/tmp"] if os.name == "posix" else []
    for folder in filter(None, candidates):
        if os.path.isdir(folder) and os.access(folder, os.W_OK | os.X_OK):
            tempfile.tempdir = os.path.abspath(folder)
            return


_interrupted = 0
#: Whether this process runs the command line as its program (told at the package's import, while
#: ``python -m`` still shows as ``-m`` in ``sys.argv``).
_AS_PROGRAM = _started_as_the_program()
if _AS_PROGRAM:
    for _signum in (_signal.SIGINT, _signal.SIGTERM):
        if _signal.getsignal(_signum) in (_signal.default_int_handler, _signal.SIG_DFL):
            _signal.signal(_signum, _defer_interrupt)
    _choose_the_temporary_folder()


__version__ = "0.1.0"

#: The package's API at the top, each imported when first used (``import identification.cli`` stays light:
#: a command can be interrupted from its first milliseconds with one line and status 130).
_API = {"InputError": ".errors", "Recording": ".recording", "read_recording": ".recording",
        "write_recording": ".recording", "preprocess": ".recording.preprocess", "PaperResult": ".identify.paper",
        "identify_paper": ".identify.paper"}

__all__ = [*_API, "__version__"]


def __getattr__(name):
    if name in _API:
        import importlib

        return getattr(importlib.import_module(_API[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
