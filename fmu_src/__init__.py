"""Sources of the FMU kinds, one folder per kind (shipped as package data).

Each folder ``fmu_src/<kind>/`` holds a pythonfmu slave script, its manifest
``kind.json``, the reference result of its default experiment and a README.
The modules beside the folders are shared by the kinds: ``table_slave.py``
(the table-driven slave base class) and ``pythonfmu_wrapper.py`` (the
workarounds for pythonfmu's FMI wrapper); a kind's ``kind.json`` copies them
into its FMUs under module names unique to the kind.  None of this runs as
part of this package: the scripts and modules run inside the FMUs built by
:mod:`build_scripts`.
"""
