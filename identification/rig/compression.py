"""A compression test of a rig tire: the slow force–deformation measurement the static stiffness comes from.

The cleat-test paper (section 2.3.2, Table 5) loads each tire slowly in a hydraulic press, at 3 to
20 kg/s, and takes the slope of force against deformation as the static stiffness (eq. 18).  Its static
stiffnesses, 276–322 kN/m, are 100–170 kN/m below the cleat test's dynamic ones (section 4): loaded slowly,
the rubber creeps.  The rig's tire is a standard linear solid for that reason:

    F = k_static D + F_m,    dF_m/dt = (k_dynamic − k_static) dD/dt − F_m / tau

a spring k_static (the relaxed stiffness the compression test sees) in parallel with a Maxwell branch whose
stiffness makes up the dynamic stiffness at the cleat's frequencies (tau ≫ 1/(2π · 3 Hz)) and relaxes in
tau, far shorter than a loading that takes minutes.  The press loads at a constant rate to a peak force
and unloads at the same rate; deformation and force are read by sensors with white noise.  The truth file
holds k_static; the pipeline never reads it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._files import json_text

__all__ = ["COMPRESSION_DEFAULTS", "compression_test", "write_compression"]

#: The test of the embedded day's front tire (the rig's FL: dynamic k 550 kN/m).  Its static stiffness is
#: 150 kN/m below, within the paper's 100–170 kN/m (section 4); loaded at 10 kg/s (98.1 N/s) to 25 kN.
COMPRESSION_DEFAULTS = {
    "k_dynamic_N_m": 550e3,
    "k_static_N_m": 400e3,
    "relaxation_s": 2.0,
    "rate_N_s": 10.0 * 9.80665,
    "peak_N": 25e3,
    "sample_rate_hz": 2.0,
    "noise_force_N": 30.0,
    "noise_deformation_m": 0.05e-3,
}


def compression_test(*, seed: int = 5, **overrides) -> dict:
    """Load and unload the standard linear solid of the module docstring at a constant force rate.

    The deformation is integrated on a fine grid (1 ms, exact for the linear ODE between samples is not
    needed at these rates) under force control, then sampled at ``sample_rate_hz`` and noise is added.

    Parameters
    ----------
    seed : int
        Seed of the sensor noise.
    **overrides
        Any of :data:`COMPRESSION_DEFAULTS`.

    Returns
    -------
    dict
        ``deformation_m``, ``force_N`` (measured, arrays) and ``truth`` (the parameters).
    """
    unknown = set(overrides) - set(COMPRESSION_DEFAULTS)
    if unknown:
        raise ValueError(f"unknown compression-test parameter(s): {', '.join(sorted(unknown))}")
    p = dict(COMPRESSION_DEFAULTS, **overrides)
    ks, km, tau = p["k_static_N_m"], p["k_dynamic_N_m"] - p["k_static_N_m"], p["relaxation_s"]
    t_peak = p["peak_N"] / p["rate_N_s"]
    dt = 1e-3
    n = int(round(2 * t_peak / dt)) + 1
    t = np.arange(n) * dt
    force = p["rate_N_s"] * np.where(t <= t_peak, t, 2 * t_peak - t)
    # Force control: F = ks D + Fm and dFm/dt = km dD/dt - Fm/tau give
    # dD/dt = (dF/dt + Fm/tau) / (ks + km), dFm/dt = km dD/dt - Fm/tau (explicit Euler at dt << tau).
    dfdt = np.gradient(force, dt)
    defl = np.zeros(n)
    fm = 0.0
    for i in range(n - 1):
        rate = (dfdt[i] + fm / tau) / (ks + km)
        defl[i + 1] = defl[i] + dt * rate
        fm += dt * (km * rate - fm / tau)
    every = int(round(1.0 / (p["sample_rate_hz"] * dt)))
    rng = np.random.default_rng(seed)
    d = defl[::every] + rng.normal(0.0, p["noise_deformation_m"], defl[::every].size)
    f = force[::every] + rng.normal(0.0, p["noise_force_N"], force[::every].size)
    return {"deformation_m": d, "force_N": f, "truth": {"format": "cleat-rig-compression-truth/1", "seed": seed,
                                                          "parameters": p}}


def write_compression(stem, *, seed: int = 5, **overrides) -> Path:
    """Write ``STEM.csv`` (columns ``deformation_mm``, ``force_kN``, as the paper's press records them)
    and ``STEM.truth.json``; returns the CSV's path."""
    run = compression_test(seed=seed, **overrides)
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    lines = ["# compression test of a rig tire (identification.rig.compression); loading then unloading",
             "time_s,deformation_mm,force_kN"]
    dt = 1.0 / run["truth"]["parameters"]["sample_rate_hz"]
    lines += [f"{i * dt:.1f},{d * 1e3:.3f},{f / 1e3:.4f}"
              for i, (d, f) in enumerate(zip(run["deformation_m"], run["force_N"]))]
    csv_path = stem.with_name(stem.name + ".csv")
    csv_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    stem.with_name(stem.name + ".truth.json").write_text(json_text(run["truth"], indent=1) + "\n",
                                                         encoding="utf-8")
    return csv_path
