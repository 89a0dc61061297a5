"""Field artifacts x effects: identification and diagnosis on rig recordings as the field makes them.

For each artifact (engine vibration, DC offset and drift, a sensor upside down, a GPS speed error, a
bevelled cleat (its profile in the sidecar), all five together, and none for reference) and each effect of the rig (none and the six), ``--draws``
randomized rig runs (speed 7 or 10 km/h; engine 25-80 Hz, 0.5-3 m/s^2, 2-4 orders; offset up to
+-5 m/s^2, drift up to +-1 m/s^2/s; a random channel flipped; the sidecar's speed 3-6 % off, either
sign; a bevel of 5-30 mm on the 100 mm cleat; left/right stagger 0-50 mm), each seen by

* the paper's method and the waveform fit on every channel (``identify``: where a channel is outside
  the paper's rules, the waveform fit on the decay there is, as the command gives it), and
* the joint diagnosis of all channels (``diagnose``),

against the rig's truth (k, c, effects, speed).  A flip is "named" by the conditioning's warning or, where
that left the sign open, by the diagnosis' sign test (``sign_test`` in its JSON).  Goals (issue "Recordings as the field makes them"):
identification on every channel; after diagnosis k within 3 % and c within 10 %; the effects named
as without the artifact (the rig's effect, no ``enveloping`` from periodic excitation); a flipped
channel named in a warning; the speed from the front/rear delay (the diagnosis' fitted delay) within
1 % while the sidecar is off.

Prints one line per run and a table per artifact.  Run: ``python benchmarks/sweep_field.py``
(about 40 min on one core; ``--workers 2`` halves it), ``--draws 1 --effects none,enveloping`` for
a quick look.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))

ARTIFACTS = ("none", "engine", "offset_drift", "flipped", "speed_error", "bevel", "all")
EFFECTS = ("none", "enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
           "periodic_disturbance")
TIRES = ("FL", "FR", "RL", "RR")
#: The names the diagnosis gives each rig effect: the rig's body is rigid and rolls.
NAMES = {"none": [], "axle_coupling": ["axle_coupling", "roll_coupling"]}


def draw(artifact: str, rng: np.random.Generator) -> dict:
    """Rig parameters of one randomized draw of `artifact`."""
    ov = {"speed_kmh": float(rng.choice([7.0, 10.0])), "cleat.stagger_m": float(rng.uniform(0.0, 0.05))}
    kinds = ("engine", "offset_drift", "flipped", "speed_error", "bevel") if artifact == "all" else (artifact,)
    if "engine" in kinds:
        ov.update({"engine.frequency_hz": float(rng.uniform(25, 80)), "engine.amplitude_m_s2": float(rng.uniform(0.5, 3)),
                   "engine.orders": int(rng.integers(2, 5))})
    if "offset_drift" in kinds:
        ov.update({"sensor.offset_m_s2": float(rng.uniform(0.5, 5)), "sensor.drift_m_s2_per_s": float(rng.uniform(0.1, 1))})
    if "flipped" in kinds:
        ov["sensor.flipped"] = str(rng.choice(TIRES))
    if "speed_error" in kinds:
        ov["speed_error"] = float(rng.choice([-1, 1]) * rng.uniform(0.03, 0.06))
    if "bevel" in kinds:
        ov["cleat.bevel_m"] = float(rng.uniform(0.005, 0.03))
    return ov


def one(job: tuple) -> dict:
    """Run one draw; a JSON-ready summary."""
    from identification.diagnose.run import run_tractor_diagnosis
    from identification.errors import InputError
    from identification.identify.graceful import Refusal, identify_channels
    from identification.rig.generate import run_rig
    from identification.recording.window import focus

    artifact, effect, seed = job
    ov = draw(artifact, np.random.default_rng([seed, ARTIFACTS.index(artifact), EFFECTS.index(effect)]))
    run = run_rig([] if effect == "none" else [effect], ov, seed=seed)
    rec, truth = run.recording, run.truth["tires"]
    out: dict = {"artifact": artifact, "effect": effect, "seed": seed, "params": ov}
    with contextlib.redirect_stderr(io.StringIO()):
        cond = focus(rec, announce=False).conditioning
    out["warned_flipped"] = cond.get("flipped", [])
    for name in ("paper", "waveform"):     # as `cleatfmu identify --method NAME`: a refused channel's fallback
        try:
            with contextlib.redirect_stderr(io.StringIO()):
                res = identify_channels(rec, method=name)
            given = {t: (r.fallback if isinstance(r, Refusal) else r) for t, r in res.items()}
            out[name] = {t: [r.k / truth[t]["k"] - 1, r.c / truth[t]["c"] - 1] if r is not None else None
                         for t, r in given.items()}
            out[name + "_refused"] = {t: r.rule for t, r in res.items() if isinstance(r, Refusal)}
        except InputError as exc:
            out[name] = str(exc)
    t0 = time.perf_counter()
    try:
        diag, gain = run_tractor_diagnosis(rec)
        doc = diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after)
        out["diagnosis"] = {t: [x["k"] / truth[t]["k"] - 1, x["c"] / truth[t]["c"] - 1] for t, x in doc["tires"].items()}
        out["effects"] = doc["effects"]
        signs = doc.get("sign_test")
        if signs:      # a sign the conditioning left open, settled by the joint fit
            out["sign_test"] = signs
            if signs.get("chosen", "as recorded") != "as recorded":
                out["warned_flipped"] = sorted(out["warned_flipped"] + [signs["chosen"]])
        v_delay = doc["body"]["speed_m_s"]["from_delay"]
        out["speed_error_after"] = v_delay / run.truth["speed_m_s"] - 1 if v_delay else None
    except (InputError, ValueError) as exc:
        out["diagnosis"] = f"{type(exc).__name__}: {exc}"
    out["seconds"] = time.perf_counter() - t0
    return out


def verdict(r: dict) -> list[str]:
    """What a run misses of the goals (empty: all met)."""
    miss = []
    for name in ("paper", "waveform", "diagnosis"):
        if isinstance(r[name], str):
            miss.append(f"{name} refused: {r[name][:90]}")
        elif name != "diagnosis" and any(v is None for v in r[name].values()):
            miss.append(f"{name}: nothing for {[t for t, v in r[name].items() if v is None]}")
    if isinstance(r["diagnosis"], dict):
        for t, (ek, ec) in r["diagnosis"].items():
            if abs(ek) > 0.03 or abs(ec) > 0.10:
                miss.append(f"{t} k {ek:+.1%} c {ec:+.1%}")
        want = NAMES.get(r["effect"], [r["effect"]])
        if sorted(r["effects"]) != sorted(want):
            miss.append(f"named {r['effects']}, rig {want}")
        if r.get("speed_error_after") is not None and abs(r["speed_error_after"]) > 0.01:
            miss.append(f"speed from the delay {r['speed_error_after']:+.2%}")
    flipped = r["params"].get("sensor.flipped")
    if flipped and r["warned_flipped"] != [flipped]:
        miss.append(f"flipped {flipped}, warned {r['warned_flipped']}")
    if not flipped and r["warned_flipped"]:
        miss.append(f"warned flipped {r['warned_flipped']} (none is)")
    return miss


def _all_given(entry) -> bool:
    return isinstance(entry, dict) and all(v is not None for v in entry.values())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=3)
    ap.add_argument("--artifacts", default=",".join(ARTIFACTS))
    ap.add_argument("--effects", default=",".join(EFFECTS))
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", help="also write every run's summary to this file")
    args = ap.parse_args(argv)
    jobs = [(a, e, s) for a in args.artifacts.split(",") for e in args.effects.split(",") for s in range(args.draws)]
    results = []
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(one, jobs):
            miss = verdict(r)
            worst = max((max(abs(ek), abs(ec) / 3.33) for ek, ec in r["diagnosis"].values()), default=0) \
                if isinstance(r["diagnosis"], dict) else float("nan")
            fallbacks = sorted(set(r.get("paper_refused", {})) | set(r.get("waveform_refused", {})))
            note = f"  (fallback: {', '.join(fallbacks)})" if fallbacks else ""
            print(f"{r['artifact']:<13}{r['effect']:<21}{r['seed']:>2}  {r['seconds']:5.1f} s  "
                  f"{'ok' if not miss else 'MISS: ' + '; '.join(miss)}{note}", flush=True)
            r["miss"], r["worst"] = miss, worst
            results.append(r)
    print("\nartifact       runs  goals met  paper ok  waveform ok  diagnosis: max |k err|  max |c err|  names right"
          "  (paper ok / waveform ok: a value for every channel, the paper's rules met or the fallback's)")
    for a in args.artifacts.split(","):
        rs = [r for r in results if r["artifact"] == a]
        diag = [v for r in rs if isinstance(r["diagnosis"], dict) for v in r["diagnosis"].values()]
        names = sum(1 for r in rs if not any(m.startswith("named") for m in r["miss"]))
        print(f"{a:<14}{len(rs):>5}{sum(not r['miss'] for r in rs):>11}"
              f"{sum(_all_given(r['paper']) for r in rs):>10}{sum(_all_given(r['waveform']) for r in rs):>13}"
              f"{max((abs(k) for k, _ in diag), default=float('nan')):>24.2%}"
              f"{max((abs(c) for _, c in diag), default=float('nan')):>13.2%}{names:>13}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
