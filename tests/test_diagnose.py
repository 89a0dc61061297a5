"""Diagnosis of one tire: hide an effect in a rig recording and require the pipeline to find it.

The one-tire diagnosis is the joint diagnosis restricted to that tire's channel and the same side's other
axle (:func:`identification.diagnose.run.run_diagnosis`).  Each draw randomizes the effect's magnitude,
the tires' k and c, the speed (7/10 km/h), the sampling rate (500-2000 Hz), the noise and the tire
diagnosed.  The diagnosis reads only the recording; the truth is used to judge it.
"""

import ast
import json
import re
from pathlib import Path

import numpy as np
import pytest

from identification.diagnose.run import run_diagnosis
from identification.rig import run_rig, write_run

EFFECTS = ("enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
           "periodic_disturbance")


def draw(effects, seed):
    """Rig parameters and the tire to diagnose for one randomized draw."""
    rng = np.random.default_rng(seed)
    p = {"speed_kmh": float(rng.choice([7.0, 10.0])), "sensor.rate_hz": float(rng.choice([500, 1000, 1500, 2000])),
         "sensor.noise_m_s2": float(rng.uniform(0.02, 0.1))}
    for tire, k0, c0 in (("FL", 550e3, 4200), ("FR", 520e3, 4300), ("RL", 420e3, 2400), ("RR", 450e3, 2500)):
        p[f"tire.{tire}.k_N_m"] = k0 * rng.uniform(0.9, 1.1)
        p[f"tire.{tire}.c_Ns_m"] = c0 * rng.uniform(0.85, 1.15)
    tire = str(rng.choice(["FL", "FR", "RL", "RR"]))
    if "enveloping" in effects:
        p["enveloping.footprint_front_m"] = rng.uniform(0.25, 0.5)
        p["enveloping.footprint_rear_m"] = rng.uniform(0.3, 0.5)
    if "lift_off" in effects:
        p["cleat.height_m"] = rng.uniform(0.04, 0.06)
        tire = str(rng.choice(["FL", "FR"]))   # the rear tires' static deflection exceeds the rebound
    if "axle_coupling" in effects:
        p["axle_coupling.pitch_dynamic_index"] = rng.uniform(0.6, 0.85)
        for left, right in (("FL", "FR"), ("RL", "RR")):   # the half-tractor assumes left-right symmetry
            p[f"tire.{right}.k_N_m"] = p[f"tire.{left}.k_N_m"]
            p[f"tire.{right}.c_Ns_m"] = p[f"tire.{left}.c_Ns_m"]
    if "nonlinear_stiffness" in effects:
        p["nonlinear_stiffness.exponent"] = rng.uniform(1.3, 2.0)
    if "friction_damping" in effects:
        p["friction_damping.force_N"] = rng.uniform(200, 500)
    if "periodic_disturbance" in effects:
        p["periodic_disturbance.amplitude_m"] = rng.uniform(0.0005, 0.002)
        if rng.random() < 0.5:
            p["periodic_disturbance.frequency_hz"] = rng.uniform(6, 30)
    return p, tire


def _seed(effects, index):
    return 1000 + 17 * index + 101 * len(effects) + sum(map(ord, "".join(effects)))


def _diagnose(effects, index):
    p, tire = draw(effects, _seed(effects, index))
    run = run_rig(effects, p, seed=_seed(effects, index))
    diag, gain = run_diagnosis(run.recording, tire, workers=1)
    return run, tire, diag, gain


def _assert_recovers_truth(run, tire, diag, gain):
    truth = run.truth["tires"][tire]
    assert diag.channels in ((tire,), tuple(sorted((tire, ("R" if tire[0] == "F" else "F") + tire[1]))))
    assert diag.final.params[f"k_{tire}"] == pytest.approx(truth["k"], rel=0.03)
    assert diag.final.params[f"c_{tire}"] == pytest.approx(truth["c"], rel=0.10)
    assert gain.nrmse_after[tire] <= gain.nrmse_before[tire] / 2, (gain.nrmse_before, gain.nrmse_after)
    assert gain.agreement <= 1e-6          # fitting model and FMU co-simulation


@pytest.mark.parametrize("index", range(3))
@pytest.mark.parametrize("effect", EFFECTS)
def test_hidden_effect_is_named_first(effect, index):
    run, tire, diag, gain = _diagnose((effect,), index)
    assert diag.effects[:1] == [effect], (diag.effects, tire, run.truth["parameters"]["speed_kmh"])
    assert effect in diag.evidence and diag.evidence[effect]
    _assert_recovers_truth(run, tire, diag, gain)


@pytest.mark.parametrize("index", range(3))
def test_baseline_recordings_name_no_effect(index):
    run, tire, diag, gain = _diagnose((), index)
    assert diag.effects == []
    assert diag.final.model.effects == diag.baseline.model.effects == frozenset()
    truth = run.truth["tires"][tire]
    assert diag.final.params[f"k_{tire}"] == pytest.approx(truth["k"], rel=0.01)
    assert diag.final.params[f"c_{tire}"] == pytest.approx(truth["c"], rel=0.03)


@pytest.mark.parametrize("other", ["lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
                                   "periodic_disturbance"])
def test_realistic_composites_name_both(other):
    run, tire, diag, gain = _diagnose(("enveloping", other), 0)
    assert set(diag.effects) >= {"enveloping", other}, diag.effects
    _assert_recovers_truth(run, tire, diag, gain)


def test_evidence_a_person_can_check():
    run, tire, diag, gain = _diagnose(("lift_off",), 0)
    text = diag.evidence["lift_off"]
    m = re.search(r"(FL|FR|RL|RR) hub at (-?\d\.\d\d) g for (\d+) ms from t = (\d+\.\d+) s", text)
    assert m, text
    tire, g_level, ms, start = m.group(1), float(m.group(2)), float(m.group(3)), float(m.group(4))
    assert abs(g_level + 1.0) < 0.2
    # the truth's longest contact-loss interval of that tire is the one described
    a, b = max(run.truth["tires"][tire]["contact_loss_s"], key=lambda ab: ab[1] - ab[0])
    assert start == pytest.approx(a, abs=0.01)
    assert ms == pytest.approx((b - a) * 1e3, abs=10)


def test_cli_json_fmu_plot_and_no_truth(cli, tmp_path):
    p, tire = draw(("enveloping",), _seed(("enveloping",), 0))
    run = run_rig(("enveloping",), p, seed=3)
    csv_path, truth_path = write_run(run, tmp_path / "rec")
    truth_path.unlink()   # the diagnosis must not need (or read) the truth
    res = cli("diagnose", csv_path, "--tire", tire, "--json", "--fmu", tmp_path / "ext.fmu",
              "--plot", tmp_path / "d.png", "--workers", "1")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert set(doc) == {"tire", "effects", "summary", "nrmse_before", "nrmse_after", "noise_nrmse", "unexplained",
                        "k", "c", "k_ci", "c_ci", "parameters", "evidence"}
    assert doc["tire"] == tire and doc["effects"][0] == "enveloping"
    assert doc["k_ci"][0] < doc["k"] < doc["k_ci"][1] and doc["c_ci"][0] < doc["c"] < doc["c_ci"][1]
    assert doc["parameters"]["footprint"]["unit"] == "m" and 0.1 < doc["parameters"]["footprint"]["value"] < 0.6
    assert doc["nrmse_after"] < doc["nrmse_before"] / 2
    assert set(doc["evidence"]) == set(doc["effects"])
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(tmp_path / "ext.fmu")) == []
    assert (tmp_path / "d.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the text form (on a one-hub recording of the same effect: the same command, a fraction of the fit)
    one, _ = write_run(run_rig(("enveloping",), {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=3),
                       tmp_path / "one")
    text = cli("diagnose", one, "--tire", "fl", "--workers", "1")
    assert text.code == 0 and "effects the four-corner model misses: enveloping" in text.out, text.out
    assert "FL: k " in text.out and "NRMSE" in text.out


def test_diagnosis_code_never_touches_the_truth():
    pkg = Path(__file__).parents[1] / "identification" / "diagnose"
    for path in pkg.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                assert "truth" not in node.value.lower() or node.value.startswith(("\n", " ")), path.name
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [a.name for a in node.names] + [getattr(node, "module", "") or ""]
                assert not any("rig" in n.split(".") for n in names), (path.name, names)


@pytest.mark.parametrize("args,needle", [(("--tire", "RR"), "tire RR is not in the recording"),
                                         (("--plot", "x.jpg"), "must end with .png"),
                                         (("--fmu", "x.zip"), "must end with .fmu")])
def test_cli_bad_input(cli, tmp_path, args, needle):
    run = run_rig((), {"sensor.channels": "FL"}, seed=1)
    csv_path, _ = write_run(run, tmp_path / "rec")
    res = cli("diagnose", csv_path, *args)
    assert res.code == 2 and res.out == "" and needle in res.err
    assert len(res.err.strip().splitlines()) == 1


def test_cli_single_channel_recording_falls_back_to_the_corner_model(cli, tmp_path):
    """A recording of one hub: the diagnosis runs on that channel alone (no pair, no body), per-tire JSON."""
    p, _ = draw(("enveloping",), _seed(("enveloping",), 1))
    run = run_rig(("enveloping",), dict(p, **{"sensor.channels": "RL"}), seed=5)
    csv_path, _ = write_run(run, tmp_path / "rec")
    res = cli("diagnose", csv_path, "--json", "--workers", "1")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert doc["tire"] == "RL" and doc["effects"] == ["enveloping"]
    assert doc["k"] == pytest.approx(run.truth["tires"]["RL"]["k"], rel=0.03)
    assert doc["c"] == pytest.approx(run.truth["tires"]["RL"]["c"], rel=0.10)
    assert doc["nrmse_after"] < doc["nrmse_before"] / 2
