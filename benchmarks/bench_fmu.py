"""Steps per second of the point-contact tire FMU under a bare fmpy FMU2Slave loop.

Each step is one ``setReal`` of the four inputs, one ``doStep`` and one
``getReal`` of the three Real outputs — the cost an importer pays per
communication step.  The same loop runs, in the same process and interleaved
in rounds, for

* ``cleatfmu``: the FMU built by :func:`build_scripts.build_fmu`;
* ``pythonfmu baseline``: a minimal pythonfmu slave with the same inputs,
  parameters and outputs (computed in ``do_step``), no post-processing,
  built into a temporary folder.

The reported figure is the median over rounds; the ratio is ours / baseline
(the target is >= 0.90).  Usage::

    python benchmarks/bench_fmu.py [--steps 20000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import textwrap
import time
from pathlib import Path

BASELINE_SOURCE = textwrap.dedent('''
    from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


    class BenchBaselineTire(Fmi2Slave):

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.hub_z, self.hub_vz, self.road_z, self.road_vz = 0.75, 0.0, 0.0, 0.0
            self.stiffness, self.damping, self.unloaded_radius = 4.0e5, 2.0e3, 0.75
            self.force_z, self.deflection, self.deflection_rate, self.in_contact = 0.0, 0.0, 0.0, False
            for name in ("hub_z", "hub_vz", "road_z", "road_vz"):
                self.register_variable(Real(name, causality=Fmi2Causality.input))
            for name in ("stiffness", "damping", "unloaded_radius"):
                self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                            variability=Fmi2Variability.tunable))
            for name in ("force_z", "deflection", "deflection_rate"):
                self.register_variable(Real(name, causality=Fmi2Causality.output))
            self.register_variable(Boolean("in_contact", causality=Fmi2Causality.output,
                                           variability=Fmi2Variability.discrete))

        def do_step(self, current_time, step_size):
            self.deflection = self.unloaded_radius - (self.hub_z - self.road_z)
            self.deflection_rate = self.road_vz - self.hub_vz
            self.force_z = self.stiffness * self.deflection + self.damping * self.deflection_rate
            self.in_contact = self.deflection > 0.0
            return True
''')

INPUTS = ("hub_z", "hub_vz", "road_z", "road_vz")
OUTPUTS = ("force_z", "deflection", "deflection_rate")


def build_baseline(folder: Path) -> Path:
    """Build the plain pythonfmu baseline FMU into `folder`."""
    from pythonfmu.builder import FmuBuilder

    script = folder / "bench_baseline_tire.py"
    script.write_text(BASELINE_SOURCE, encoding="utf-8")
    saved_path = list(sys.path)
    try:
        return Path(FmuBuilder.build_FMU(script, dest=folder))
    finally:
        sys.path[:] = saved_path
        sys.modules.pop("bench_baseline_tire", None)


def open_slave(fmu: Path, name: str):
    """Instantiate and initialise `fmu` with fmpy; returns (slave, input vrs, output vrs)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu), validate=False)
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, [vrs[n] for n in INPUTS], [vrs[n] for n in OUTPUTS]


def steps_per_second(slave, vr_in, vr_out, n_steps: int, h: float = 1e-3) -> float:
    """Run the bare loop (setReal, doStep, getReal) for `n_steps`; return steps/s."""
    set_real, do_step, get_real = slave.setReal, slave.doStep, slave.getReal
    t = 0.0
    start = time.perf_counter()
    for i in range(n_steps):
        set_real(vr_in, [0.74 - 1e-6 * (i % 100), 0.01, 0.0, 0.0])
        do_step(t, h)
        get_real(vr_out)
        t += h
    return n_steps / (time.perf_counter() - start)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20000, help="steps per round (default %(default)s)")
    parser.add_argument("--rounds", type=int, default=5, help="rounds, interleaved (default %(default)s)")
    args = parser.parse_args(argv)

    import fmpy
    import pythonfmu

    from build_scripts import build_fmu

    with tempfile.TemporaryDirectory(prefix="cleatfmu_bench_") as tmp:
        tmp = Path(tmp)
        ours = build_fmu("point_contact", tmp / "point_contact.fmu")
        baseline = build_baseline(tmp)
        slaves = {"cleatfmu": open_slave(ours, "ours"), "pythonfmu baseline": open_slave(baseline, "baseline")}
        for slave, vr_in, vr_out in slaves.values():
            steps_per_second(slave, vr_in, vr_out, 1000)  # warm-up
        rates = {name: [] for name in slaves}
        for _ in range(args.rounds):
            for name, (slave, vr_in, vr_out) in slaves.items():
                rates[name].append(steps_per_second(slave, vr_in, vr_out, args.steps))
        for slave, _, _ in slaves.values():
            slave.terminate()
            slave.freeInstance()

    print(f"bare fmpy FMU2Slave loop (setReal 4, doStep, getReal 3); {args.rounds} rounds x {args.steps} steps; "
          f"fmpy {fmpy.__version__}, pythonfmu {pythonfmu.__version__}, Python {sys.version.split()[0]}")
    median = {name: statistics.median(r) for name, r in rates.items()}
    for name, r in rates.items():
        print(f"  {name:<20} {median[name]:>10,.0f} steps/s  (rounds: {', '.join(f'{x:,.0f}' for x in r)})")
    ratio = median["cleatfmu"] / median["pythonfmu baseline"]
    print(f"  ratio cleatfmu / baseline: {ratio:.3f} (target >= 0.90)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
