"""The package's layering, held by import-linter contracts (``[tool.importlinter]`` in pyproject.toml).

* the independent recording generator (``tests/independent``) imports nothing of the package: accuracy and
  coverage measured on its recordings are not measured against the fitter's own physics;
* the stages, one folder each, import only the ones below them: cli -> report -> comfort -> diagnose -> fmu
  -> identify -> model -> recording, over the base modules (_files, errors, workers, executors), which import
  no stage;
* the pipeline never imports the virtual rig;
* nothing but the command line imports ``identification.cli`` (the stages are a Python API under it).
"""

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LINT = [sys.executable, "-c", "import sys; from importlinter.cli import lint_imports_command; "
                              "sys.exit(lint_imports_command())"]


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(LINT + ["--no-cache"], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(cwd), "PATH": ""})


def test_every_layering_contract_is_kept():
    proc = _lint(ROOT)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert "5 kept, 0 broken" in proc.stdout


def test_a_generator_module_importing_the_package_breaks_its_contract(tmp_path):
    """The contracts bite: the same configuration over a copy of the generator with one module that imports
    the package's tire law."""
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (tmp_path / "identification").symlink_to(ROOT / "identification")
    shutil.copytree(ROOT / "tests" / "independent", tmp_path / "tests" / "independent",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "tests" / "independent" / "borrowed.py").write_text("from identification.model.tire_law import *\n")
    proc = _lint(tmp_path)
    assert proc.returncode == 1
    assert "The independent recording generator shares no code with the package BROKEN" in proc.stdout
    assert "tests.independent.borrowed -> identification.model.tire_law" in proc.stdout


def test_a_stage_importing_a_later_one_breaks_the_layers(tmp_path):
    """The layers bite: a copy of the package in which the recording stage imports the diagnosis."""
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    shutil.copytree(ROOT / "identification", tmp_path / "identification",
                    ignore=shutil.ignore_patterns("__pycache__", "data"))
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "__init__.py").write_text("")
    shutil.copytree(ROOT / "tests" / "independent", tmp_path / "tests" / "independent",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "identification" / "recording" / "upward.py").write_text("from ..diagnose import run\n")
    proc = _lint(tmp_path)
    assert proc.returncode == 1
    assert "no stage imports a later one BROKEN" in proc.stdout
    assert "identification.recording.upward -> identification.diagnose.run" in proc.stdout
