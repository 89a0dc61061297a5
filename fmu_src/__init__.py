"""Sources of the FMU kinds, one folder per kind (shipped as package data).

Each folder ``fmu_src/<kind>/`` holds a pythonfmu slave script, its manifest
``kind.json``, the reference result of its default experiment and a README.
The folders are data, not Python packages: their scripts run inside the FMUs
built by :mod:`build_scripts`, never as part of this package.
"""
