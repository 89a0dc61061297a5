"""Compare a co-simulated tire with the measurement: where the simulation is wrong.

``cleatfmu simulate TIRE.fmu REC.csv --tire FL`` runs the tire FMU in the
quarter-tractor (:mod:`identification.fmu.cosim`) over the recording's cleat and
compares the hub acceleration with the measured one.

* **Time base.** The simulated acceleration is taken as the mean over each
  step of the co-simulation grid (the hub velocity difference over the step
  divided by its length, so an impulse keeps its area in its own step),
  low-passed there with the preprocessing filter, and sampled at the
  recording's times - as an acquisition samples its anti-alias-filtered
  signal.  (Averaging over the recording's own, longer sample interval would
  attenuate the impact by that box's sinc, 1.6 % at 100 Hz for 1 kHz.)
* **Alignment.** The cleat arrives at the measured impact onset
  (:func:`identification.recording.preprocess.preprocess`); the remaining offset (the
  onset detector's bias, a few ms) is found as the time shift, within
  ±30 ms, that minimises the squared difference over the analysis window.
* **Filtering.** The measurement gets the preprocessing low-pass (zero-phase
  5th-order Butterworth, 100 Hz by default) on its own time base.
* **Analysis window** = impact transient + free decay, from 50 ms before the
  impact onset to the end of the tire's free-vibration window (for a front tire
  the rear axle's arrival, less the filter guard; for a rear tire the record's
  end).  NRMSE = RMS(sim − meas) / RMS(meas) and R² over it.
* **Windows** break the residual down: ``impact`` (50 ms before the onset to
  the cleat exit + guard), ``free_decay`` (from there to the window end) and
  ``other_axle`` (front tire: from the rear axle's arrival to the end of the
  record; rear tire: from 50 ms before the front axle's impact, L/v earlier,
  to 50 ms before its own).  Each reports its NRMSE, the RMS error, the
  ratio of the RMS error to the measurement's noise RMS (≈ 1 where the
  simulation is right), and its ``misfit_share``: the residual energy beyond
  the noise, Σ (sim − meas)² − n σ², as a share of that of all windows.  The
  window with the largest share is where the simulation is wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from .cosim import CosimResult, run_quarter_tractor
from ..errors import InputError
from ..identify.paper import identify_paper
from ..recording.preprocess import DEFAULT_CUTOFF_HZ, TireSignal, filter_guard_s, lowpass, preprocess
from ..recording import FRONT_TIRES, Recording

__all__ = ["DEFAULT_MAX_STEP_S", "MAX_ALIGNMENT_S", "Window", "Comparison", "simulate_recording", "box_average"]

#: Default largest communication step of the co-simulation, s.
DEFAULT_MAX_STEP_S = 2.5e-4
_LEAD_S = 0.05
_MAX_SHIFT_S = 0.03
#: A window's RMS misfit beyond this multiple of the noise RMS is far from a model that explains the data.
UNEXPLAINED_ERROR_TO_NOISE = 10.0

#: Search limit of the (sub-sample) alignment of the simulated to the measured acceleration, s.
MAX_ALIGNMENT_S = _MAX_SHIFT_S


@dataclass(frozen=True)
class Window:
    """Residual statistics over one time window (m/s² unless stated)."""

    start_s: float
    end_s: float
    nrmse: float
    rms_error_m_s2: float
    rms_measured_m_s2: float
    error_to_noise: float
    excess_energy: float = 0.0     # Σ (sim − meas)² − n σ², (m/s²)²
    misfit_share: float = 0.0      # excess_energy / Σ over all windows

    def to_json(self) -> dict:
        return {"start_s": self.start_s, "end_s": self.end_s, "nrmse": self.nrmse,
                "rms_error_m_s2": self.rms_error_m_s2, "rms_measured_m_s2": self.rms_measured_m_s2,
                "error_to_noise": self.error_to_noise, "misfit_share": self.misfit_share}


@dataclass(frozen=True, eq=False)
class Comparison:
    """Measured vs co-simulated hub acceleration of one tire."""

    tire: str
    time_s: np.ndarray
    measured_m_s2: np.ndarray          # low-pass filtered
    simulated_m_s2: np.ndarray         # low-pass filtered, on the recording's time base
    nrmse: float
    r2: float
    alignment_s: float
    k_fmu: float
    c_fmu: float
    k_reidentified: float
    c_reidentified: float
    decay_rate_measured: float         # 1/s, positive for a decay
    decay_rate_simulated: float
    windows: dict[str, Window]
    measured_signal: TireSignal
    simulated_signal: TireSignal
    cosim: CosimResult
    method: str = "paper"
    extra: dict = field(default_factory=dict)

    @property
    def alignment_at_limit(self) -> bool:
        """The alignment reached its search limit (±:data:`MAX_ALIGNMENT_S`): the best shift may lie beyond it,
        so the simulated impact is out of phase with the measured one and the NRMSE overstates the misfit of
        the tire model (the arrival or the speed is off)."""
        return abs(self.alignment_s) >= MAX_ALIGNMENT_S - 1e-4

    @property
    def warnings(self) -> list:
        """Plain-language warnings about this comparison."""
        out = []
        if self.alignment_at_limit:
            out.append(f"the alignment of simulated to measured acceleration reached its search limit "
                       f"({self.alignment_s * 1e3:+.1f} ms of ±{MAX_ALIGNMENT_S * 1e3:.0f} ms): the simulated "
                       f"response is out of phase with the measured one (the impact time, the speed or the model "
                       f"is wrong)")
        # the window where the misfit is furthest above the noise, and that window's ratio
        name = max(self.windows, key=lambda n: self.windows[n].error_to_noise, default=None)
        worst = self.windows[name].error_to_noise if name is not None else 0.0
        if self.extra.get("channels", 1) == 4 and worst > UNEXPLAINED_ERROR_TO_NOISE:
            out.append(f"the misfit is {worst:.0f} x the noise in the {name} window: on a "
                       f"whole-tractor recording one corner under its own mass cannot follow a body that couples "
                       f"the four tires; run 'cleatfmu diagnose' on the recording and simulate the four FMUs "
                       f"under its body (--body DIAG.json)")
        return out

    @property
    def worst_window(self) -> str:
        """The window holding the largest share of the misfit beyond noise."""
        return max(self.windows, key=lambda n: self.windows[n].misfit_share)

    def to_json(self) -> dict:
        """The ``simulate --json`` document."""
        return {"tire": self.tire, "nrmse": self.nrmse, "r2": self.r2, "alignment_s": self.alignment_s,
                "alignment_at_limit": self.alignment_at_limit, "warnings": self.warnings,
                "k_fmu": self.k_fmu, "c_fmu": self.c_fmu,
                "k_reidentified": self.k_reidentified, "c_reidentified": self.c_reidentified,
                "decay_rate_measured": self.decay_rate_measured, "decay_rate_simulated": self.decay_rate_simulated,
                "windows": {name: w.to_json() for name, w in self.windows.items()}}


def box_average(cosim: CosimResult, time_s, interval_s: float, shift_s: float = 0.0) -> np.ndarray:
    """Mean hub acceleration over [t − h/2, t + h/2] for each t, shifted by `shift_s`, m/s²."""
    return cosim.mean_acceleration(np.asarray(time_s, dtype=float) - shift_s, interval_s)


def _sensed(cosim: CosimResult, rec: Recording, cutoff_hz: float):
    """``simulated(shift_s)``: what the recording's accelerometer shows of the co-simulated hub, delayed by
    `shift_s` and low-passed as the measurement is.

    Through the recording's acquisition chain (its anti-alias filter and AC coupling,
    :func:`identification.model.acquisition.sensed_acceleration`, computed once on the co-simulation grid and
    interpolated at the shifted sample times), or, without an anti-alias filter, the mean acceleration over
    each sample interval; then the analysis low-pass at the recording's rate.
    """
    from ..model.acquisition import sensed_acceleration

    t, fs = rec.time_s, rec.sample_rate_hz
    traj = cosim.trajectory
    aa = rec.acquisition
    if aa is not None and aa.anti_alias_order:
        grid = traj.time_s
        chained = sensed_acceleration(traj, 0, grid, fs, aa)

        def at(shift):
            return np.interp(t - shift, grid, chained)
    else:
        def at(shift):
            return traj.mean_acceleration(0, t - shift, 1.0 / fs)

    def simulated(shift):
        return lowpass(at(shift), sample_rate_hz=fs, cutoff_hz=cutoff_hz)
    return simulated


def _window(t, meas, sim, start, end, noise) -> Window:
    sel = (t >= start) & (t <= end)
    if sel.sum() < 2:
        return Window(float(start), float(end), math.nan, math.nan, math.nan, math.nan)
    sq = (sim[sel] - meas[sel]) ** 2
    err = float(np.sqrt(np.mean(sq)))
    ref = float(np.sqrt(np.mean(meas[sel] ** 2)))
    return Window(float(start), float(end), err / ref if ref > 0 else math.inf, err, ref,
                  err / noise if noise > 0 else math.inf,
                  excess_energy=max(0.0, float(np.sum(sq)) - sel.sum() * noise ** 2))


def _with_shares(windows: dict[str, Window]) -> dict[str, Window]:
    from dataclasses import replace
    total = sum(w.excess_energy for w in windows.values())
    return {n: replace(w, misfit_share=w.excess_energy / total if total > 0 else 0.0) for n, w in windows.items()}


def _reidentify(rec: Recording, tire: str, accel, cutoff_hz: float, method: str):
    sim_rec = Recording(time_s=rec.time_s, accel_m_s2={tire: accel}, speed_m_s=rec.speed_m_s,
                        cleat_height_m=rec.cleat_height_m, cleat_width_m=rec.cleat_width_m,
                        wheelbase_m=rec.wheelbase_m, wheel_load_N={tire: rec.wheel_load_N[tire]},
                        source=f"co-simulation of {rec.source}")
    sig = preprocess(sim_rec, [tire], cutoff_hz=cutoff_hz)[tire]
    if method == "waveform":
        from ..identify.waveform import identify_waveform
        return sig, identify_waveform(sig, rec.mass_kg(tire), source=sim_rec.source)
    return sig, identify_paper(sig, rec.mass_kg(tire), source=sim_rec.source)


def simulate_recording(fmu_path, rec: Recording, tire: str, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                       max_step_s: float = DEFAULT_MAX_STEP_S, method: str = "paper",
                       start_values: dict | None = None) -> Comparison:
    """Co-simulate the tire FMU over the recording's cleat and compare with the measurement.

    Parameters
    ----------
    fmu_path : path-like
        Tire FMU.
    rec : Recording
    tire : str
        Channel to compare.
    cutoff_hz : float
        Low-pass cut-off applied to both signals, Hz.
    max_step_s : float
        Largest co-simulation communication step, s.
    method : {"paper", "waveform"}
        How k and c are re-identified from the simulated acceleration.
    start_values : dict, optional
        FMU parameters to override.
    """
    if method not in ("paper", "waveform"):
        raise ValueError(f"unknown method {method!r}")
    sig = preprocess(rec, [tire], cutoff_hz=cutoff_hz)[tire]
    t, fs = rec.time_s, rec.sample_rate_hz
    ts = 1.0 / fs
    mass = rec.mass_kg(tire)
    try:
        cosim = run_quarter_tractor(
            fmu_path, mass_kg=mass, speed_m_s=rec.speed_m_s, cleat_height_m=rec.cleat_height_m,
            cleat_width_m=rec.cleat_width_m, arrival_s=sig.impact_s, t0_s=t[0] - 2 * _MAX_SHIFT_S,
            duration_s=t[-1] - t[0] + 4 * _MAX_SHIFT_S, max_step_s=max_step_s, start_values=start_values,
            cleat_profile=rec.cleat_profile)
    except InputError:
        raise
    except Exception as exc:  # an FMU that fails (fmi2Fatal / fmi2Error) raises from fmpy
        raise InputError(fmu_path, f"the FMU failed during the co-simulation: {exc}") from None
    measured = sig.filtered_m_s2
    start, end = sig.impact_s - _LEAD_S, sig.window_end_s
    sel = (t >= start) & (t <= end)

    simulated = _sensed(cosim, rec, cutoff_hz)

    def sse(shift):
        return float(np.sum((simulated(shift)[sel] - measured[sel]) ** 2))

    grid = np.linspace(-_MAX_SHIFT_S, _MAX_SHIFT_S, 61)
    best = grid[int(np.argmin([sse(s) for s in grid]))]
    step = grid[1] - grid[0]
    res = optimize.minimize_scalar(sse, bounds=(max(-_MAX_SHIFT_S, best - step), min(_MAX_SHIFT_S, best + step)),
                                   method="bounded", options={"xatol": 1e-6})
    shift = float(res.x)
    sim = simulated(shift)
    resid = sim[sel] - measured[sel]
    nrmse = float(np.sqrt(np.mean(resid ** 2)) / np.sqrt(np.mean(measured[sel] ** 2)))
    r2 = 1 - float(np.sum(resid ** 2)) / float(np.sum((measured[sel] - measured[sel].mean()) ** 2))

    guard = filter_guard_s(cutoff_hz)
    delay = rec.rear_axle_delay_s()
    noise = max(sig.noise_m_s2, 1e-12)
    windows = {"impact": _window(t, measured, sim, start, sig.free_start_s, noise),
               "free_decay": _window(t, measured, sim, sig.free_start_s, end, noise)}
    if tire in FRONT_TIRES:
        windows["other_axle"] = _window(t, measured, sim, sig.impact_s + delay - guard, t[-1], noise)
    else:
        windows["other_axle"] = _window(t, measured, sim, max(t[0], sig.impact_s - delay - _LEAD_S),
                                        sig.impact_s - _LEAD_S, noise)
    windows = _with_shares(windows)
    sim_sig, reid = _reidentify(rec, tire, box_average(cosim, t, ts, shift), cutoff_hz, method)
    measured_decay = -identify_paper(sig, mass, source=rec.source).decay_rate
    return Comparison(
        tire=tire, time_s=t, measured_m_s2=measured, simulated_m_s2=sim, nrmse=nrmse, r2=r2, alignment_s=shift,
        k_fmu=float(cosim.parameters["stiffness"]), c_fmu=float(cosim.parameters["damping"]),
        k_reidentified=reid.k, c_reidentified=reid.c, decay_rate_measured=measured_decay,
        decay_rate_simulated=-reid.decay_rate, windows=windows, measured_signal=sig, simulated_signal=sim_sig,
        cosim=cosim, method=method, extra={"channels": len(rec.tires)})
