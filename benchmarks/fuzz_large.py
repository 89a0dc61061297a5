"""A large run of the command-line fuzz suite (the strategies of ``tests/test_fuzz.py`` and
``tests/test_fuzz_commands.py``, the property of the first).

Each generated case must end in a valid result (exit 0) or in one line
``cleatfmu: error: <file or option>: <problem>`` with exit status 2 and no file
written.  Prints, per strategy, the number of cases by outcome (valid, exit 2,
failure), the most frequent error messages, and the first failures in full.
Exit status 1 when any case failed.

Run: ``python benchmarks/fuzz_large.py`` (20,000 cases), or
``python benchmarks/fuzz_large.py --examples 2000 --seed 7 --only recording sidecar``.
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402

import test_fuzz  # noqa: E402
import test_fuzz_commands  # noqa: E402

#: Every strategy, by name.
STRATEGIES = {**test_fuzz.ALL_STRATEGIES, **test_fuzz_commands.COMMAND_STRATEGIES}

#: Share of the cases per strategy (export builds an FMU per valid case, diagnose, simulate and rig run a fit, a
#: co-simulation or the rig: fewer of them).
WEIGHTS = {"recording": 0.30, "sidecar": 0.20, "identify_options": 0.12, "params": 0.13, "export_options": 0.06,
           "diagnose": 0.05, "simulate": 0.06, "rig": 0.08, "static": 0.10, "comfort": 0.10, "ride": 0.03,
           "ssp": 0.03, "simulate_body": 0.03, "export_diagnosis": 0.04, "map": 0.05, "seat": 0.04}


def _message_kind(message: str) -> str:
    """An error message without its numbers and quoted values (to group similar messages)."""
    message = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", message)
    return re.sub(r"[-+]?\d[\w.+-]*", "#", message)[:110]


def run_strategy(name: str, examples: int, seed_value: int, keep: int = 3) -> dict:
    """Run `examples` cases of strategy `name`; return the counts, message kinds and the first failures."""
    counts = collections.Counter()
    kinds = collections.Counter()
    failures: list[str] = []

    @seed(seed_value)
    @settings(max_examples=examples, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(case=STRATEGIES[name]())
    def run(case):
        details: dict = {}
        try:
            outcome = test_fuzz.check_case(case, details)
        except test_fuzz.FuzzFailure as exc:
            counts["failure"] += 1
            if len(failures) < keep:
                failures.append(f"{exc}\n  case: {case!r}")
            return
        counts[outcome] += 1
        if outcome == "error":
            kinds[_message_kind(details["message"])] += 1

    run()
    return {"counts": counts, "kinds": kinds, "failures": failures}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=20_000, help="total number of cases (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default %(default)s)")
    parser.add_argument("--only", nargs="+", choices=sorted(WEIGHTS), help="run these strategies only")
    parser.add_argument("--messages", type=int, default=8, help="most frequent error messages shown per strategy")
    args = parser.parse_args(argv)
    names = args.only or list(WEIGHTS)
    total_weight = sum(WEIGHTS[n] for n in names)
    grand = collections.Counter()
    failed = []
    print(f"{'strategy':<18}{'cases':>8}{'valid':>8}{'exit 2':>8}{'failures':>10}{'time/s':>9}")
    for name in names:
        n = max(1, round(args.examples * WEIGHTS[name] / total_weight))
        start = time.perf_counter()
        result = run_strategy(name, n, args.seed)
        c = result["counts"]
        cases = sum(c.values())
        print(f"{name:<18}{cases:>8}{c['valid']:>8}{c['error']:>8}{c['failure']:>10}"
              f"{time.perf_counter() - start:>9.1f}", flush=True)
        for kind, count in result["kinds"].most_common(args.messages):
            print(f"{'':<4}{count:>6}  {kind}")
        grand.update(c)
        failed += result["failures"]
    print(f"{'total':<18}{sum(grand.values()):>8}{grand['valid']:>8}{grand['error']:>8}{grand['failure']:>10}")
    for text in failed:
        print("\nFAILURE " + text)
    return 1 if grand["failure"] else 0


if __name__ == "__main__":
    sys.exit(main())
