"""Which footprint law explains the independent simulator's cleat crossings: the parabolic footprint or the rigid ring.

For each recording of the independent sweep (``tests/independent``), the diagnosis' model of the
recording's expected body and enveloping (``TractorFitModel``; friction and a progressive tire when the
truth has them; lugs and lift-off left out) is fitted twice, with the parabolic footprint and with the
rigid ring over an elastic bed (the tire law's ``ring_envelope``): first with the truth's k and c and the
arrivals of the generator's draw fixed, then from there with every parameter free.  It prints each
fit's weighted residual, its residual to noise per channel, the footprints and, for the free fits,
the errors of k and c against the truth.  The diagnosis never sees the truth; this script does, to
measure how well each law can explain the data at best.

Run: ``python benchmarks/envelope_with_truth.py --seeds 20,29 --cache runs/independent`` (the
recordings of ``benchmarks/sweep_independent.py --cache``; it names a missing one).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

#: effects of the truth that the fitted model carries (lugs need their own start; lift-off is a detail here)
CARRIED = ("axle_coupling", "roll_coupling", "front_axle_pivot", "enveloping", "nonlinear_stiffness",
           "friction_damping")
#: start values of the free parameters besides the truth's
STARTS = {"roll_index": 1.0, "pivot_index": 0.1, "exponent": 1.2, "friction": 100.0, "footprint_front": 0.3,
          "footprint_rear": 0.35}


def fits(csv: Path, ring: bool) -> list[tuple[str, object]]:
    from identification.diagnose.joint_fit import fit_tractor
    from identification.model.fitting import TractorFitModel, TractorProblem
    from identification.recording.preprocess import default_cutoff_hz
    from identification.recording.record import read_recording
    from identification.recording.window import focus
    from tests.independent.generate import draw

    truth = json.loads(csv.with_suffix(".truth.json").read_text())
    scenario = draw(truth["setting"], truth["seed"])
    v = scenario.speed_kmh / 3.6
    rec = read_recording(csv)
    cutoff = default_cutoff_hz(rec.sample_rate_hz)   # the commands' default
    rec = focus(rec, cutoff_hz=cutoff, announce=False)
    pb = TractorProblem.from_recording(rec, cutoff_hz=cutoff)
    effects = [e for e in truth["expected_effects"] if e in CARRIED]
    model = TractorFitModel(effects, pb, ring=ring)
    fixed = {f"{q}_{t}": x[name] for t, x in truth["tires"].items() for q, name in (("k", "k"), ("c", "c"))}
    fixed.update(arrival=scenario.t0_s, stagger=scenario.stagger_m / v, delay=scenario.vehicle.wheelbase_m / v)
    start = dict(STARTS, pitch_index=(truth.get("body") or {}).get("pitch_index", 1.0), **fixed)   # corners: no body
    first = fit_tractor(model, {n: start[n] for n in model.names}, fixed={n: fixed[n] for n in model.names
                                                                          if n in fixed}, budget=400)
    return [("k, c, arrivals fixed", first), ("free", fit_tractor(model, first.params, budget=400))], truth


def main(argv=None) -> int:
    from identification.diagnose.joint_fit import unexplained
    from sweep_independent import generated

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", required=True, help="seeds of the independent sweep, e.g. 20,29")
    ap.add_argument("--cache", default="runs/independent", help="folder of the generated recordings")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    for csv in generated(Path(args.cache), seeds):
        print(f"{csv.stem}:")
        for ring in (False, True):
            steps, truth = fits(csv, ring)
            for label, fit in steps:
                pb = fit.model.problem
                ratios = [(unexplained(pb, fit.prediction, c) or {}).get("residual_to_noise", 0.0)
                          for c in pb.channels]
                feet = "/".join(f"{fit.params[n]:.2f}" for n in fit.model.names if n.startswith("footprint_"))
                line = (f"  {'ring     ' if ring else 'parabolic'} {label:21s} weighted residual "
                        f"{fit.weighted_sse():10.4g}  residual/noise {' '.join(f'{r:.1f}' for r in ratios)}"
                        f"  footprints {feet} m")
                if label == "free":
                    line += "  k, c errors " + " ".join(
                        f"{t} {fit.params['k_' + t] / x['k'] - 1:+.1%}/{fit.params['c_' + t] / x['c'] - 1:+.0%}"
                        for t, x in truth["tires"].items())
                print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
