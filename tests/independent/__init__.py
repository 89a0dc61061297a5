"""An independent cleat-test simulator: recordings the pipeline has never seen the physics of.

Nothing here imports ``identification``: the multibody dynamics and the integrator are Exudyn's
(PyPI ``exudyn``, a multibody engine from outside this project), the tire is a rigid circle over a bed of
bristles whose footprint and enveloping emerge from its geometry, the cleat has bevels and rounded edges, and the
acquisition chain is simulated as analog filters on a grid at least ten times the output rate.
It is the only place accuracy and interval coverage of the pipeline are claimed from
(``benchmarks/sweep_independent.py``).

Modules
-------
terrain
    Cleat cross-sections (trapezoid with rounded top edges) as polylines; terrain height.
tires
    The tire laws: a point follower and a bristle-bed tire (progressive per-bristle law,
    per-bristle dampers, arctan friction, lugs as a modulation of the tire's radius).
vehicle
    The Exudyn models: independent corners, a rigid tractor (heave, pitch, roll) with an optional
    pivoting front axle; the cleat crossing and the hub accelerations.
sensor
    The acquisition chain: engine vibration, analog anti-alias (Butterworth or Bessel), AC coupling,
    sampling, noise, quantisation, offset and drift.
truth
    The truth experiment: a small free decay of each loaded wheel on flat ground in the same engine,
    fitted with a damped sinusoid: the equivalent linear k and c.
generate
    Draw a scenario, run it, write ``cleat-recording/1`` files and the truth.
"""
