"""FMUs: the identified tire as files other tools load, and the one master that runs them.

* :mod:`~identification.fmu.export` - a point-contact tire FMU (native C or pythonfmu; FMI 2.0 or 3.0);
* :mod:`~identification.fmu.tire_files` - MF-Tyre ``.tir`` and Chrono tire JSON with the vertical values;
* :mod:`~identification.fmu.master` - the one co-simulation master over tire FMUs (any body);
* :mod:`~identification.fmu.cosim`, :mod:`~identification.fmu.tractor_cosim` - a corner, a half-tractor,
  the whole tractor of FMUs over the cleat;
* :mod:`~identification.fmu.validation` - the co-simulation against the measurement;
* :mod:`~identification.fmu.simulate_inputs` - the inputs of ``cleatfmu simulate`` for the whole tractor;
* :mod:`~identification.fmu.ssp`, :mod:`~identification.fmu.ssp_run` - the tractor as an SSP 1.0 system
  of FMUs, and its runners (fmpy, libcosim, the project's master).
"""
