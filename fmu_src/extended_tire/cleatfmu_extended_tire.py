"""Entry module of the extended tire FMU (the module named in slavemodule.txt).

The slave class is :class:`cleatfmu_extended_tire_slave.CleatfmuExtendedTire`.
pythonfmu 0.7's FMI wrapper re-executes this source at every instantiation to
find the class; see ``cleatfmu_extended_tire_wrapper`` for why that
re-execution binds a stand-in and nothing else.
"""

if locals() is globals():  # imported
    from cleatfmu_extended_tire_slave import CleatfmuExtendedTire
else:  # re-executed by the wrapper's class finder
    import cleatfmu_extended_tire_wrapper as _wrapper

    CleatfmuExtendedTire = _wrapper.on_reexecution(globals())
    del _wrapper

__all__ = ["CleatfmuExtendedTire"]
