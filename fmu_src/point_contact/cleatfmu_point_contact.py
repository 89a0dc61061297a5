"""Entry module of the point-contact tire FMU (the module named in slavemodule.txt).

The slave class is :class:`cleatfmu_point_contact_slave.CleatfmuPointContact`.
pythonfmu 0.7's FMI wrapper re-executes this source at every instantiation to
find the class; see ``cleatfmu_point_contact_wrapper`` for why that
re-execution binds a stand-in and nothing else.
"""

if locals() is globals():  # imported
    from cleatfmu_point_contact_slave import CleatfmuPointContact
else:  # re-executed by the wrapper's class finder
    import cleatfmu_point_contact_wrapper as _wrapper

    CleatfmuPointContact = _wrapper.on_reexecution(globals())
    del _wrapper

__all__ = ["CleatfmuPointContact"]
