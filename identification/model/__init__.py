"""The physics of a cleat run, built once per recording: the model record and its time stepping.

* :mod:`~identification.model.tractor` - the model record: the body (corners,
  half-tractors or the rigid tractor with a rigid or pivoting front axle), the
  four tire laws, the cleat and each wheel's arrival;
* :mod:`~identification.model.stepping` - the co-simulation master's stepping
  scheme for any body, in plain Python (the reference, also driving FMUs);
* :mod:`~identification.model.kernels` - the same stepping compiled with numba
  for the fitting models;
* :mod:`~identification.model.sensing` - what the model's accelerometers show
  after the acquisition chain and the analysis low-pass, all channels in one
  compiled pass.
"""

from .tractor import Body, Cleat, TractorModel, cleat_inputs
from .stepping import run_body

__all__ = ["Body", "Cleat", "TractorModel", "cleat_inputs", "run_body"]
