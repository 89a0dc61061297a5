"""When the whole-tractor diagnosis runs its selection again from another start (the rescue's scaled search,
the searches with the responses' scale fitted): only from a start that is new, not from where the first
selection began or ended (``joint_select._new_start``; docs/method/diagnosis.md)."""

from __future__ import annotations

import pytest

from identification.diagnose.joint_select import OTHER_TIMING_S, OTHER_TIRES, _new_start

TIRES = {"k_FL": 5.2e5, "c_FL": 3800.0, "k_RR": 4.1e5, "c_RR": 2600.0}
TIMING = {"arrival": 0.7475, "stagger": -0.029, "delay": 1.0685}
ENVELOPED = {"arrival": 0.7545, "stagger": -0.023, "delay": 1.0625}
FITTED = {"arrival": 0.7065, "stagger": 0.0105, "delay": 1.0962}   # where the first selection ended


def _start(tires=TIRES, timing=TIMING, enveloped=ENVELOPED):
    return {**tires, **timing, "enveloped": dict(enveloped)}


def _moved(timing, name, by):
    return dict(timing, **{name: timing[name] + by})


def test_the_first_start_or_where_the_selection_ended_is_not_new():
    start0 = _start()
    assert not _new_start(_start(), start0, FITTED)
    assert not _new_start(_start(timing=_moved(FITTED, "arrival", 0.6 * OTHER_TIMING_S)), start0, FITTED)
    assert not _new_start(_start(timing=_moved(TIMING, "delay", -0.6 * OTHER_TIMING_S)), start0, FITTED)
    k = dict(TIRES, k_FL=TIRES["k_FL"] * (1 + 0.5 * OTHER_TIRES))
    assert not _new_start(_start(tires=k), start0, FITTED)


@pytest.mark.parametrize("name", ["arrival", "stagger", "delay"])
def test_arrivals_off_both_the_start_and_the_fit_are_new(name):
    beyond = max(TIMING[name], FITTED[name]) + 2 * OTHER_TIMING_S    # one quantity off both, the rest the start's
    assert _new_start(_start(timing=dict(TIMING, **{name: beyond})), _start(), FITTED)
    # off the start but where the selection ended: not new
    at_fit = dict(TIMING, **{name: FITTED[name]})
    assert not _new_start(_start(timing=at_fit), _start(), at_fit)


def test_scaled_tires_or_other_enveloped_arrivals_are_new():
    start0 = _start()
    scaled = {n: v * (0.55 if n.startswith("k_") else 1.0) for n, v in TIRES.items()}
    assert _new_start(_start(tires=scaled, timing=FITTED), start0, FITTED)
    assert _new_start(_start(timing=FITTED, enveloped=_moved(ENVELOPED, "stagger", 2 * OTHER_TIMING_S)),
                      start0, FITTED)
