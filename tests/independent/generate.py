"""Scenarios of the independent simulator: draw one, run it, write the recording and its truth.

A scenario is a setting (which effects are present) plus random draws of everything else: speed
4-14 km/h, sampling 200-2000 Hz, cleat 15-50 mm high with an undeclared bevel of 0.5-6 mm and
rounded top edges, the analog chain (Butterworth or Bessel anti-alias, AC coupling 0-0.5 Hz, declared
in the sidecar or not), noise, quantisation, engine lines, offsets and drifts, a GPS speed error of up
to 1 %.  The truth (``NAME.truth.json``, format ``independent-truth/1``) holds per tire the free-decay
k and c (:mod:`.truth`), the friction force, the contact losses, and the effects a right diagnosis names.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .sensor import Chain, acquire
from .terrain import cleat_polyline
from .tires import TireSpec
from .truth import free_decay_truth
from .vehicle import GRAVITY, WHEELS, Vehicle, cross_cleat

__all__ = ["SETTINGS", "Scenario", "draw", "run", "write"]

#: setting -> (layout, tire kind, extra effects)
SETTINGS = {
    "corners point": ("corners", "point", ()),
    "corners": ("corners", "bed", ()),
    "corners progressive": ("corners", "bed", ("nonlinear_stiffness",)),
    "corners friction": ("corners", "bed", ("friction_damping",)),
    "corners lugs": ("corners", "bed", ("periodic_disturbance",)),
    "corners tall cleat": ("corners", "bed", ("tall",)),
    "rigid": ("rigid", "bed", ()),
    "rigid lugs": ("rigid", "bed", ("periodic_disturbance",)),
    "pivot": ("pivot", "bed", ()),
    "rigid friction": ("rigid", "bed", ("friction_damping",)),
}
#: contact lost this long (s) counts as lift-off
LIFT_OFF_MIN_S = 0.004


@dataclass
class Scenario:
    setting: str
    seed: int
    speed_kmh: float
    rate_hz: float
    cleat_height_m: float
    cleat_width_m: float
    bevel_m: float
    round_m: float
    stagger_m: float
    t0_s: float
    vehicle: Vehicle
    chain: Chain
    declare_acquisition: bool
    speed_error: float
    offsets: dict = field(default_factory=dict)
    drifts: dict = field(default_factory=dict)

    @property
    def effects(self) -> tuple:
        return SETTINGS[self.setting][2]


def _tire(rng, kind, front, effects):
    radius = rng.uniform(0.66, 0.70) if front else rng.uniform(0.85, 0.89)
    k = rng.uniform(450e3, 650e3) if front else rng.uniform(350e3, 500e3)
    c = rng.uniform(3000, 5000) if front else rng.uniform(1800, 3200)
    friction = rng.uniform(150, 500) if "friction_damping" in effects else 0.0
    v_f = float(rng.uniform(0.003, 0.03))
    lug_a = rng.uniform(0.0015, 0.003) if "periodic_disturbance" in effects else 0.0
    lugs = int(rng.integers(18, 27))
    if kind == "point":
        return TireSpec("point", radius, k, c, friction_N=friction, friction_v_m_s=v_f,
                        lug_amplitude_m=lug_a, lugs=lugs)
    p = rng.uniform(0.7, 0.85) if "nonlinear_stiffness" in effects else 0.5
    kappa = 2 * k / (math.pi * math.sqrt(2 * radius)) * 0.02 ** (0.5 - p)   # about k at 20 mm
    contact = 2 * math.sqrt(2 * radius * 0.022)
    return TireSpec("bed", radius, kappa, c / contact, exponent=p, friction_N=friction / contact,
                    friction_v_m_s=v_f, lug_amplitude_m=lug_a, lugs=lugs)


def draw(setting: str, seed: int) -> Scenario:
    """A random scenario of ``setting`` (a key of :data:`SETTINGS`)."""
    layout, kind, effects = SETTINGS[setting]
    rng = np.random.default_rng(seed)
    tall = "tall" in effects
    speed = rng.uniform(9, 14) if tall else rng.uniform(4, 14)
    rate = float(rng.choice([200.0, 500.0, 1000.0, 2000.0]))
    tires = {w: _tire(rng, kind, w[0] == "F", effects) for w in WHEELS}
    wheelbase, track = rng.uniform(2.4, 2.9), rng.uniform(1.7, 2.0)
    if layout == "corners":
        masses = {w: (rng.uniform(10e3, 13e3) if w[0] == "F" else rng.uniform(14e3, 17e3)) / GRAVITY for w in WHEELS}
        vehicle = Vehicle("corners", tires, corner_mass_kg=masses, wheelbase_m=wheelbase, track_m=track)
        stagger = rng.uniform(-0.3, 0.3)
    else:
        mass = rng.uniform(5000, 6200)
        front_share = rng.uniform(0.38, 0.46)
        vehicle = Vehicle(layout, tires, mass_kg=mass, cg_from_front_m=(1 - front_share) * wheelbase,
                          cg_left_m=rng.uniform(-0.05, 0.05), pitch_index=rng.uniform(0.6, 1.3),
                          roll_gyration_m=rng.uniform(0.5, 0.8), wheelbase_m=wheelbase, track_m=track,
                          axle_mass_kg=rng.uniform(250, 450), axle_roll_inertia_kg_m2=rng.uniform(80, 200))
        stagger = rng.uniform(-0.15, 0.15) * speed / 3.6
    aa_kind = str(rng.choice(["butter", "bessel"]))
    chain = Chain(rate_hz=rate, aa_kind=aa_kind, aa_order=int(rng.integers(2, 9)),
                  aa_cutoff_hz=rate * rng.uniform(0.2, 0.3),
                  highpass_hz=float(rng.choice([0.0, rng.uniform(0.02, 0.5)])),
                  noise_m_s2=rng.uniform(0.02, 0.1),
                  lsb_m_s2=float(rng.choice([0.0, rng.uniform(0.002, 0.01)])),
                  engine_hz=float(rng.choice([0.0, 0.0, rng.uniform(25, min(80, rate * 0.18))])),
                  engine_m_s2=rng.uniform(0.2, 1.0), engine_orders=int(rng.integers(2, 4)))
    offsets = {w: float(rng.uniform(-2, 2)) if rng.random() < 0.3 else 0.0 for w in WHEELS}
    drifts = {w: float(rng.uniform(-0.05, 0.05)) if rng.random() < 0.2 else 0.0 for w in WHEELS}
    return Scenario(setting=setting, seed=seed, speed_kmh=speed, rate_hz=rate,
                    cleat_height_m=rng.uniform(0.045, 0.05) if tall else rng.uniform(0.015, 0.05),
                    cleat_width_m=rng.uniform(0.08, 0.15), bevel_m=rng.uniform(0.0005, 0.006),
                    round_m=rng.uniform(0.0, 0.005), stagger_m=stagger, t0_s=rng.uniform(0.5, 0.8),
                    vehicle=vehicle, chain=chain, declare_acquisition=aa_kind == "butter" and rng.random() < 0.7,
                    speed_error=rng.uniform(-0.01, 0.01), offsets=offsets, drifts=drifts)


def run(sc: Scenario) -> dict:
    """Simulate the scenario: {"time_s", "accel": {wheel: samples}, "truth": {...}}."""
    v = sc.speed_kmh / 3.6
    m = max(10, math.ceil(1e4 / sc.rate_hz))
    step = 1.0 / (m * sc.rate_hz)
    lugs = any(t.lug_amplitude_m > 0 for t in sc.vehicle.tires.values())
    pre = 1.0 if lugs else 0.3
    stagger_s = sc.stagger_m / v
    duration = sc.t0_s + max(0.0, stagger_s) + sc.vehicle.wheelbase_m / v + 2.5
    cleat = cleat_polyline(sc.cleat_height_m, sc.cleat_width_m, sc.bevel_m, sc.round_m)
    x_left = (pre + sc.t0_s) * v
    crossing = cross_cleat(sc.vehicle, speed_m_s=v, cleats={"L": cleat, "R": cleat},
                           cleat_x_m={"L": x_left, "R": x_left + sc.stagger_m}, step_s=step,
                           duration_s=pre + duration + 0.01)
    for w in WHEELS:   # the bristle bed must reach beyond every contact (the cleat's top under the lowest hub)
        spec = sc.vehicle.tires[w]
        if spec.kind == "bed":
            drop = spec.radius_m + spec.lug_amplitude_m - (float(crossing.hub_z[w].min()) - sc.cleat_height_m)
            if drop > 0 and math.sqrt(max(0.0, 2 * spec.radius_m * drop - drop ** 2)) >= spec.x_max_m:
                raise ValueError(f"{w}: the contact reaches the bristle bed's end ({spec.x_max_m} m)")
    rng = np.random.default_rng([sc.seed, 1])
    accel, t = {}, None
    for w in WHEELS:
        chain = Chain(**{**asdict(sc.chain), "offset_m_s2": sc.offsets[w], "drift_m_s2_per_s": sc.drifts[w]})
        t, accel[w] = acquire(crossing.time_s, crossing.accel_z[w], chain, rng, record_from_s=pre,
                              duration_s=duration)
    window = (crossing.time_s >= pre) & (crossing.time_s <= pre + duration)
    tires = {}
    for w in WHEELS:
        load = crossing.static_force_z[w]
        fd = free_decay_truth(sc.vehicle.tires[w], load)
        lost = crossing.force_z[w][window] <= 0.0
        longest, run_len = 0, 0
        for flag in lost:
            run_len = run_len + 1 if flag else 0
            longest = max(longest, run_len)
        spec = sc.vehicle.tires[w]
        contact = 2 * math.sqrt(2 * spec.radius_m * max(spec.radius_m - fd["static_height_m"], 0.0))
        tires[w] = {"k": float(fd["k"]), "c": float(fd["c"]), "mass_kg": float(fd["mass_kg"]),
                    "load_N": float(load), "free_decay_fit_rms_rel": float(fd["fit_rms_rel"]),
                    "friction_N": float(spec.friction_N * (contact if spec.kind == "bed" else 1.0)),
                    "contact_loss_s": float(lost.sum() * step), "longest_contact_loss_s": float(longest * step),
                    "kind": spec.kind, "exponent": spec.exponent, "lug_amplitude_m": spec.lug_amplitude_m}
    expected = set(e for e in sc.effects if e != "tall")
    if sc.vehicle.tires["FL"].kind == "bed":
        expected.add("enveloping")
    if sc.vehicle.layout != "corners":
        expected |= {"axle_coupling", "roll_coupling"}
    if sc.vehicle.layout == "pivot":
        expected.add("front_axle_pivot")
    if any(tt["longest_contact_loss_s"] >= LIFT_OFF_MIN_S for tt in tires.values()):
        expected.add("lift_off")
    truth = {"format": "independent-truth/1", "setting": sc.setting, "seed": sc.seed,
             "expected_effects": sorted(expected), "tires": tires,
             "scenario": {"speed_kmh": sc.speed_kmh, "rate_hz": sc.rate_hz, "cleat_height_m": sc.cleat_height_m,
                          "cleat_width_m": sc.cleat_width_m, "bevel_m": sc.bevel_m, "round_m": sc.round_m,
                          "stagger_m": sc.stagger_m, "layout": sc.vehicle.layout, "step_s": step,
                          "chain": asdict(sc.chain), "declared_acquisition": sc.declare_acquisition,
                          "speed_error": sc.speed_error, "offsets": sc.offsets, "drifts": sc.drifts}}
    if sc.vehicle.layout != "corners":
        veh = sc.vehicle
        truth["body"] = {"mass_kg": veh.mass_kg, "pitch_index": veh.pitch_index,
                         "roll_gyration_m": veh.roll_gyration_m, "cg_from_front_m": veh.cg_from_front_m}
    return {"time_s": t, "accel": accel, "truth": truth, "loads": {w: crossing.static_force_z[w] for w in WHEELS}}


def write(sc: Scenario, result: dict, stem: str | os.PathLike) -> Path:
    """Write NAME.csv, NAME.json (cleat-recording/1, written here by hand) and NAME.truth.json."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    t = result["time_s"]
    cols = np.column_stack([t] + [result["accel"][w] for w in WHEELS])
    with open(stem.with_suffix(".csv"), "w", encoding="ascii") as fh:
        fh.write("time," + ",".join(WHEELS) + "\n")
        np.savetxt(fh, cols, fmt=["%.6f"] + ["%.6g"] * len(WHEELS), delimiter=",")
    side = {"format": "cleat-recording/1", "speed_kmh": round(sc.speed_kmh * (1 + sc.speed_error), 2),
            "cleat_height_mm": round(sc.cleat_height_m * 1e3, 1), "cleat_width_mm": round(sc.cleat_width_m * 1e3, 1),
            "wheelbase_m": round(sc.vehicle.wheelbase_m, 3),
            "wheel_load_kN": {w: round(result["loads"][w] / 1e3, 2) for w in WHEELS},
            "description": f"independent simulator, setting {sc.setting!r}, seed {sc.seed}"}
    if sc.declare_acquisition:
        side["acquisition"] = {"anti_alias_order": sc.chain.aa_order,
                               "anti_alias_cutoff_hz": round(sc.chain.aa_cutoff_hz, 3),
                               "highpass_hz": round(sc.chain.highpass_hz, 4)}
    stem.with_suffix(".json").write_text(json.dumps(side, indent=1), encoding="utf-8")
    Path(str(stem) + ".truth.json").write_text(json.dumps(result["truth"], indent=1), encoding="utf-8")
    return stem.with_suffix(".csv")
