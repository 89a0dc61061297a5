""""none" is said of a diagnosis only where every channel is at its noise floor: where the final model leaves
channels above it, the command line and the report say which, and how much is left."""

from __future__ import annotations

import types

import pytest

from identification.diagnose.joint_select import diagnose_tractor
from identification.diagnose.wording import effects_sentence
from identification.rig import run_rig


def _doc(effects, shares):
    return {"effects": effects, "tires": {t: {"unexplained": None if s is None else
                                              {"share": s, "window": [0.5, 1.2], "residual_to_noise": 9.0}}
                                          for t, s in shares.items()}}


def test_none_alone_only_where_every_channel_is_at_its_noise_floor():
    assert effects_sentence(_doc([], {"FL": None, "FR": None})) == \
        "none: the four-corner model explains every channel to within its noise"
    assert effects_sentence(_doc(["enveloping"], {"FL": None, "FR": None})) == "enveloping"
    text = effects_sentence(_doc([], {"FL": 0.97, "FR": None, "RL": 0.42}))
    assert text.startswith("none named, yet the four-corner model leaves FL, RL above the noise floor")
    assert "up to 97 % of a channel's signal energy" in text
    assert "up to 100 % of" in effects_sentence(_doc([], {"FL": 0.99995}))     # never "1e+02 %"
    assert "up to 326 % of" in effects_sentence(_doc([], {"FL": 3.26}))        # a model worse than none
    assert "up to 6.8 % of" in effects_sentence(_doc([], {"FL": 0.068}))
    text = effects_sentence(_doc(["enveloping", "lift_off"], {"FL": None, "RR": 0.35}))
    assert text == ("enveloping, lift_off; the extended model still leaves RR above the noise floor (up to 35 % "
                    "of a channel's signal energy left)")


@pytest.fixture(scope="module")
def unexplained_diagnosis():
    """A rig recording whose tires envelop the cleat, diagnosed with no candidate effect: the point-contact
    baseline leaves the footprint's smoother impact above the noise floor."""
    run = run_rig(("enveloping",), {"duration_s": 5.0}, seed=4)
    return diagnose_tractor(run.recording, effects=())


def test_a_diagnosis_that_names_nothing_but_leaves_a_residual_says_so(unexplained_diagnosis):
    doc = unexplained_diagnosis.to_json()
    left = [t for t, v in doc["tires"].items() if v["unexplained"]]
    assert doc["effects"] == [] and left          # the case: nothing named, residual above the noise
    text = effects_sentence(doc)
    assert text.startswith("none named, yet the four-corner model leaves " + ", ".join(left))
    assert "within its noise" not in text
    assert doc["summary"] == text                 # the JSON carries the first line's words
    for tire in doc["tires"]:                     # --tire's JSON: that tire's residual and words alone
        one = unexplained_diagnosis.tire_json(tire)
        assert one["unexplained"] == doc["tires"][tire]["unexplained"]
        assert one["noise_nrmse"] == doc["tires"][tire]["noise_nrmse"]
        others = [t for t in doc["tires"] if t != tire]
        assert (one["summary"].startswith(f"none named, yet the four-corner model leaves {tire} above")
                if one["unexplained"] else one["summary"].startswith("none: ")), one["summary"]
        assert not any(f" {t} " in one["summary"] or f" {t}," in one["summary"] for t in others), one["summary"]


def test_the_report_does_not_call_an_unexplained_diagnosis_within_noise(unexplained_diagnosis):
    from identification.report.html import _diagnosis_section

    doc = unexplained_diagnosis.to_json()
    doc.update(agreement=0.0, seconds=1.0, intervals="conditional on the model")
    r = types.SimpleNamespace(stem="run", diagnosis=types.SimpleNamespace(diagnosis=doc, errors=[], figures={},
                                                                          ride=None))
    html = _diagnosis_section(r)
    assert "within noise" not in html and "within its noise" not in html
    assert "none named, yet the four-corner model leaves" in html


def test_a_recording_the_model_explains_is_called_so():
    run = run_rig((), {"duration_s": 5.0}, seed=4)
    doc = diagnose_tractor(run.recording, effects=()).to_json()
    assert all(v["unexplained"] is None for v in doc["tires"].values())
    assert effects_sentence(doc) == "none: the four-corner model explains every channel to within its noise"
