"""Virtual cleat-test rig: recordings of a tractor crossing a cleat, with known truth.

The rig simulates the tractor of the cleat-test paper (Tables 1, 2, 4) over a
rectangular cleat with switchable physical effects (``enveloping``,
``lift_off``, ``axle_coupling``, ``nonlinear_stiffness``,
``friction_damping``, ``periodic_disturbance``), records hub accelerations
through a modelled sensor chain, and writes the truth beside the recording.

It shares no force-law or solver code with the pipeline's models or the FMUs:
finding a hidden effect would otherwise be circular.
"""

from .generate import TRUTH_FORMAT, RigRun, run_rig, write_run
from .params import EFFECTS, PARAMS, resolve

__all__ = ["EFFECTS", "PARAMS", "TRUTH_FORMAT", "RigRun", "resolve", "run_rig", "write_run"]
