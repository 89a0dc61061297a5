"""The identified vertical tire as an MF-Tyre property file (.tir) and in a Chrono tire JSON.

No package on PyPI reads .tir files, so the files are read back by a reader written here from the
published layout of MF-Tyre/Pacejka property files (as shipped, e.g., with Project Chrono's vehicle data:
``[SECTION]`` lines, ``KEY = value $comment``, ``!`` and ``$`` comment lines, ``{...}`` table headers),
independent of the writer's own parser; the Chrono JSON with the standard library's ``json``."""

from __future__ import annotations

import json
import re

import pytest

from identification.recording import STANDARD_GRAVITY

K, C, MASS = 585645.5398891533, 4592.916820857637, 1168.6

SUPPLIER_TIR = (
    "!****SUPPLIER BASE TIRE****\r\n"
    "!FILE_TYPE:    tir\r\n"
    "$------------------------------------------------mdi\r\n"
    "[MDI_HEADER]\r\n"
    "FILE_TYPE             =             'tir'\r\n"
    "FILE_VERSION          =               3.0\r\n"
    "$------------------------------------------------units\r\n"
    "[UNITS]\r\n"
    "LENGTH                =        'meter'\r\n"
    "FORCE                 =       'newton'\r\n"
    "[MODEL]\r\n"
    "PROPERTY_FILE_FORMAT  =      'PAC2002'\r\n"
    "USE_MODE              =              4        $Tyre use switch (IUSED)\r\n"
    "[DIMENSION]\r\n"
    "UNLOADED_RADIUS       =         0.8600        $Free tyre radius\r\n"
    "WIDTH                 =         0.6000        $Nominal section width of the tyre\r\n"
    "$------------------------------------------------parameter\r\n"
    "[VERTICAL]\r\n"
    "VERTICAL_STIFFNESS    =    7.1000e+005        $Tyre vertical stiffness\r\n"
    "VERTICAL_DAMPING      =             50        $Tyre vertical damping\r\n"
    "BREFF                 =          8.400        $Low load stiffness e.r.r.\r\n"
    "FNOMIN                =          11000        $Nominal wheel load\r\n"
    "[DEFLECTION_LOAD_CURVE]\r\n"
    "{pen        fz}\r\n"
    "0.000       0.000\r\n"
    "0.010    7100.000\r\n"
    "[LONGITUDINAL_COEFFICIENTS]\r\n"
    "PCX1                  =    1.4000e+000        $Shape factor Cfx for longitudinal force\r\n"
    "PDX1                  =    9.3385e-001        $Longitudinal friction Mux at Fznom\r\n"
    "\tVERTICAL_STIFFNESS_NOTE = 'not a key of [VERTICAL]'\r\n"
)

CHRONO_FIALA = """{
  "Name": "Supplier Fiala Tire",
  "Type": "Tire",
  "Template": "FialaTire",
  "Mass": 37.6,
  "Fiala Parameters": {
    "Unloaded Radius":    0.86,
    "Width":              0.6,
    "Vertical Stiffness": 7.1e5,
    "Vertical Damping":   50,
    "CSLIP":              1e5,
    "CALPHA":             5e4,
    "UMIN":               0.5,
    "UMAX":               0.8
  }
}
"""


def read_tir(text: str) -> dict:
    """{SECTION: {KEY: value}} of a property file: numbers as floats, 'strings' without quotes."""
    out, section = {}, None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "!${":
            continue
        if line.startswith("["):
            section = out.setdefault(line[1:line.index("]")], {})
            continue
        if "=" not in line:
            continue                                   # a table row
        key, value = (part.strip() for part in line.split("$", 1)[0].split("=", 1))
        section[key] = value.strip("'") if value.startswith("'") else float(value)
    return out


@pytest.fixture
def params(tmp_path):
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"recording": "day.csv", "speed_kmh": 7.0,
                                "tires": {"FL": {"k": K, "c": C, "mass": MASS}}}))
    return path


def test_a_vertical_tir_holds_the_identified_values_in_si(cli, params, tmp_path):
    out = tmp_path / "out" / "FL.tir"
    res = cli("export", params, "--format", "tir", "-o", out, "--unloaded-radius-m", "0.86")
    assert res.code == 0, res.err
    tir = read_tir(out.read_text(encoding="ascii"))
    assert tir["MDI_HEADER"]["FILE_TYPE"] == "tir"
    assert tir["UNITS"] == {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radians", "MASS": "kg",
                            "TIME": "second"}
    assert tir["MODEL"]["USE_MODE"] == 0                                       # vertical force only
    assert tir["DIMENSION"]["UNLOADED_RADIUS"] == 0.86
    vertical = tir["VERTICAL"]
    assert vertical["VERTICAL_STIFFNESS"] == pytest.approx(K, rel=1e-6)
    assert vertical["VERTICAL_DAMPING"] == pytest.approx(C, rel=1e-6)
    assert vertical["FNOMIN"] == pytest.approx(MASS * STANDARD_GRAVITY, rel=1e-6)
    assert res.err == ""                                                       # the radius was given


def test_the_supplier_tir_changes_in_its_two_vertical_values_only(cli, params, tmp_path):
    base = tmp_path / "supplier.tir"
    base.write_bytes(SUPPLIER_TIR.encode("latin-1"))
    out = tmp_path / "patched.tir"
    res = cli("export", params, "--format", "tir", "--base", base, "-o", out)
    assert res.code == 0, res.err
    before, after = SUPPLIER_TIR.encode("latin-1").split(b"\r\n"), out.read_bytes().split(b"\r\n")
    assert len(before) == len(after)
    changed = [i for i, (a, b) in enumerate(zip(before, after)) if a != b]
    assert [before[i].split(b"=")[0].strip() for i in changed] == [b"VERTICAL_STIFFNESS", b"VERTICAL_DAMPING"]
    for i in changed:                      # the key, its alignment and the comment kept; the number replaced
        a, b = before[i].decode(), after[i].decode()
        assert re.sub(r"=\s+\S+", "=", a).split("=")[0] == re.sub(r"=\s+\S+", "=", b).split("=")[0]
        assert a.split("$")[1] == b.split("$")[1]
    tir = read_tir(out.read_bytes().decode("latin-1"))
    assert tir["VERTICAL"]["VERTICAL_STIFFNESS"] == pytest.approx(K, rel=1e-6)
    assert tir["VERTICAL"]["VERTICAL_DAMPING"] == pytest.approx(C, rel=1e-6)
    assert tir["VERTICAL"]["FNOMIN"] == 11000 and tir["MODEL"]["USE_MODE"] == 4
    assert base.read_bytes() == SUPPLIER_TIR.encode("latin-1")                 # the supplier's file untouched
    assert "FNOMIN" not in res.err                       # 11000 N is within 10 % of the test's 11460 N


def test_a_supplier_nominal_load_far_from_the_tests_is_said(cli, params, tmp_path):
    base = tmp_path / "supplier.tir"
    base.write_bytes(SUPPLIER_TIR.replace("11000", "25000").encode("latin-1"))
    res = cli("export", params, "--format", "tir", "--base", base, "-o", tmp_path / "p.tir")
    assert res.code == 0 and "FNOMIN 25000 N is not the test's wheel load" in res.err


def test_the_chrono_tire_json_changes_in_its_two_vertical_values_only(cli, params, tmp_path):
    base = tmp_path / "fiala.json"
    base.write_text(CHRONO_FIALA)
    out = tmp_path / "patched.json"
    res = cli("export", params, "--format", "chrono-json", "--base", base, "-o", out)
    assert res.code == 0, res.err
    got, want = json.loads(out.read_text()), json.loads(CHRONO_FIALA)
    assert got["Fiala Parameters"].pop("Vertical Stiffness") == pytest.approx(K, rel=1e-15)
    assert got["Fiala Parameters"].pop("Vertical Damping") == pytest.approx(C, rel=1e-15)
    for key in ("Vertical Stiffness", "Vertical Damping"):
        want["Fiala Parameters"].pop(key)
    assert got == want
    number = r'("Vertical (?:Stiffness|Damping)":\s*)[^,\n]+'
    assert re.sub(number, r"\1#", out.read_text()) == re.sub(number, r"\1#", CHRONO_FIALA)


@pytest.mark.parametrize("args,base,needle", [
    (("--format", "chrono-json"), None, "give it with --base"),
    (("--format", "fmu", "--base", "{base}"), SUPPLIER_TIR, "use it with --format tir or chrono-json"),
    (("--format", "tir", "--base", "{base}"), "[MODEL]\nUSE_MODE = 4\n", "has no [VERTICAL] section"),
    (("--format", "tir", "--base", "{base}"), "[VERTICAL]\nFNOMIN = 1\n",
     "[VERTICAL] has no VERTICAL_STIFFNESS or VERTICAL_DAMPING"),
    (("--format", "tir", "--base", "{base}"),
     "[VERTICAL]\nVERTICAL_STIFFNESS = 1\nVERTICAL_DAMPING = 2\nVERTICAL_DAMPING = 3\n", "given twice"),
    (("--format", "tir", "--base", "{missing}"), None, "no such file"),
    (("--format", "chrono-json", "--base", "{base}"), '{"Vertical Stiffness": 1}', '0 numeric "Vertical Damping"'),
    (("--format", "chrono-json", "--base", "{base}"), "[" * 20000 + "]" * 20000, "malformed JSON"),
    (("--format", "tir", "-o", "{tmp}/x.fmu"), None, "must end with .tir"),
])
def test_bad_tire_file_exports_fail_in_one_line_and_write_nothing(cli, params, tmp_path, args, base, needle):
    path = tmp_path / "base.txt"
    if base is not None:
        path.write_text(base)
    args = [a.format(base=path, missing=tmp_path / "nope.tir", tmp=tmp_path) for a in args]
    before = set(tmp_path.iterdir())
    res = cli("export", params, *args)
    assert res.code == 2 and res.out == "" and needle in res.err, res.err
    assert len(res.err.strip().splitlines()) == 1
    assert set(tmp_path.iterdir()) == before
