"""FMU-side workarounds for the FMI wrapper (the C++ binary) of pythonfmu 0.7.

This module runs inside FMUs, not in the cleatfmu package: the build copies it
into every FMU under a name unique to the FMU kind (e.g.
``cleatfmu_point_contact_wrapper``), so it imports only the standard library.

What the wrapper does, per FMI call, and what this module provides against it:

* ``fmi2Instantiate`` inserts the FMU's resources folder into ``sys.path``
  (one more entry per instance): :func:`forget_duplicate_path` keeps one.
* ``fmi2Instantiate`` re-executes the source of the FMU's entry module (module
  namespace as globals, a fresh dict as locals) to find the slave class: a
  class in the locals whose ``__mro__`` has an entry, after the first, whose
  repr reads ``<class '....Fmi2Slave'>``; it then instantiates the module
  attribute of that name.  It keeps a copy of that MRO and the repr of every
  entry alive for the rest of the process, and afterwards releases one
  reference to the module namespace that it does not own.
  :func:`on_reexecution` takes that reference beforehand and returns
  :class:`FinderTarget`, a stand-in with a two-entry MRO and shared repr
  strings, to be bound under the slave class's name during the
  re-execution — so the wrapper keeps about 0.3 kB per instantiation instead
  of a copy of the slave class's MRO and reprs (or, for a class defined in the
  entry module itself, a fresh copy of the whole class).
* When a Python call raises, the wrapper returns fmi2Fatal and releases one
  reference to the slave instance, its class and its log queue that it does
  not own, then keeps using them: :func:`before_failing` takes one reference
  to each first, so that a host that carries on, or frees the instance, does
  not touch freed memory.  When the slave's constructor raises, only the
  class reference is released: :func:`before_failing_construction`.
* Log messages still queued when the instance is freed are delivered to a
  logger that is already destroyed: a slave must not log in ``__init__``
  unless it then raises.
"""

import ctypes
import sys

__all__ = ["FinderTarget", "before_failing", "before_failing_construction", "forget_duplicate_path",
           "on_reexecution", "take_reference"]

_HELD = []


def _reference_taker():
    try:
        return ctypes.PYFUNCTYPE(None, ctypes.py_object)(("Py_IncRef", ctypes.pythonapi))
    except (AttributeError, OSError):  # C API not visible from here: hold the references instead
        return _HELD.append


#: ``take_reference(obj)`` adds one reference to `obj` that is never released.
take_reference = _reference_taker()


def before_failing(slave):
    """Compensate the references the wrapper releases when a call of `slave` raises."""
    for obj in (slave, type(slave), slave.log_queue):
        take_reference(obj)


def before_failing_construction(slave):
    """Compensate the reference to the slave class the wrapper releases when construction raises."""
    take_reference(type(slave))


def forget_duplicate_path(path):
    """Keep only the first entry equal to `path` in ``sys.path``."""
    if path and sys.path.count(path) > 1:
        first = sys.path.index(path)
        sys.path[:] = [p for i, p in enumerate(sys.path) if p != path or i == first]


class _FinderMeta(type):
    """Metaclass of the stand-ins: a fixed repr string and a fixed ``__mro__``."""

    def __repr__(cls):
        return cls.finder_repr

    @property
    def __mro__(cls):
        return cls.finder_mro


class _Fmi2SlaveTag(metaclass=_FinderMeta):
    finder_repr = "<class 'wrapper.Fmi2Slave'>"


class FinderTarget(metaclass=_FinderMeta):
    """Stand-in seen by the wrapper's class finder; never instantiated."""

    finder_repr = "<>"


FinderTarget.finder_mro = (FinderTarget, _Fmi2SlaveTag)


def on_reexecution(namespace):
    """Call from the entry module when the wrapper re-executes it; bind the result.

    Parameters
    ----------
    namespace : dict
        The entry module's ``globals()``.

    Returns
    -------
    type
        :class:`FinderTarget`, to be bound under the slave class's name.
    """
    take_reference(namespace)
    return FinderTarget
