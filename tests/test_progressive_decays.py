"""A progressive tire told by its free decays' second harmonic, on recordings of the independent simulator.

Bristle-bed tires (``tests/independent/tires.py``): a rigid circle pressing a bed of bristles each of law
κ δ^p, whose force on flat ground integrates to F ∝ δ^(p + 1/2) (the contact length grows as √δ): p = 1/2 is
a linear tire, p ≈ 0.75 a progressive one of exponent ≈ 1.25.  The free decays' second harmonic must give that
exponent (within its interval) and hold n = 1 for the linear bed; and the whole diagnosis of the progressive
corners names the law, which its overall gain alone (4-5 % beside the footprint's misfit on this seed) never did.
Checked against the independent engine's tire laws, which share no code with the fitter.
"""

from __future__ import annotations

import warnings

import pytest

pytest.importorskip("exudyn", reason="the independent simulator needs exudyn (the test extra)")
warnings.filterwarnings("ignore", category=DeprecationWarning, module="exudyn")
pytestmark = pytest.mark.independent   # generated and diagnosed: CI's sweeps step (docs/testing.md)

from identification.diagnose.decay_shape import exponent_evidence  # noqa: E402
from identification.model.fitting import TractorProblem  # noqa: E402
from tests.independent_cases import assert_tires_hold_the_truth, independent_recording  # noqa: E402


@pytest.fixture(scope="module")
def progressive(tmp_path_factory):
    return independent_recording("corners progressive", 153, tmp_path_factory.mktemp("independent"))


def _law_exponents(truth) -> dict:
    return {w: t["exponent"] + 0.5 for w, t in truth["tires"].items()}


def test_the_decays_of_progressive_tires_give_their_exponent(progressive):
    rec, cutoff, truth = progressive
    verdict, (u, half), each = exponent_evidence(TractorProblem.from_recording(rec, cutoff_hz=cutoff), ())
    laws = _law_exponents(truth)
    assert min(laws.values()) > 1.15                                         # the case: progressive tires
    assert verdict == "progressive"
    assert len(each) >= 2, each
    for tire, est in each.items():
        assert est.n_ci[0] <= laws[tire] <= est.n_ci[1], (tire, est.n, est.n_ci, laws[tire])
    pooled = 1.0 / (1.0 - u)
    assert min(laws.values()) - 0.05 <= pooled <= max(laws.values()) + 0.05, (pooled, laws)


def test_the_decays_of_a_linear_bed_hold_n_equal_1(tmp_path):
    rec, cutoff, truth = independent_recording("corners", 112, tmp_path)
    assert set(_law_exponents(truth).values()) == {1.0}
    verdict, pooled, each = exponent_evidence(TractorProblem.from_recording(rec, cutoff_hz=cutoff), ())
    assert verdict == "linear", (pooled, {t: (e.n, e.n_ci) for t, e in each.items()})
    assert each                                                              # a decay counted


def test_no_decay_counts_under_a_named_body(progressive):
    rec, cutoff, _ = progressive
    verdict, pooled, each = exponent_evidence(TractorProblem.from_recording(rec, cutoff_hz=cutoff),
                                              ("axle_coupling", "roll_coupling"))
    assert (verdict, pooled, each) == ("no decay", None, {})


def test_the_diagnosis_names_the_progressive_law_the_decays_show(progressive):
    from identification.diagnose.joint_select import diagnose_tractor

    rec, cutoff, truth = progressive
    diagnosis = diagnose_tractor(rec, cutoff_hz=cutoff)
    assert sorted(diagnosis.effects) == sorted(truth["expected_effects"]), diagnosis.effects
    assert "the free decays' second harmonic agrees" in diagnosis.evidence["nonlinear_stiffness"]
    n = diagnosis.final.params["exponent"]
    laws = _law_exponents(truth)
    assert min(laws.values()) - 0.1 <= n <= max(laws.values()) + 0.1, (n, laws)
    # the joint fit's k (the tangent at the static load, the truth's k) and the decays' c where the joint c
    # strays: every tire within the 3 % and 10 %, its interval holding the truth
    assert_tires_hold_the_truth(diagnosis, truth, c_interval=True)
