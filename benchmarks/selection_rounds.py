"""The whole-tractor diagnosis' selection, round by round: every candidate with its gate, ΔBIC, gain and
bounds, for recordings (e.g. the independent sweep's tuning seeds), and the effects named against the
truth's where a ``NAME.truth.json`` lies beside a recording.

A tool for finding why an effect is missed or falsely named: a candidate refused for its gate, for a gain
under 25 %, for a parameter out of its bounds, or beaten by another.  The diagnosis runs as the command
runs it (focused, decimated, the default cut-off), without the FMU co-simulation.

Run: ``python benchmarks/selection_rounds.py REC.csv [REC.csv ...] [--rows OUT.jsonl] [--evidence]
[--code CHECKOUT] [--workers 2]``.  About as long as ``cleatfmu diagnose`` per recording.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import warnings
from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _use(code: str) -> None:
    sys.path.insert(0, code)


def rounds_of(path: str) -> dict:
    """One recording's selection: {"recording", "effects", "expected", "rounds": [[candidate, ...], ...]}."""
    warnings.simplefilter("ignore")
    from identification.diagnose.joint_select import MIN_DELTA_BIC, MIN_GAIN, diagnose_tractor
    from identification.errors import InputError
    from identification.recording import read_recording
    from identification.recording.preprocess import default_cutoff_hz
    from identification.recording.window import decimate, focus

    try:
        with contextlib.redirect_stderr(io.StringIO()):
            rec = read_recording(path)
            cutoff = default_cutoff_hz(rec.sample_rate_hz)
            rec = decimate(focus(rec, cutoff_hz=cutoff, announce=False), cutoff_hz=cutoff)
            diag = diagnose_tractor(rec, cutoff_hz=cutoff)
    except InputError as exc:
        return {"recording": path, "error": str(exc)}
    truth = Path(path).with_suffix(".truth.json")
    expected = json.loads(truth.read_text())["expected_effects"] if truth.exists() else None
    rounds = [[{"effect": c.effect, "gate": bool(c.passed_gate), "qualified": bool(c.qualified),
                "delta_bic": float(c.delta_bic), "gain": float(c.gain), "local_gain": c.local_gain,
                "in_bounds": bool(c.fit.in_bounds), "evidence": c.evidence} for c in rnd] for rnd in diag.rounds]
    return {"recording": path, "effects": sorted(diag.effects), "expected": expected, "rounds": rounds,
            "rescue": diag.extra.get("rescue"), "speed_refit": diag.extra.get("speed_refit"),
            "min_delta_bic": MIN_DELTA_BIC, "min_gain": MIN_GAIN}


def table(row: dict, evidence: bool = False) -> str:
    """The recording's rounds as text: one line per candidate, ✓ where it qualified."""
    name = Path(row["recording"]).stem
    if "error" in row:
        return f"{name}: {row['error']}"
    head = f"{name}: named {', '.join(row['effects']) or '-'}"
    if row["expected"] is not None:
        head += f"; truth {', '.join(row['expected']) or '-'}" + ("" if row["effects"] == row["expected"] else " ✗")
    if row.get("speed_refit"):
        head += f"; refitted at {row['speed_refit']['from_delay_m_s'] * 3.6:.2f} km/h (first: " \
                f"{', '.join(row['speed_refit']['first_effects']) or '-'})"
    lines = [head]
    for i, rnd in enumerate(row["rounds"]):
        for c in rnd:
            why = "" if c["qualified"] else " (" + ", ".join(
                w for w, bad in (("gate", not c["gate"]), ("bounds", not c["in_bounds"]),
                                 ("ΔBIC", c["delta_bic"] < row["min_delta_bic"]),
                                 ("gain", c["gain"] < row["min_gain"])) if bad) + ")"
            mark = "✓" if c["qualified"] else " "
            lines.append(f"  round {i} {mark} {c['effect']:55s} ΔBIC {c['delta_bic']:9.1f} gain {c['gain']:7.3f}{why}")
            if evidence:
                lines += [f"      {e}: {text}" for e, text in c["evidence"].items()]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("recordings", nargs="+", help="recording CSV files (their sidecars beside them)")
    ap.add_argument("--rows", help="also write one JSON line per recording here")
    ap.add_argument("--evidence", action="store_true", help="print every candidate's evidence sentences")
    ap.add_argument("--code", default=str(ROOT), help="the checkout whose identification is run")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    missing = [p for p in args.recordings if not Path(p).is_file()]
    if missing:
        print(f"selection_rounds: {missing[0]}: no such file", file=sys.stderr)
        return 2
    out = open(args.rows, "w", encoding="utf-8") if args.rows else None
    with Pool(max(1, args.workers), initializer=_use, initargs=(args.code,)) as pool:
        for row in pool.imap(rounds_of, args.recordings):
            print(table(row, args.evidence), flush=True)
            if out:
                out.write(json.dumps(row) + "\n")
    if out:
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
