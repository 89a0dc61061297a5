"""Coherence of the left and right tracks of a road: a uniform model and a class-dependent one.

ISO 8608 describes one track's spectrum, not how the two tracks a vehicle
rides on are related.  The magnitude-squared coherence γ²(n) between them, over
the spatial frequency n (cycles/m), is 1 at long wavelengths (the tracks rise
and fall together) and falls towards 0 at wavelengths short against the track
width B.  Two models are offered (:data:`COHERENCE_MODELS`):

``"uniform"`` (the default), the same exponential for every class::

    γ²(n) = exp(−a · n · B),   a = DEFAULT_COHERENCE_DECAY = 2,

a parametric choice of this package;

``"class"``, a measured coherence that depends on the ISO 8608 class (classes
A to E only)::

    γ²(n) = [1 + (Ω · B / Ω_p)^w]^(−p),   Ω = 2π n (rad/m),   w = 2,

with (Ω_p in rad/m, p) of :data:`CLASS_COHERENCE`.  The formula and the class
parameters are those of Project Chrono's vehicle terrain
``RandomSurfaceTerrain`` (``src/chrono_vehicle/terrain/RandomSurfaceTerrain.cpp``
of projectchrono/chrono: ``Coherence()``, with the exponent a of the track width
1, and the ``ISO8608_A_CORR`` .. ``ISO8608_E_CORR`` presets, which have no
entries for classes F to H).  Chrono blends the two tracks' harmonic phases
with this value; here it is taken as the magnitude-squared coherence γ², which
:func:`identification.comfort.road.road_profile` then reproduces in
expectation.  Rough roads are less coherent at long wavelengths: at n = 0.1
cycles/m and B = 1.8 m class E gives γ² = 0.58, class A 0.94, the uniform
model 0.70; the order holds up to about 0.3 cycles/m and reverses beyond, where
every class is below 0.3 and the smaller exponent p of the rough classes makes
their coherence fall more slowly (at 1 cycle/m: A 0.03, E 0.07).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ._checks import positive

__all__ = ["DEFAULT_COHERENCE_DECAY", "COHERENCE_MODELS", "CLASS_COHERENCE", "CLASS_COHERENCE_WAVINESS",
           "track_coherence", "class_coherence", "coherence"]

#: Default decay a of the uniform coherence model γ²(n) = exp(−a n B).
DEFAULT_COHERENCE_DECAY = 2.0
#: The coherence models: one for every class, or the class-dependent measured one.
COHERENCE_MODELS = ("uniform", "class")
#: (Ω_p rad/m, p) of the class-dependent coherence, ISO 8608 classes A to E (Project Chrono's
#: RandomSurfaceTerrain presets ISO8608_A_CORR .. ISO8608_E_CORR).
CLASS_COHERENCE = {"A": (8.5, 3.5), "B": (5.3, 2.2), "C": (3.0, 1.3), "D": (1.6, 0.8), "E": (0.8, 0.5)}
#: Exponent w of the class-dependent coherence (the road's waviness, 2 for the ISO 8608 classes).
CLASS_COHERENCE_WAVINESS = 2.0


def track_coherence(n_cpm, track_width_m: float = 1.8, *, decay: float = DEFAULT_COHERENCE_DECAY) -> np.ndarray:
    """Magnitude-squared coherence of the left and right tracks by the uniform model, γ²(n) = exp(−a n B).

    Parameters
    ----------
    n_cpm : array_like
        Spatial frequencies, cycles/m (≥ 0).
    track_width_m : float
        Distance B between the tracks, m (> 0).
    decay : float
        Dimensionless decay a (≥ 0; 0: identical tracks).

    Returns
    -------
    ndarray
        γ²(n) in [0, 1], the shape of `n_cpm`.
    """
    b = positive("track width", track_width_m)
    a = float(decay)
    if not (math.isfinite(a) and a >= 0):
        raise InputError("coherence decay", f"must be a finite number >= 0, got {decay!r}")
    n = np.asarray(n_cpm, dtype=float)
    return np.exp(-a * np.abs(n) * b)


def class_coherence(n_cpm, track_width_m: float, road_class: str) -> np.ndarray:
    """Magnitude-squared coherence of the tracks by the class-dependent model, [1 + (2π n B / Ω_p)²]^(−p).

    Parameters
    ----------
    n_cpm : array_like
        Spatial frequencies, cycles/m.
    track_width_m : float
        Distance B between the tracks, m (> 0).
    road_class : str
        ISO 8608 class, ``"A"`` to ``"E"`` (the model has no parameters for F to H).

    Returns
    -------
    ndarray
        γ²(n) in (0, 1], the shape of `n_cpm`.
    """
    b = positive("track width", track_width_m)
    name = str(road_class).strip().upper()
    if name not in CLASS_COHERENCE:
        raise InputError("coherence", f"the class-dependent coherence is measured for ISO 8608 classes "
                                      f"{', '.join(CLASS_COHERENCE)} only, not {road_class!r}; use the uniform model")
    omega_p, p = CLASS_COHERENCE[name]
    omega = 2.0 * math.pi * np.abs(np.asarray(n_cpm, dtype=float))
    return (1.0 + (omega * b / omega_p) ** CLASS_COHERENCE_WAVINESS) ** (-p)


def coherence(n_cpm, track_width_m: float, *, model: str = "uniform", road_class: str | None = None,
              decay: float = DEFAULT_COHERENCE_DECAY) -> np.ndarray:
    """γ²(n) of the tracks by a model of :data:`COHERENCE_MODELS` (``"class"`` needs `road_class`;
    ``"uniform"`` uses `decay`)."""
    if model == "uniform":
        return track_coherence(n_cpm, track_width_m, decay=decay)
    if model == "class":
        return class_coherence(n_cpm, track_width_m, road_class)
    raise InputError("coherence", f"unknown coherence model {model!r} (allowed: {', '.join(COHERENCE_MODELS)})")
