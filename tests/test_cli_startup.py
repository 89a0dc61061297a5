"""Start-up of the command line: a command builds only its own parser and imports only what it needs."""

from __future__ import annotations

import json
import subprocess
import sys

from identification.cli import command_line as cli
from identification.recording import STANDARD_GRAVITY

#: Packages that take most of a second to import and that ``cleatfmu export`` does not need.
HEAVY = ("scipy", "numba", "matplotlib", "fmpy", "control", "numpy")


def _choices(parser) -> dict:
    """``{command: its sub-parser}`` of a cleatfmu parser."""
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return dict(action.choices)


def test_every_command_gets_the_same_parser_alone_as_among_all():
    full = _choices(cli.build_parser())
    assert set(full) == {"identify", *cli._COMMAND_MODULE_OF}
    for name, sub in full.items():
        alone = _choices(cli.build_parser(name))
        assert name in alone, name
        assert alone[name].get_default("func") is sub.get_default("func"), name
        assert [a.dest for a in alone[name]._actions] == [a.dest for a in sub._actions], name
    assert set(_choices(cli.build_parser("exprt"))) == set(full)  # a misspelt command: every choice listed


def test_export_imports_neither_scipy_numba_matplotlib_nor_fmpy_beyond_the_package(tmp_path):
    """In a fresh interpreter, ``cleatfmu export`` of a native FMU (cached binaries) loads none of the heavy
    packages (numpy aside); the FMU's hub starts at the static
    equilibrium of the corner mass: r0 - m g / k."""
    params = tmp_path / "params.json"
    k, mass = 412345.0, 1716.2
    params.write_text(json.dumps({"tires": {"FL": {"k": k, "c": 2345.0, "mass": mass}}}), encoding="utf-8")
    fmu = tmp_path / "FL.fmu"
    script = (f"import sys, identification\n"
              f"before = set(sys.modules)\n"
              f"from identification.cli import main\n"
              f"status = main(['export', {str(params)!r}, '-o', {str(fmu)!r}, '--platforms', 'linux64'])\n"
              f"new = sorted(m for m in set(sys.modules) - before if m.split('.')[0] in {HEAVY[:-1]!r})\n"
              f"print(status, ' '.join(new))\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    status, _, new = done.stdout.splitlines()[-1].partition(" ")
    assert status == "0" and new == "", done.stdout
    from fmpy import read_model_description

    starts = {v.name: float(v.start) for v in read_model_description(str(fmu)).modelVariables
              if v.start is not None}
    assert starts["hub_z"] == 0.75 - mass * STANDARD_GRAVITY / k
    assert starts["stiffness"] == k


def test_blas_is_held_to_one_thread_inside_the_diagnosis_and_restored_after():
    from threadpoolctl import threadpool_info

    from identification.workers import one_blas_thread

    def blas_threads():
        return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]

    before = blas_threads()
    inside = one_blas_thread(blas_threads)()
    assert inside and all(n == 1 for n in inside)
    assert blas_threads() == before


def test_a_first_run_says_it_compiles_and_a_second_does_not(tmp_path):
    """An empty numba cache (a fresh install): the compiled kernel is not on disk, the command says so on
    stderr before it steps the model; after one run it is cached and nothing is said."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    code = ("import sys; from identification.cli.util import announce_compilation; announce_compilation()\n"
            "from identification.model.kernels import compiled_on_disk, run_model\n"
            "from identification.model.fitting import TractorFitModel, TractorProblem\n"
            "from identification.recording import read_recording\n"
            "from identification.recording.examples import example_path\n"
            "pb = TractorProblem.from_recording(read_recording(example_path('7kmh')))\n"
            "m = TractorFitModel((), pb)\n"
            "print(compiled_on_disk())\n")
    first = subprocess.run([sys.executable, "-c", code + "m.simulate({n: 1.0 for n in m.names} | "
                            "{f'k_{t}': 5e5 for t in pb.channels} | {f'c_{t}': 3e3 for t in pb.channels} | "
                            "{'arrival': 1.0})\nprint(compiled_on_disk())"], env=env, capture_output=True,
                           text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    assert "compiling the model's stepping code" in first.stderr
    assert first.stdout.split() == ["False", "True"]
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stderr
    assert "compiling" not in second.stderr and second.stdout.split() == ["True"]
    # the same source in another folder (a reinstall, a checkout beside its installed copy; its files newer)
    # loads that compilation; one module changed anywhere in the package compiles afresh
    import shutil
    from pathlib import Path

    import identification

    for name, change in (("copy", None), ("changed", "tire_law.py")):
        shutil.copytree(Path(identification.__file__).parent, tmp_path / name / "identification",
                        ignore=shutil.ignore_patterns("__pycache__"))
        if change:
            with open(tmp_path / name / "identification" / "model" / change, "a", encoding="utf-8") as f:
                f.write("\n# changed\n")
        again = subprocess.run([sys.executable, "-c", code + "import identification; print(identification.__file__)"],
                               env=env, capture_output=True, text=True, timeout=300, cwd=tmp_path / name)
        assert again.returncode == 0, again.stderr
        assert again.stdout.split()[-1].startswith(str(tmp_path / name)), again.stdout
        assert again.stdout.split()[0] == ("False" if change else "True"), (name, again.stdout, again.stderr)
        assert ("compiling" in again.stderr) == bool(change), (name, again.stderr)


def test_the_cache_keeps_recent_versions_and_removes_old_unused_ones(tmp_path):
    """Beside the version in use, the five most recently used versions stay, and of the others only those
    unused for over a week are removed (another checkout may still be running a recent one)."""
    import os
    import time

    from identification._compile import _prune

    now = time.time()
    ages_days = {f"cleatfmu-{i:02d}": age for i, age in enumerate([0.1, 0.2, 1, 2, 3, 4, 5, 8, 30, 400])}
    for name, age in ages_days.items():
        (tmp_path / name / "model").mkdir(parents=True)
        os.utime(tmp_path / name, (now - age * 86400, now - age * 86400))
    (tmp_path / "other_library").mkdir()
    os.utime(tmp_path / "other_library", (now - 400 * 86400, now - 400 * 86400))
    current = tmp_path / "cleatfmu-in-use"
    current.mkdir()
    _prune(current)
    kept = sorted(p.name for p in tmp_path.iterdir())
    assert kept == sorted(["cleatfmu-00", "cleatfmu-01", "cleatfmu-02", "cleatfmu-03", "cleatfmu-04",
                           "cleatfmu-05", "cleatfmu-06", "cleatfmu-in-use", "other_library"])
    assert time.time() - current.stat().st_mtime < 60
