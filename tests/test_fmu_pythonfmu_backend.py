"""The pythonfmu backend: a build after a pythonfmu FMU was loaded in the same process."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import build_scripts


def test_build_after_loading_a_pythonfmu_fmu_in_the_process_still_writes_binaries(tmp_path):
    # In a fresh process: nothing has imported pythonfmu before the FMU is loaded.
    script = textwrap.dedent(f"""
        import sys, zipfile
        from build_scripts.runners import open_fmpy_slave
        first = {str(tmp_path / "first.fmu")!r}
        s = open_fmpy_slave(first)
        s.terminate(); s.freeInstance()
        import pythonfmu
        assert "resources" in pythonfmu.__file__, pythonfmu.__file__  # the FMU's copy shadows the installed one
        from build_scripts import build_fmu
        for kind in ("point_contact", "extended_tire"):
            out = build_fmu(kind, {str(tmp_path)!r} + f"/{{kind}}.fmu")
            names = zipfile.ZipFile(out).namelist()
            assert any(n.startswith("binaries/linux64/") for n in names), names
            s = open_fmpy_slave(out)
            s.terminate(); s.freeInstance()
        print("ok")
    """)
    build_scripts.build_fmu("point_contact", tmp_path / "first.fmu")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(build_scripts.__file__).parent.parent), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "ok"
