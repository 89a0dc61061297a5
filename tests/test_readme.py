"""The README and the documentation are executable: every command block runs, page by page, in order.

Each page (``README.md`` and every ``docs/**/*.md``) runs its blocks in order in a temporary folder of its own,
so a page starts with the commands that make what it needs. A fenced block is one of:

* ``<!-- ci:main -->`` / ``<!-- ci:test -->``: the README's two quick-start commands, which ``.ci/run`` runs itself;
* ``<!-- synopsis -->``: a synopsis with placeholders (``REC.csv``, ``[--json]``); every command and option
  it names must exist;
* ``<!-- not run: REASON -->``: not run, for the reason given (the benchmarks); the scripts it names exist;
* a ``text`` block: a command's output (or a diagram) as shown, not run;
* otherwise run: ``sh`` blocks with bash (``set -euo pipefail``, the package's ``cleatfmu`` on the PATH),
  the ``python`` block (the Python API example) in one process, ``json`` blocks read as what they show
  (a recording's sidecar).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: Every page whose blocks are checked: the README first, then the documentation in path order.
PAGES = ["README.md"] + sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").rglob("*.md"))
_BLOCK = re.compile(r"(?:<!--\s*(?P<mark>[^>]*?)\s*-->[ \t]*\n)?(?P<indent>[ \t]*)```(?P<lang>\w*)\n(?P<body>.*?)"
                    r"^(?P=indent)```[ \t]*$", re.S | re.M)


def _blocks(page: str) -> list[dict]:
    """Every fenced block of a page: its page, line, language, marker comment (or None) and text (indentation
    removed)."""
    text = (ROOT / page).read_text(encoding="utf-8")
    out = []
    for m in _BLOCK.finditer(text):
        indent = len(m.group("indent"))
        body = "\n".join(line[indent:] for line in m.group("body").splitlines())
        out.append({"page": page, "line": text.count("\n", 0, m.start("lang")) + 1, "lang": m.group("lang"),
                    "mark": m.group("mark"), "body": body})
    return out


PAGE_BLOCKS = {page: _blocks(page) for page in PAGES}
BLOCKS = [b for page in PAGES for b in PAGE_BLOCKS[page]]

#: What each page's blocks say they write, in the page's folder.
WRITES = {
    "README.md": ["diagnosis.txt"] + [f"fmus/testday_7kmh_{t}.fmu" for t in ("FL", "FR", "RL", "RR")],
    "docs/guide/recordings.md": ["REC.csv", "REC.json", "REC.truth.json"],
    "docs/guide/identify.md": ["REC.truth.json", "waveform.json"],
    "docs/guide/export.md": ["params.json", "FL.fmu"],
    "docs/guide/simulate.md": ["params.json", "FL.fmu", "FL.png", "DIAG.json", "DIAG.png", "ALL.png"]
    + [f"fmus/REC_{t}.fmu" for t in ("FL", "FR", "RL", "RR")],
    "docs/guide/diagnose.md": ["FL_ext.fmu"],
    "docs/guide/ride.md": ["ride.png"],
    "docs/fmu.md": ["params.json", "FL.fmu"],
}


def _kind(block: dict) -> str:
    mark = block["mark"] or ""
    where = f"{block['page']} line {block['line']}"
    if mark.startswith("ci:"):
        return "ci"
    if mark == "synopsis":
        return "synopsis"
    if mark.startswith("not run:") and mark[len("not run:"):].strip():
        return "not run"
    assert not mark, f"{where}: unknown block marker <!-- {mark} -->"
    if block["lang"] == "text":
        return "output"
    assert block["lang"] in ("sh", "python", "json"), \
        f"{where}: a ```{block['lang']} block is neither run nor marked"
    return "run"


def test_every_block_is_run_or_marked_and_ci_runs_the_quick_start():
    kinds = [_kind(b) for b in BLOCKS]
    run = [b for b, k in zip(BLOCKS, kinds) if k == "run"]
    assert len(run) >= 12 and {b["lang"] for b in run} == {"sh", "python", "json"}
    assert [b["lang"] for b in run].count("python") == 1 and [b["lang"] for b in run].count("json") == 1
    # the quick start holds exactly the two commands CI runs, main job first, and only the README has them
    quick = README[README.index("## Quick start"):README.index("\n## ", README.index("## Quick start") + 1)]
    ci = [b for b, k in zip(BLOCKS, kinds) if k == "ci"]
    assert [b["mark"] for b in ci] == ["ci:main", "ci:test"] and all(b["body"] in quick for b in ci)
    assert {b["page"] for b in ci} == {"README.md"}
    assert ci[0]["body"].endswith("cleatfmu demo") and "pytest" in ci[1]["body"]
    ci_run = (ROOT / ".ci" / "run").read_text()
    assert "for name in main test" in ci_run and "README.md" in ci_run
    # the documentation is built, strictly, after the tests
    assert ci_run.index("for name in main test") < ci_run.index("mkdocs build --strict")
    # chromium comes from CI's setup, before the tests, never from a test
    assert ci_run.index("bash .ci/setup-debian") < ci_run.index("for name in main test")
    assert "apt-get install" in (ROOT / ".ci" / "setup-debian").read_text()
    installs = re.compile(r"apt-get (?:update|install -y)")
    assert [p.name for p in (ROOT / "tests").glob("test_*.py")
            if p.name != Path(__file__).name and installs.search(p.read_text())] == []


def test_synopses_name_real_commands_and_options():
    from identification.cli import build_parser
    commands = next(a for a in build_parser()._actions if getattr(a, "choices", None)).choices
    checked = 0
    for block in (b for b in BLOCKS if _kind(b) == "synopsis"):
        for line in block["body"].splitlines():
            words = line.split("#", 1)[0].split()
            if not words or words[0] != "cleatfmu":
                continue
            where = (block["page"], block["line"], line)
            assert words[1] in commands, where
            options = {o for a in commands[words[1]]._actions for o in a.option_strings}
            for option in re.findall(r"(?<![\w-])(--?[a-z][a-z0-9-]*)", " ".join(words[2:])):
                assert option in options, (*where, option)
            checked += 1
    assert checked >= 10


def test_scripts_of_blocks_not_run_exist():
    named = [m for b in BLOCKS if _kind(b) == "not run"
             for m in re.findall(r"python (\S+\.py)", b["body"])]
    assert len(named) >= 10
    assert [p for p in named if not (ROOT / p).is_file()] == []


def _embedded_recording() -> Path:
    return Path(str(resources.files("identification") / "data" / "testday_7kmh.csv"))


def _python_example(code: str, cwd: Path, env: dict, *, skip_teardown: bool = False) -> dict:
    """Run the Python API example (docs/fmu.md) in one process in `cwd`; its variables that are numbers, as JSON.

    With `skip_teardown` the process leaves with ``os._exit(0)`` once the numbers are out: pythonfmu's own
    finalisation at interpreter exit can abort ("corrupted double-linked list": 2 of 36 runs in
    ``tests/test_fmu_pythonfmu_backend.py``, and once in a CI run of this test), after the example is done.
    """
    dump = ("\nimport json as _j, sys as _s\n_j.dump({_k: _v for _k, _v in dict(globals()).items() "
            "if isinstance(_v, (int, float)) and not _k.startswith('_')}, _s.stdout)\n")
    if skip_teardown:
        dump += "_s.stdout.flush()\nimport os as _o\n_o._exit(0)\n"
    proc = subprocess.run([sys.executable, "-c", code + dump], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("page", [p for p in PAGES if any(_kind(b) == "run" for b in PAGE_BLOCKS[p])])
def test_blocks_run_in_order(page, tmp_path):
    """Every runnable block of one page, in order, in one folder: each command's files feed the next blocks."""
    from identification import read_recording

    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
               MPLBACKEND="Agg")
    assert shutil.which("cleatfmu", path=env["PATH"]), "the package's cleatfmu command is not installed"
    for block in (b for b in PAGE_BLOCKS[page] if _kind(b) == "run"):
        where = f"{page} line {block['line']}"
        if block["lang"] == "sh":
            proc = subprocess.run(["bash", "-c", "set -euo pipefail\n" + block["body"]], cwd=tmp_path, env=env,
                                  capture_output=True, text=True, timeout=300)
            assert proc.returncode == 0, f"{where}: exit {proc.returncode}\n{proc.stderr[-2000:]}"
            assert "Traceback" not in proc.stderr, (where, proc.stderr)
        elif block["lang"] == "python":
            # the Python API example: the force the native FMU exported above gives at 2 cm deflection
            k = json.loads((tmp_path / "params.json").read_text())["tires"]["FL"]["k"]
            assert _python_example(block["body"], tmp_path, env)["force"] == pytest.approx(k * 0.02, rel=1e-9)
        else:
            # the sidecar shown: a recording of the four tires with it, read back, keeps its values
            sidecar = json.loads(block["body"])
            folder = tmp_path / "sidecar"
            folder.mkdir()
            shutil.copyfile(_embedded_recording(), folder / "REC.csv")
            (folder / "REC.json").write_text(block["body"])
            rec = read_recording(folder / "REC.csv")
            assert rec.speed_kmh == sidecar["speed_kmh"] and rec.wheel_load_N["RR"] == pytest.approx(15510.0)
    # what the blocks say they write
    for name in WRITES.get(page, []):
        assert (tmp_path / name).stat().st_size > 0, (page, name)


def test_every_page_that_runs_blocks_says_what_they_write():
    assert sorted(WRITES) == sorted(p for p in PAGES if any(_kind(b) == "run" for b in PAGE_BLOCKS[p]))


def test_python_example_runs_with_the_pythonfmu_fmu_too(tmp_path):
    from build_scripts import build_fmu
    build_fmu("point_contact", tmp_path / "FL.fmu", backend="pythonfmu",
              start_values={"stiffness": 500e3, "damping": 4000.0, "unloaded_radius": 0.75})
    code = next(b["body"] for b in BLOCKS if b["lang"] == "python" and _kind(b) == "run")
    assert _python_example(code, tmp_path, dict(os.environ), skip_teardown=True)["force"] == \
        pytest.approx(500e3 * 0.02, rel=1e-12)
