"""The README's quick start and its fmpy example stay true."""

import re
from pathlib import Path

import pytest

README = (Path(__file__).parents[1] / "README.md").read_text()


def test_quick_start_has_exactly_two_commands_that_ci_runs():
    quick = README[README.index("## Quick start"):README.index("## Workflow")]
    blocks = re.findall(r"<!-- ci:(\w+) -->\s*```sh\n(.+?)\n```", quick, re.S)
    assert [name for name, _ in blocks] == ["main", "test"]
    assert blocks[0][1].endswith("cleatfmu demo") and "pytest" in blocks[1][1]
    ci = (Path(__file__).parents[1] / ".ci" / "run").read_text()
    assert "for name in main test" in ci and "README.md" in ci


@pytest.mark.parametrize("backend", ["native", "pythonfmu"])
def test_fmpy_example_runs(tmp_path, monkeypatch, backend):
    from build_scripts import build_fmu
    build_fmu("point_contact", tmp_path / "FL.fmu", backend=backend,
              start_values={"stiffness": 500e3, "damping": 4000.0, "unloaded_radius": 0.75})
    section = README[README.index("### Using the FMU in another tool"):]
    code = re.search(r"```python\n(.+?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README example", "exec"), scope)
    assert scope["force"] == pytest.approx(500e3 * (0.75 - 0.73), rel=1e-12)
