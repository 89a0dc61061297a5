"""Build, complete and check the project's FMI 2.0 and 3.0 co-simulation FMUs.

* :func:`build_fmu` — build an FMU of a kind in ``fmu_src`` with given start
  values, with the pythonfmu backend or the native (C) one
  (:mod:`build_scripts.native`, :mod:`build_scripts.native_fmu`);
* :mod:`build_scripts.check` — ``python -m build_scripts.check``: build every
  kind, validate it, simulate its default experiment with fmpy against the
  reference result and run it in libcosimpy;
* :mod:`build_scripts.reference` — ``python -m build_scripts.reference KIND``:
  rewrite a kind's reference result (after an intended change of behaviour).
"""

from .build import build_fmu, resolve_start_values
from .kinds import kind_names, load_kind

__all__ = ["build_fmu", "resolve_start_values", "kind_names", "load_kind"]
