"""Randomized acceptance sweep of the whole-tractor diagnosis, and the coverage of its 95 % intervals.

Rig draws per setting (randomized k and c per tire, pitch index, roll radius
of gyration, rigid or pivoting front axle, stagger up to ±0.15 s, 5-12 km/h, 500-2000 Hz sampling, noise
0.02-0.1 m/s²), each diagnosed from its recording alone; the truth judges:

* k within 3 %, c within 10 % per tire; pitch and roll index within 10 %;
* the effects named against the rig's (``axle_coupling`` in the rig is the
  rigid tractor, named ``axle_coupling`` + ``roll_coupling``, and with its
  pivot flag also ``front_axle_pivot``; ``lift_off`` only where some tire of
  the draw actually lost contact);
* coverage: where the named model is the rig's (the model is right), the
  share of k, c and (k, c) pairs whose 95 % intervals hold the truth.

Run: ``python benchmarks/sweep_tractor.py [--draws 3] [--seed 0] [--workers 2]``
(about 20 s per recording on 2 cores).
"""

import argparse
import json
import time

import numpy as np

from identification.diagnose.joint_select import diagnose_tractor
from identification.rig import run_rig

#: setting -> rig effects (the rig's axle_coupling is the rigid tractor)
SETTINGS = {
    "corners": (),
    "rigid": ("axle_coupling",),
    "rigid + enveloping": ("axle_coupling", "enveloping"),
    "rigid + enveloping + lift_off": ("axle_coupling", "enveloping", "lift_off"),
    "pivot": ("axle_coupling", "front_axle_pivot"),
    "pivot + enveloping": ("axle_coupling", "front_axle_pivot", "enveloping"),
}


def _draw(rng, effects):
    speed = float(rng.uniform(5, 12))
    over = {"speed_kmh": speed, "sensor.rate_hz": float(rng.choice([500, 1000, 2000])),
            "sensor.noise_m_s2": float(rng.uniform(0.02, 0.1))}
    for t in ("FL", "FR", "RL", "RR"):
        front = t[0] == "F"
        over[f"tire.{t}.k_N_m"] = float(rng.uniform(450e3, 650e3) if front else rng.uniform(350e3, 500e3))
        over[f"tire.{t}.c_Ns_m"] = float(rng.uniform(3000, 5000) if front else rng.uniform(1800, 3200))
    if "axle_coupling" in effects:
        over["axle_coupling.pitch_dynamic_index"] = float(rng.uniform(0.6, 1.3))
        over["axle_coupling.roll_gyration_m"] = float(rng.uniform(0.5, 0.8))
        stagger_s = float(rng.uniform(-0.15, 0.15))
        over["cleat.stagger_m"] = stagger_s * speed / 3.6
    if "front_axle_pivot" in effects:
        over["axle_coupling.front_axle_pivot"] = 1
        over["axle_coupling.front_axle_roll_inertia_kg_m2"] = float(rng.uniform(80, 200))
    if "enveloping" in effects:
        over["enveloping.footprint_front_m"] = float(rng.uniform(0.2, 0.4))
        over["enveloping.footprint_rear_m"] = float(rng.uniform(0.25, 0.5))
    return over


def _expected(effects, truth=None):
    """The effects a right diagnosis names: the rig's, with roll coupling on a rigid body, and lift-off only if
    some tire did lose contact (on a low cleat the unilateral tires may never leave the ground)."""
    out = set(effects)
    if "axle_coupling" in out:
        out.add("roll_coupling")
    if truth is not None and not any(t.get("contact_loss_s") for t in truth["tires"].values()):
        out.discard("lift_off")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=3, help="recordings per setting")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows, cover = [], {"k": [], "c": [], "pair": []}
    worst = {"k": 0.0, "c": 0.0, "index": 0.0}
    t_all = time.perf_counter()
    for name, effects in SETTINGS.items():
        for i in range(args.draws):
            over = _draw(rng, effects)
            seed = int(rng.integers(1 << 30))
            run = run_rig(tuple(e for e in effects if e != "front_axle_pivot"), over, seed=seed)
            t0 = time.perf_counter()
            diag = diagnose_tractor(run.recording, workers=args.workers)
            wall = time.perf_counter() - t0
            truth = run.truth
            p, ci = diag.final.params, diag.final.ci
            right = set(diag.effects) == _expected(effects, truth)
            k_err = max(abs(p[f"k_{t}"] / truth["tires"][t]["k"] - 1) for t in diag.channels)
            c_err = max(abs(p[f"c_{t}"] / truth["tires"][t]["c"] - 1) for t in diag.channels)
            idx_err = 0.0
            if "axle_coupling" in effects and "pitch_index" in p and "roll_index" in p:
                idx_err = max(abs(p["pitch_index"] / truth["body"]["pitch_dynamic_index"] - 1),
                              abs(p["roll_index"] / truth["body"]["roll_dynamic_index"] - 1))
            worst = {"k": max(worst["k"], k_err), "c": max(worst["c"], c_err), "index": max(worst["index"], idx_err)}
            missed = {}
            if right:
                for t in diag.channels:
                    ink = ci[f"k_{t}"][0] <= truth["tires"][t]["k"] <= ci[f"k_{t}"][1]
                    inc = ci[f"c_{t}"][0] <= truth["tires"][t]["c"] <= ci[f"c_{t}"][1]
                    cover["k"].append(ink)
                    cover["c"].append(inc)
                    cover["pair"].append(ink and inc)
                    for q, inside in (("k", ink), ("c", inc)):
                        if not inside:   # the miss in half-widths of the interval
                            lo, hi = ci[f"{q}_{t}"]
                            half = (hi - lo) / 2
                            missed[f"{q}_{t}"] = round((p[f"{q}_{t}"] - truth["tires"][t][q]) / half, 2) if half \
                                else "zero-width interval"
            left = [t for t, u in diag.unexplained.items() if u is not None]
            tests = {t: diag.residual_test(t) for t in diag.channels}
            ratios = {t: [round(v["residual_to_noise"], 2), round(v["worst_span_to_noise"], 2)]
                      for t, v in tests.items()}
            rows.append(dict(setting=name, seed=seed, speed_kmh=round(over["speed_kmh"], 1),
                             rate_hz=over["sensor.rate_hz"], noise=round(over["sensor.noise_m_s2"], 3),
                             effects=diag.effects, right_model=right, k_err=round(k_err, 4), c_err=round(c_err, 4),
                             index_err=round(idx_err, 4), unexplained=left, residual_to_noise=ratios, missed=missed,
                             seconds=round(wall, 1)))
            print(json.dumps(rows[-1]), flush=True)
    n = len(cover["k"])
    print()
    print(f"recordings: {len(rows)}; model right on {sum(r['right_model'] for r in rows)}; "
          f"total {time.perf_counter() - t_all:.0f} s")
    print(f"worst |k| error {worst['k']:.2%} (accept 3 %), worst |c| error {worst['c']:.2%} (accept 10 %), "
          f"worst index error {worst['index']:.2%} (accept 10 %)")
    tires = [v for r in rows for v in r["residual_to_noise"].values()]
    print(f"tires at the noise floor (residual within 1.5x the noise over the window and 3x over every 0.1 s): "
          f"{sum(w <= 1.5 and s <= 3.0 for w, s in tires)} of {len(tires)}; within 1.5x over the window alone: "
          f"{sum(w <= 1.5 for w, _ in tires)}; worst stretch: median {np.median([s for _, s in tires]):.2f}x, "
          f"largest {max(s for _, s in tires):.2f}x the noise")
    within = sum(r["k_err"] <= 0.03 and r["c_err"] <= 0.10 for r in rows)
    print(f"recordings with every k within 3 % and every c within 10 %: {within} of {len(rows)}")
    if n:
        print(f"coverage of the 95 % intervals where the model is right ({n} tires): "
              f"k {np.mean(cover['k']):.0%}, c {np.mean(cover['c']):.0%}, (k, c) pairs {np.mean(cover['pair']):.0%}")


if __name__ == "__main__":
    main()
