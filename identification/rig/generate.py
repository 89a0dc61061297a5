"""Run the virtual rig: a recording in ``cleat-recording/1`` plus its truth.

The truth file (``NAME.truth.json``, format ``cleat-rig-truth/1``) holds every
parameter, the active effects with their magnitudes, and per tire the true k,
c, corner mass, cleat arrival, excitation interval and contact-loss intervals.
The pipeline never reads it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .._files import atomic_write_texts, json_text
from ..recording import Acquisition, Recording, format_recording
from . import params as P
from .artifacts import active, artifact_rng, engine_vibration, sensor_artifacts
from .road import RoadInput
from .sensor import apply_chain, chain_modes
from .solver import hub_acceleration_on_grid, integrate
from .vehicle import STANDARD_GRAVITY, TIRES, build_plant

__all__ = ["RigRun", "run_rig", "write_run", "TRUTH_FORMAT"]

TRUTH_FORMAT = "cleat-rig-truth/1"
#: Pre-roll before t = 0 when a periodic excitation must reach steady state, s.
_PRE_ROLL_S = 0.5
#: The engine's vibration enters the sensor chain this long before the run starts, s (the anti-alias
#: filter has then long settled; the AC coupling's slow start on a zero-mean vibration is negligible).
_ENGINE_PRE_ROLL_S = 0.2


@dataclass(eq=False)
class RigRun:
    """One rig run: the recording and its truth (a JSON-ready dict)."""

    recording: Recording
    truth: dict
    accel_true_m_s2: np.ndarray   # (4, n) hub acceleration before the sensor chain, at the sample times
    #                               (the vehicle's response: without the engine vibration)


def _check_consistency(v: dict) -> None:
    total = sum(v[f"tire.{t}.load_N"] for t in TIRES) / STANDARD_GRAVITY
    if abs(total / v["vehicle.mass_kg"] - 1) > 0.01:
        raise InputError("--param", f"vehicle.mass_kg = {v['vehicle.mass_kg']:g} kg does not match the wheel "
                                    f"loads (sum / g = {total:.1f} kg)")
    if v["sensor.aa_order"] > 0 and v["sensor.aa_cutoff_hz"] >= v["sensor.rate_hz"] / 2:
        raise InputError("--param", "sensor.aa_cutoff_hz must be below half the sampling rate")
    if v["t0_s"] >= v["duration_s"]:
        raise InputError("--param", "t0_s must be inside the recording (t0_s < duration_s)")


def run_rig(effects=(), overrides: dict | None = None, *, seed: int = 0) -> RigRun:
    """Simulate one cleat crossing.

    Parameters
    ----------
    effects : iterable of str
        Active effects (names in :data:`identification.rig.params.EFFECTS`).
    overrides : dict, optional
        Parameter values by key (see :data:`identification.rig.params.PARAMS`).
    seed : int
        Seed of the measurement noise and of the lug phases.

    Returns
    -------
    RigRun
    """
    effects = P.parse_effects(list(effects))
    v = P.resolve(overrides)
    _check_consistency(v)
    rng = np.random.default_rng(seed)
    speed = v["speed_kmh"] / 3.6
    L, stagger = v["vehicle.wheelbase_m"], v["cleat.stagger_m"]
    # FL, FR, RL, RR; a negative stagger puts the right-hand cleat first (FR before FL, RR before RL)
    arrival = v["t0_s"] + np.array([0.0, stagger, L, L + stagger]) / speed
    front = [True, True, False, False]
    footprint = np.zeros(4)
    if "enveloping" in effects:
        footprint = np.array([v["enveloping.footprint_front_m"] if f else v["enveloping.footprint_rear_m"]
                              for f in front])
    lug_phase = rng.uniform(0, 2 * np.pi, 4)
    lug_amp, lug_freq = 0.0, np.zeros(4)
    if "periodic_disturbance" in effects:
        lug_amp = v["periodic_disturbance.amplitude_m"]
        if v["periodic_disturbance.frequency_hz"] > 0:
            lug_freq = np.full(4, v["periodic_disturbance.frequency_hz"])
        else:
            pitch = [np.pi * v[f"tire.{'front' if f else 'rear'}.diameter_m"]
                     / v[f"tire.{'front' if f else 'rear'}.lugs"] for f in front]
            lug_freq = speed / np.array(pitch)
    profile = _profile(v)
    road = RoadInput(arrival, speed, v["cleat.height_m"], v["cleat.width_m"], footprint,
                     lug_amp, lug_freq, lug_phase, profile=profile)
    plant = build_plant(v, effects, road)

    fs = v["sensor.rate_hz"]
    over = v["solver.oversample"]
    h = 1.0 / (fs * over)
    n_samples = int(round(v["duration_s"] * fs))
    # start at rest before the earliest excitation of any tire (with a negative stagger, FR's; it may
    # even precede t = 0, then the recording begins after that hit)
    first_excitation = min(road.excitation_interval(i)[0] for i in range(4))
    t_start = min(0.0, first_excitation - 0.05) - (_PRE_ROLL_S if lug_amp else 0.0)
    n_pre = int(np.ceil(-t_start / h - 1e-9))
    t_start = -n_pre * h
    n_nodes = n_pre + (n_samples - 1) * over + 1
    t_end = t_start + (n_nodes - 1) * h
    traj = integrate(plant, t_start, t_end, plant.linear_steady_state(t_start), rtol=v["solver.rtol"])
    acc, cuts = hub_acceleration_on_grid(plant, traj, t_start, h, n_nodes)
    aa_cut = v["sensor.aa_cutoff_hz"] or fs / 4
    poles, res, direct = chain_modes(int(v["sensor.aa_order"]), aa_cut, v["sensor.highpass_hz"])
    measured = apply_chain(acc, t_start, h, cuts, poles, res, direct)
    a_rng = artifact_rng(seed)
    # the engine runs before the recording: its vibration passes the chain (linear: on its own) from
    # _ENGINE_PRE_ROLL_S earlier, so that the chain has settled on it when the recording starts
    n_eng = int(round(_ENGINE_PRE_ROLL_S / h))
    engine, engine_info = engine_vibration(t_start + h * np.arange(-n_eng, n_nodes), v, a_rng)
    if engine_info:
        measured += apply_chain(engine, t_start - n_eng * h, h, [], poles, res, direct)[:, n_eng:]
    pick = slice(n_pre, None, over)
    y = measured[:, pick]
    time = np.arange(n_samples) / fs
    channels = v["sensor.channels"].split(",")
    y, sensor_info = sensor_artifacts(y, time, TIRES, v, a_rng)
    y = y + v["sensor.noise_m_s2"] * rng.standard_normal(y.shape)
    if v["sensor.lsb_m_s2"] > 0:
        y = v["sensor.lsb_m_s2"] * np.round(y / v["sensor.lsb_m_s2"])
    rec = Recording(
        time_s=time, accel_m_s2={c: y[TIRES.index(c)] for c in channels}, speed_m_s=speed * (1 + v["speed_error"]),
        cleat_height_m=v["cleat.height_m"], cleat_width_m=v["cleat.width_m"], wheelbase_m=L,
        wheel_load_N={c: v[f"tire.{c}.load_N"] for c in channels},
        description="virtual cleat-test rig recording", source="<rig>",
        acquisition=Acquisition(int(v["sensor.aa_order"]), float(aa_cut) if v["sensor.aa_order"] else 0.0,
                                float(v["sensor.highpass_hz"])),
        cleat_profile=None if profile is None or profile.is_rectangular else profile)
    truth = _truth(v, effects, seed, plant, road, traj, t_end)
    truth["artifacts"] = dict(active(v), **engine_info, **sensor_info)
    truth["speed_m_s"] = speed
    return RigRun(recording=rec, truth=truth, accel_true_m_s2=acc[:, pick])


def _profile(v: dict):
    """The cleat's profile from ``cleat.profile_mm`` or ``cleat.bevel_m`` (None: rectangular)."""
    from ..recording.cleat import CleatProfile, parse_profile

    if v["cleat.profile_mm"]:
        pts = [[float(c) for c in item.split(":")] for item in v["cleat.profile_mm"].split(",")]
        return parse_profile(pts, v["cleat.height_m"], v["cleat.width_m"], "--param cleat.profile_mm")
    if v["cleat.bevel_m"] > 0:
        if v["cleat.bevel_m"] > v["cleat.width_m"] / 2:
            raise InputError("--param", "cleat.bevel_m must be at most half of cleat.width_m")
        return CleatProfile.bevelled(v["cleat.height_m"], v["cleat.width_m"], v["cleat.bevel_m"])
    return None


def _truth(v, effects, seed, plant, road, traj, t_end) -> dict:
    loss: dict[int, list] = {i: [] for i in range(4)}
    open_at: dict[int, float] = {}
    for t, i, contact in sorted(traj.switches):
        if not contact and i not in open_at:
            open_at[i] = t
        elif contact and i in open_at:
            loss[i].append([open_at.pop(i), t])
    for i, t in open_at.items():
        loss[i].append([t, t_end])
    effect_params = {e: {k.split(".", 1)[1]: v[k] for k in P.PARAMS if k.startswith(e + ".")} for e in effects}
    tires = {}
    for i, name in enumerate(TIRES):
        tires[name] = {
            "k": float(plant.k[i]), "c": float(plant.c[i]), "mass": float(plant.load[i] / STANDARD_GRAVITY),
            "load_N": float(plant.load[i]), "static_deflection_m": float(plant.defl0[i]),
            "arrival_s": float(road.arrival[i]), "excitation_s": list(road.excitation_interval(i)),
            "footprint_m": float(road.fp[i]),
            "lug_frequency_hz": float(road.lug_w[i] / (2 * np.pi)) if road.lug_a else 0.0,
            "contact_loss_s": [[float(a), float(b)] for a, b in loss[i]],
        }
    return {"format": TRUTH_FORMAT, "seed": int(seed), "effects": effect_params, "parameters": dict(v),
            "tires": tires, "body": plant.inertia or None,
            "solver": {"method": "DOP853", "rtol": v["solver.rtol"], "pieces": len(traj.pieces),
                       "rhs_evaluations": int(traj.nfev)}}


def _time_decimals(rate_hz: float) -> int:
    """Fewest decimals that write the sample times exactly (or to 1e-3 of a step)."""
    for d in range(0, 7):
        if abs(10 ** d / rate_hz - round(10 ** d / rate_hz)) < 1e-9:
            return max(d, 1)
    return int(np.ceil(np.log10(rate_hz))) + 3


def write_run(run: RigRun, stem, *, value_decimals: int = 4) -> tuple[Path, Path]:
    """Write ``STEM.csv``, ``STEM.json`` and ``STEM.truth.json``; return (csv, truth) paths.

    All three files appear together or not at all.
    """
    stem = Path(stem)
    if stem.suffix.lower() == ".csv":
        stem = stem.with_suffix("")
    truth_path = stem.with_name(stem.name + ".truth.json")
    truth = dict(run.truth, recording=stem.name + ".csv")
    fs = run.recording.sample_rate_hz
    files = format_recording(run.recording, stem, time_decimals=_time_decimals(fs), value_decimals=value_decimals)
    files[truth_path] = json_text(truth, indent=1) + "\n"
    atomic_write_texts(files)
    return next(iter(files)), truth_path
