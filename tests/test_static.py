"""Static stiffness from a compression test (eq. 18): the slope, its interval, units, the loading branch, the CLI."""

import argparse
import json

import numpy as np
import pytest

from identification.cli import command_line as cli
from identification.cli import static as static_cmd
from identification.errors import InputError
from identification.identify.static import read_compression, static_stiffness, static_stiffness_file

K_TABLE5 = 295.08e3        # N/m: Table 5, front tire at 6.67 kg/s
NOISE_N = 40.0


def _loading(n=60, k=K_TABLE5, seed=0, top_m=0.03):
    rng = np.random.default_rng(seed)
    d = np.linspace(0.0, top_m, n) + rng.normal(0.0, 2e-5, n)
    f = k * d + 120.0 + rng.normal(0.0, NOISE_N, n)
    return d, f


def _write(path, columns: dict, rows=None):
    names = list(columns)
    lines = [",".join(names)]
    values = zip(*columns.values()) if rows is None else rows
    lines += [",".join(str(v) for v in row) for row in values]
    path.write_text("\n".join(lines) + "\n")
    return path


def _args(*argv):
    parser = argparse.ArgumentParser(prog="cleatfmu")
    static_cmd.add_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(["static", *map(str, argv)])


@pytest.fixture
def registered(monkeypatch):
    """``cleatfmu static`` in the CLI's command list (whether or not cli.py names it yet)."""
    if "static" not in cli._COMMAND_MODULE_OF:
        monkeypatch.setattr(cli, "_COMMAND_MODULES", [*cli._COMMAND_MODULES, ".static"])
        monkeypatch.setattr(cli, "_COMMAND_MODULE_OF", {**cli._COMMAND_MODULE_OF, "static": ".static"})


def test_known_slope_recovered_within_its_interval(tmp_path):
    d, f = _loading()
    result = static_stiffness_file(_write(tmp_path / "c.csv", {"deformation_m": d, "force_N": f}))
    lo, hi = result.k_ci95_N_per_m
    assert lo < K_TABLE5 < hi
    assert hi - lo < 0.01 * K_TABLE5
    assert result.k_N_per_m == pytest.approx(K_TABLE5, rel=0.005)
    assert result.intercept_N == pytest.approx(120.0, abs=40.0)
    assert result.r2 > 0.999 and result.residual_std_N == pytest.approx(NOISE_N, rel=0.3)
    assert result.n_loading == 60 and result.local_points.sum() == 60 and result.local_points.size == 5
    assert np.all(np.abs(result.local_slope_N_per_m - K_TABLE5) < 4 * result.local_se_N_per_m)
    assert np.all(np.diff(result.local_deformation_m) > 0)


def test_the_95_percent_interval_covers_the_true_slope_95_percent_of_the_time():
    hits = []
    for seed in range(400):
        lo, hi = static_stiffness(*_loading(n=20, seed=seed)).k_ci95_N_per_m
        hits.append(lo < K_TABLE5 < hi)
    assert 0.92 < np.mean(hits) < 0.98


def test_mm_and_kN_columns_give_the_same_stiffness(tmp_path):
    d, f = _loading(seed=3)
    si = static_stiffness_file(_write(tmp_path / "si.csv", {"deformation_m": d, "force_N": f}))
    paper = static_stiffness_file(_write(tmp_path / "mm.csv", {"time_s": np.arange(d.size), "Force_kN": f / 1e3,
                                                              "deformation_mm": d * 1e3}))
    assert paper.k_N_per_m == pytest.approx(si.k_N_per_m, rel=1e-9)
    assert paper.k_ci95_N_per_m == pytest.approx(si.k_ci95_N_per_m, rel=1e-9)
    lo, hi = paper.k_ci95_N_per_m
    assert lo < K_TABLE5 < hi


def test_loading_and_unloading_loop_fits_the_loading_branch_only():
    d, f = _loading(n=50, seed=4)
    back = np.linspace(0.03, 0.0, 40)[1:]
    d_all = np.r_[d, back]
    f_all = np.r_[f, 0.8 * K_TABLE5 * back - 500.0]          # the unloading branch: softer, below (hysteresis)
    loop = static_stiffness(d_all, f_all)
    only = static_stiffness(d, f)
    assert (loop.first, loop.stop) == (0, 50)
    assert loop.k_N_per_m == only.k_N_per_m
    assert loop.to_json()["n_rows_not_fitted"] == 39
    lo, hi = loop.k_ci95_N_per_m
    assert lo < K_TABLE5 < hi
    # two cycles, the second softer (Mullins effect): the first loading branch is fitted
    twice = static_stiffness(np.r_[d_all, d[1:]], np.r_[f_all, 0.7 * f[1:]])
    assert (twice.first, twice.stop) == (0, 50) and twice.k_N_per_m == only.k_N_per_m
    # a record that starts with a short unloading: the branch starts at the smallest deformation
    pre = np.array([0.004, 0.002])
    late = static_stiffness(np.r_[pre, d_all], np.r_[K_TABLE5 * pre, f_all])
    assert (late.first, late.stop) == (2, 52) and late.k_N_per_m == only.k_N_per_m


def test_local_slope_shows_a_stiffening_curve():
    d = np.linspace(0.0, 0.04, 80)
    f = 250e3 * d + 2.5e6 * d ** 2                           # dF/dD = 250 kN/m .. 450 kN/m
    result = static_stiffness(d, f, segments=4)
    assert np.all(np.diff(result.local_slope_N_per_m) > 0)
    np.testing.assert_allclose(result.local_slope_N_per_m, 250e3 + 5e6 * result.local_deformation_m, rtol=1e-9)
    spread = result.local_deformation_m[-1] - result.local_deformation_m[0]
    assert result.local_slope_range == pytest.approx(5e6 * spread / 350e3, rel=1e-9)


def test_cli_json_from_the_parser(tmp_path, capsys):
    d, f = _loading(seed=7)
    path = _write(tmp_path / "c.csv", {"deformation_m": d, "force_N": f})
    args = _args(path, "--json")
    assert args.func is static_cmd.run and args.segments == 5 and args.plot is None
    assert args.func(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["source"] == str(path)
    lo, hi = doc["k_ci95_N_per_m"]
    assert lo < K_TABLE5 < hi and lo < doc["k_static_N_per_m"] < hi
    assert doc["loading_branch"]["first_line"] == 2 and doc["loading_branch"]["last_line"] == 61
    assert len(doc["local_slopes"]) == 5 and doc["n_rows_not_fitted"] == 0


def test_cli_text_and_plot_written_atomically_in_a_new_folder(tmp_path, cli, registered):
    d, f = _loading(seed=8)
    path = _write(tmp_path / "c.csv", {"deformation_mm": d * 1e3, "force_kN": f / 1e3})
    out = tmp_path / "new" / "folder" / "static.png"
    res = cli("static", path, "--plot", out)
    assert res.code == 0, res.err
    assert "k_static" in res.out and "kN/m" in res.out and res.err == ""
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in out.parent.iterdir()] == ["static.png"]     # no temporary file left


def test_help_shows_the_defaults(capsys):
    with pytest.raises(SystemExit):
        _args("--help")
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: 5)" in text and "(default: no plot)" in text


BAD = {
    "missing columns": ("time_s,force_N\n0,1\n1,2\n2,3\n", "no deformation column"),
    "two deformation columns": ("deformation_m,deformation_mm,force_N\n0,0,0\n", "more than one deformation"),
    "non-numeric": ("deformation_m,force_N\n0,0\n0.01,abc\n0.02,6000\n", "line 3, column force_N: 'abc'"),
    "short row": ("deformation_m,force_N\n0,0\n0.01\n0.02,6000\n", "line 3: expected 2 cells"),
    "nan": ("deformation_m,force_N\n0,0\nnan,3000\n0.02,6000\n", "line 3, column deformation_m: non-finite"),
    "inf": ("deformation_m,force_N\n0,0\n0.01,inf\n0.02,6000\n", "non-finite"),
    "two points": ("deformation_m,force_N\n0,0\n0.01,3000\n", "2 rows: at least 3"),
    "empty": ("", "empty file"),
    "not increasing": ("deformation_m,force_N\n0.03,9000\n0.02,6000\n0.01,3000\n0.0,0\n",
                       "does not increase over 3 points"),
    "constant deformation": ("deformation_m,force_N\n0.01,0\n0.01,3000\n0.01,6000\n", "does not vary"),
    "negative stiffness": ("deformation_m,force_N\n0,9000\n0.01,6000\n0.02,3000\n0.03,0\n", "no positive stiffness"),
    "zero stiffness": ("deformation_m,force_N\n0,5000\n0.01,5000\n0.02,5000\n0.03,5000\n", "no positive stiffness"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, cli, registered, name):
    text, problem = BAD[name]
    path = tmp_path / "bad.csv"
    path.write_text(text)
    out = tmp_path / "plots" / "static.png"
    res = cli("static", path, "--json", "--plot", out)
    assert res.code == 2 and res.out == ""
    assert res.err.count("\n") == 1 and res.err.startswith(f"cleatfmu: error: {path}: ")
    assert problem in res.err
    assert not (tmp_path / "plots").exists()
    with pytest.raises(InputError, match="bad.csv"):
        read_compression(path) if name in ("missing columns", "non-numeric", "empty") else static_stiffness_file(path)


def test_missing_file_and_bad_options(tmp_path, cli, registered):
    res = cli("static", tmp_path / "none.csv")
    assert res.code == 2 and res.err == f"cleatfmu: error: {tmp_path / 'none.csv'}: no such file\n"
    d, f = _loading()
    path = _write(tmp_path / "c.csv", {"deformation_m": d, "force_N": f})
    res = cli("static", path, "--plot", tmp_path / "out.pdf")
    assert res.code == 2 and "must end with .png" in res.err and not (tmp_path / "out.pdf").exists()
    res = cli("static", path, "--segments", "0")
    assert res.code == 2 and "--segments" in res.err


def test_the_embedded_compression_test_is_the_rigs_and_holds_its_truth(tmp_path):
    """The demo's compression test is what the rig's standard linear solid writes; eq. 18 on it gives the
    truth's relaxed (static) stiffness within its 95 % interval, not the dynamic one the cleat sees."""
    import json

    from identification.recording.examples import compression_path
    from identification.rig.compression import write_compression
    shipped = compression_path()
    assert write_compression(tmp_path / "testday_compression").read_text() == shipped.read_text()
    truth = json.loads(shipped.with_name("testday_compression.truth.json").read_text())["parameters"]
    result = static_stiffness_file(shipped)
    lo, hi = result.k_ci95_N_per_m
    assert lo < truth["k_static_N_m"] < hi and hi < truth["k_dynamic_N_m"]
    assert result.local_slope_range < 0.02          # a linear tire (the paper's Figure 10): local slopes agree
