"""What the diagnosis reports per tire beside the joint fit: a collapsed joint fit (k or c outside the range it
searches) is replaced by the channel's own fit with the whole range as its interval, and said so.

The rig's truth is the reference; the diagnosis never reads it."""

import dataclasses

import numpy as np
import pytest

from identification.diagnose.free_decay import collapsed, free_decay_check
from identification.diagnose.joint_fit import fit_tractor
from identification.diagnose.joint_select import TractorDiagnosis
from identification.diagnose.joint_start import starting_values
from identification.diagnose.run import diagnosis_warnings
from identification.model.fitting import TractorFitModel, TractorProblem
from identification.rig import run_rig


@pytest.fixture(scope="module")
def corners():
    run = run_rig((), {"duration_s": 4.0, "speed_kmh": 10.0}, seed=8)
    pb = TractorProblem.from_recording(run.recording)
    start = starting_values(pb)
    model = TractorFitModel((), pb)
    fit = fit_tractor(model, {n: start[n] for n in model.names}, budget=200)
    return run, pb, start, fit


def _diagnosis(pb, start, fit, final):
    return TractorDiagnosis(problem=pb, effects=[], baseline=fit, final=final, rounds=[], evidence={},
                            unexplained={t: None for t in pb.channels}, seconds=0.0, extra={"start": start})


def test_a_sound_fit_is_not_collapsed_and_keeps_its_own_values(corners):
    run, pb, start, fit = corners
    diag = _diagnosis(pb, start, fit, fit)
    assert not any(collapsed(diag, t) for t in pb.channels)
    diag.extra["free_decay"] = free_decay_check(diag)
    for t, doc in diag.to_json()["tires"].items():
        assert doc["k_source"] in ("joint_fit", "free_decay")
        assert abs(doc["k"] / run.truth["tires"][t]["k"] - 1) < 0.03


@pytest.mark.parametrize("name, value", [("k_RL", 1e-6), ("k_RL", 1e9), ("c_RL", 1e-3)])
def test_a_collapsed_tire_reports_its_channel_fit_with_the_range_searched(corners, name, value, monkeypatch):
    """Its free decay no check (made so here): the channel's own fit, each interval the range searched."""
    from identification.diagnose import free_decay

    monkeypatch.setattr(free_decay, "MIN_DECAY_R2", 1.01)
    monkeypatch.setattr(free_decay, "DECAY_AT_NOISE", 0.0)
    run, pb, start, fit = corners
    broken = dataclasses.replace(fit, params={**fit.params, name: value})
    diag = _diagnosis(pb, start, fit, broken)
    assert [t for t in pb.channels if collapsed(diag, t)] == ["RL"]
    diag.extra["free_decay"] = free_decay_check(diag)
    doc = diag.to_json()["tires"]
    rl, truth = doc["RL"], run.truth["tires"]["RL"]
    assert rl["k_source"] == "channel_fit"
    assert abs(rl["k"] / truth["k"] - 1) < 0.05 and abs(rl["c"] / truth["c"] - 1) < 0.25   # a clean corner
    assert rl["k_ci"] == pytest.approx([0.2 * rl["k"], 5.0 * rl["k"]])                    # the range searched
    assert rl["k_ci"][0] <= truth["k"] <= rl["k_ci"][1] and rl["c_ci"][0] <= truth["c"] <= rl["c_ci"][1]
    assert all(doc[t]["k_source"] != "channel_fit" for t in ("FL", "FR", "RR"))
    warning = [w for w in diagnosis_warnings(diag, _NoGain()) if w.startswith("RL: the joint fit collapsed")]
    assert len(warning) == 1 and "not determined by the data" in warning[0]


@pytest.mark.parametrize("name, value", [("k_RL", 1e-6), ("c_RL", 1e-3)])
def test_a_collapsed_tire_with_a_valid_free_decay_reports_the_decay(corners, name, value):
    """The rig's clean corner decays as one damped mode: a collapsed RL is reported as its free decay's k and c,
    with the decay's intervals (which hold the rig's truth and are far narrower than the range searched), and
    the warning says why."""
    run, pb, start, fit = corners
    broken = dataclasses.replace(fit, params={**fit.params, name: value})
    diag = _diagnosis(pb, start, fit, broken)
    diag.extra["free_decay"] = check = free_decay_check(diag)
    assert check["RL"]["decay_only"] and check["RL"]["joint_collapsed"] and not check["RL"].get("collapsed")
    doc = diag.to_json()["tires"]
    rl, truth = doc["RL"], run.truth["tires"]["RL"]
    assert rl["k_source"] == "free_decay" and rl["c_source"] == "free_decay"
    assert rl["k"] == check["RL"]["k"] and rl["k_ci"] == check["RL"]["k_ci"] and rl["c_ci"] == check["RL"]["c_ci"]
    for q in ("k", "c"):
        assert rl[f"{q}_ci"][0] <= truth[q] <= rl[f"{q}_ci"][1], q
    assert rl["k_ci"][1] / rl["k_ci"][0] < 1.2                       # the decay's, not the range searched
    warning = [w for w in diagnosis_warnings(diag, _NoGain()) if w.startswith("RL: the joint fit collapsed")]
    assert len(warning) == 1 and "k and c are the free decay's" in warning[0]


class _NoGain:
    note = final_note = None


def test_a_disagreement_with_the_channel_fit_is_said_even_where_it_is_no_check(corners):
    """A body named: the channel's waveform fit is no check of the joint fit (the hub rings in the body's mode),
    but a joint k 40 % off it, beyond both intervals, is said, with why; the joint values stand."""
    run, pb, start, fit = corners
    k = fit.params["k_RL"] * 1.4
    moved = dataclasses.replace(fit, params={**fit.params, "k_RL": k}, ci={**fit.ci, "k_RL": (0.99 * k, 1.01 * k)})
    diag = dataclasses.replace(_diagnosis(pb, start, fit, moved), effects=["axle_coupling"])
    check = free_decay_check(diag)
    assert not check["RL"]["valid"] and check["RL"]["k_apart"] > 1
    assert check["RL"]["reason"].startswith("RL: the joint fit's k +4")
    assert " % from the channel's waveform fit's " in check["RL"]["reason"]
    # the other fit's value, in kN/m (it once printed the bare number in N/m in place of whose it was)
    other_kN = float(check["RL"]["reason"].split("waveform fit's ", 1)[1].split(" kN/m (", 1)[0])
    assert other_kN == pytest.approx(check["RL"]["k"] / 1e3, rel=1e-3)
    assert "which is no check here (axle_coupling named" in check["RL"]["reason"]
    assert all(check[t]["reason"] is None for t in ("FL", "FR", "RR"))
    diag.extra["free_decay"] = check
    assert diag.to_json()["tires"]["RL"]["k"] == k                      # the joint fit's value stands


def test_a_channel_the_model_leaves_largely_unexplained_gets_the_range_searched(corners):
    """RL's k 1.6x its truth (a model that does not describe that hub), a body named (the free decay is then
    no check to fall back on): the misfit left in RL's channel is far beyond UNDETERMINED_SHARE of its
    signal, so RL's intervals are the whole range searched, which holds the truth, and a warning gives the
    share; the other tires keep their joint intervals.  (Without a body, the free decay's values would be
    reported instead.)"""
    from identification.diagnose.free_decay import UNDETERMINED_SHARE
    from identification.diagnose.joint_fit import unexplained

    run, pb, start, fit = corners
    params = {**fit.params, "k_RL": 1.6 * run.truth["tires"]["RL"]["k"]}
    pred = fit.model.predict(params)
    wrong = dataclasses.replace(fit, params=params, prediction=pred)
    diag = dataclasses.replace(_diagnosis(pb, start, fit, wrong), effects=["axle_coupling"],
                               unexplained={t: unexplained(pb, pred, t) for t in pb.channels})
    assert diag.unexplained["RL"]["share"] > UNDETERMINED_SHARE
    assert all(diag.unexplained[t] is None for t in ("FL", "FR", "RR"))
    diag.extra["free_decay"] = check = free_decay_check(diag)
    assert check["RL"].get("undetermined") and not any(check[t].get("undetermined") for t in ("FL", "FR", "RR"))
    doc = diag.to_json()["tires"]
    rl, truth = doc["RL"], run.truth["tires"]["RL"]
    assert rl["k"] == params["k_RL"] and rl["k_source"] == "joint_fit"            # the value stands
    assert rl["k_ci"][0] <= truth["k"] <= rl["k_ci"][1] and rl["c_ci"][0] <= truth["c"] <= rl["c_ci"][1]
    assert rl["k_ci"][1] / rl["k_ci"][0] > 10                                      # not determined
    for t in ("FL", "FR", "RR"):
        assert doc[t]["k_source"] == "joint_fit" and doc[t]["k_ci"] == pytest.approx(list(fit.ci[f"k_{t}"]))
    warning = [w for w in diagnosis_warnings(diag, _NoGain()) if "of this channel's signal unexplained" in w]
    assert len(warning) == 1 and warning[0].startswith("RL") and "not determined by the data" in warning[0]


def test_an_undetermined_corner_reports_its_own_channel_fit_within_the_range_searched(corners, monkeypatch):
    """No body named: the joint fit's RL (k 1.6x its truth) leaves far more than UNDETERMINED_SHARE of its
    channel unexplained and the free decay is no check of it (its decay's R² made too low here): RL's k and c
    are the channel's own fit's, which on this clean corner is near the truth, each interval the range
    searched (holding the truth), and the warning says so."""
    from identification.diagnose import free_decay
    from identification.diagnose.joint_fit import unexplained
    from identification.diagnose.joint_start import tire_start

    run, pb, start, fit = corners
    params = {**fit.params, "k_RL": 1.6 * run.truth["tires"]["RL"]["k"]}
    pred = fit.model.predict(params)
    wrong = dataclasses.replace(fit, params=params, prediction=pred)
    diag = dataclasses.replace(_diagnosis(pb, start, fit, wrong),
                               unexplained={t: unexplained(pb, pred, t) for t in pb.channels})
    monkeypatch.setattr(free_decay, "MIN_DECAY_R2", 1.01)   # no free decay passes: the undetermined path decides
    monkeypatch.setattr(free_decay, "DECAY_AT_NOISE", 0.0)
    diag.extra["free_decay"] = check = free_decay_check(diag)
    assert check["RL"].get("undetermined") and not any(check[t].get("undetermined") for t in ("FL", "FR", "RR"))
    doc = diag.to_json()["tires"]
    rl, truth = doc["RL"], run.truth["tires"]["RL"]
    k, c = tire_start(pb, "RL")
    assert rl["k_source"] == "channel_fit" and rl["k"] == pytest.approx(k) and rl["c"] == pytest.approx(c)
    assert abs(rl["k"] / truth["k"] - 1) < 0.03 and abs(rl["c"] / truth["c"] - 1) < 0.25
    assert rl["k_ci"][0] <= truth["k"] <= rl["k_ci"][1] and rl["k_ci"][1] / rl["k_ci"][0] > 10
    assert rl["parameters"]["k"]["value"] == params["k_RL"]          # the extended model keeps its own
    assert all(doc[t]["k_source"] != "channel_fit" for t in ("FL", "FR", "RR"))
    warning = [w for w in diagnosis_warnings(diag, _NoGain()) if "of this channel's signal unexplained" in w]
    assert len(warning) == 1 and "the channel's own fit's" in warning[0]


def test_a_channel_left_above_its_noise_floor_takes_the_free_decays_c_and_keeps_the_joint_k(corners):
    """The joint values inside the free decay's interval: at the noise floor they stand; with a residual
    above it (here 3x the noise in FL, 5 % of its signal) FL's c is the free decay's, with its interval, and k
    stays the joint fit's."""
    run, pb, start, fit = corners
    left = {"share": 0.05, "window": [1.0, 1.2], "residual_to_noise": 3.0}
    k = 1.04 * fit.params["k_RL"]          # RL's joint k pulled 4 %, outside the decay's interval
    pulled = dataclasses.replace(fit, params={**fit.params, "k_RL": k}, ci={**fit.ci, "k_RL": (0.995 * k, 1.005 * k)})
    diag = dataclasses.replace(_diagnosis(pb, start, fit, pulled), unexplained={**{t: None for t in pb.channels},
                                                                                "FL": left})
    diag.extra["free_decay"] = check = free_decay_check(diag)
    assert check["FL"]["valid"] and not check["FL"]["prefer"] and check["FL"]["prefer_c"]
    assert not any(check[t]["prefer_c"] for t in ("FR", "RL", "RR"))
    assert check["RL"]["prefer"] and doc_c_source(diag, "RL") == "free_decay"   # outside: both the decay's
    assert all(not check[t]["prefer"] for t in ("FL", "FR", "RR"))              # the exact rig: inside
    doc = diag.to_json()["tires"]
    rl = doc["FL"]
    assert rl["c_source"] == "free_decay" and rl["c"] == check["FL"]["c"]
    assert rl["c_ci"][0] <= min(check["FL"]["c"], fit.params["c_FL"]) <= max(check["FL"]["c"], fit.params["c_FL"]) \
        <= rl["c_ci"][1]
    assert rl["k_source"] == "joint_fit" and rl["k"] == fit.params["k_FL"]
    assert all(doc[t]["c_source"] == "joint_fit" and doc[t]["c"] == fit.params[f"c_{t}"] for t in ("FR", "RR"))
    # the free decay's values with its own interval, which holds the rig's truth and carries the floor of a
    # rolling tire's decay (DECAY_FLOOR: at least 1 % of the value on each side)
    for tire, q in (("RL", "k"), ("RL", "c"), ("FL", "c")):
        lo, hi = doc[tire][f"{q}_ci"]
        assert [lo, hi] == pytest.approx(check[tire][f"{q}_ci"]), (tire, q)
        assert lo <= run.truth["tires"][tire][q] <= hi, (tire, q)
        assert min(doc[tire][q] - lo, hi - doc[tire][q]) >= 0.01 * doc[tire][q], (tire, q)


def doc_c_source(diag, tire):
    return diag.to_json()["tires"][tire]["c_source"]


def test_a_named_steady_line_is_taken_out_of_the_channel_before_its_free_decay_is_fitted(corners):
    """A 19 Hz line a tenth of the impact's peak, riding on a clean corner's channel (the rig's recording, no lugs): taken out at the fitted
    lug frequency (or, not named, at the quiet stretch's line refined on the record), the channel is the clean one again to 3 % of the line's amplitude, and the free decay's
    k and c are the clean channel's; left in, they are not."""
    import numpy as np

    from identification.diagnose.free_decay import _without_the_line
    from identification.identify.waveform import identify_waveform
    from identification.recording import STANDARD_GRAVITY
    from identification.recording.preprocess import preprocess

    run, pb, start, fit = corners
    rec = run.recording
    amp = 0.1 * float(np.max(np.abs(rec.accel_m_s2["FL"])))
    line = amp * np.sin(2 * np.pi * 19.0 * rec.time_s + 0.7)
    lined = dataclasses.replace(rec, accel_m_s2={**rec.accel_m_s2, "FL": rec.accel_m_s2["FL"] + line})
    final = dataclasses.replace(fit, params={**fit.params, "lug_frequency_front": 19.0})
    diag = dataclasses.replace(_diagnosis(pb, start, fit, final), effects=["periodic_disturbance"])
    cleaned = _without_the_line(lined, "FL", diag)
    assert np.max(np.abs(cleaned.accel_m_s2["FL"] - rec.accel_m_s2["FL"])) < 0.03 * amp     # (the impact projects)
    assert cleaned.accel_m_s2["FR"] is rec.accel_m_s2["FR"]
    assert _without_the_line(lined, "FL", _diagnosis(pb, start, fit, final)) is lined   # no line named or found
    # not named, but found in the quiet stretch (a periodogram's peak, 0.3 Hz off): refined on the record, the
    # same line is taken out
    found = dataclasses.replace(pb, steady_lines={"FL": {"share": 0.9, "frequency_hz": 19.3, "quiet_rms": amp}})
    unnamed = _without_the_line(lined, "FL", _diagnosis(found, start, fit, final))
    assert np.max(np.abs(unnamed.accel_m_s2["FL"] - rec.accel_m_s2["FL"])) < 0.1 * amp   # (the impact pulls f)

    def decay(r):
        sig = preprocess(r, ["FL"], cutoff_hz=pb.cutoff_hz, min_peaks=1)["FL"]
        return identify_waveform(sig, r.wheel_load_N["FL"] / STANDARD_GRAVITY)

    clean, fixed, found = decay(rec), decay(cleaned), decay(unnamed)
    assert abs(fixed.k / clean.k - 1) < 1e-3 and abs(fixed.c / clean.c - 1) < 1e-2
    assert abs(found.k / clean.k - 1) < 1e-3 and abs(found.c / clean.c - 1) < 1e-2, (found.k / clean.k, found.c / clean.c)
    from identification.errors import InputError
    try:
        raw = decay(lined)
    except InputError:          # (a line half the impact's peak: no decaying oscillation found at all)
        return
    assert abs(raw.k / clean.k - 1) > 3e-3 or abs(raw.c / clean.c - 1) > 3e-2


@pytest.fixture(scope="module")
def rigid():
    """The rig's rigid tractor (its ``axle_coupling``), diagnosed with the rigid body named."""
    run = run_rig(("axle_coupling",), {"duration_s": 4.0, "speed_kmh": 10.0}, seed=8)
    pb = TractorProblem.from_recording(run.recording)
    start = starting_values(pb)
    model = TractorFitModel(("axle_coupling", "roll_coupling"), pb)
    theta = {n: start.get(n, {"pitch_index": 0.9, "roll_index": 0.6}.get(n)) for n in model.names}
    fit = fit_tractor(model, theta, budget=300)
    diag = dataclasses.replace(_diagnosis(pb, start, fit, fit), effects=["axle_coupling", "roll_coupling"])
    return run, pb, start, fit, diag


@pytest.mark.parametrize("shift_measured", [True, False])
def test_a_named_rigid_body_is_checked_against_its_own_free_decay(rigid, shift_measured, monkeypatch):
    """Under the rigid body a channel's own decay is the body's mode: the body's free decay over the tail
    (all four channels, :mod:`identification.diagnose.body_decay`) is the check, and it holds the rig's truth;
    a joint k outside its interval is replaced by the decay's with the decay's own interval, which carries the
    floor; where the decay's window shift could not be measured, the interval is stretched to hold both (the
    body's decay rests on the whole body's model)."""
    import identification.diagnose.body_decay as bd

    if not shift_measured:
        monkeypatch.setattr(bd, "_window_shift", lambda *a: (np.zeros(a[4].size), False))
    run, pb, start, fit, diag = rigid
    check = free_decay_check(diag)
    assert all(check[t]["shift_measured"] is shift_measured for t in pb.channels)
    truth = run.truth["tires"]
    for t in pb.channels:
        assert check[t]["valid"] and check[t]["body_decay"], check[t]
        assert check[t]["k"] == pytest.approx(truth[t]["k"], rel=0.02)
        assert check[t]["k_ci"][0] <= truth[t]["k"] <= check[t]["k_ci"][1]
    k = fit.params["k_RL"] * 1.3
    moved = dataclasses.replace(fit, params={**fit.params, "k_RL": k}, ci={**fit.ci, "k_RL": (0.99 * k, 1.01 * k)})
    diag2 = dataclasses.replace(diag, final=moved)
    diag2.extra["free_decay"] = check2 = free_decay_check(diag2)
    assert check2["RL"]["prefer"] and "rigid tractor's free decay" in check2["RL"]["reason"]
    rl = diag2.to_json()["tires"]["RL"]
    assert rl["k_source"] == "free_decay" and rl["k"] == pytest.approx(check2["RL"]["k"])
    own = check2["RL"]["k_ci"]
    assert rl["k_ci"][0] <= truth["RL"]["k"] <= rl["k_ci"][1]
    if shift_measured:
        assert rl["k_ci"] == pytest.approx(own) and rl["k_ci"][1] < k and "stretched" not in check2["RL"]["reason"]
    else:
        assert rl["k_ci"][1] >= 1.01 * k and "stretched" in check2["RL"]["reason"]     # holds both
    assert min(check2["RL"]["k"] - own[0], own[1] - check2["RL"]["k"]) >= 0.01 * check2["RL"]["k"]   # the floor


def test_a_body_decay_that_does_not_count_says_why(rigid, monkeypatch):
    """With a bound the decay cannot meet, the check falls back to the channels' fits and says why."""
    import identification.diagnose.body_decay as bd

    run, pb, start, fit, diag = rigid
    monkeypatch.setattr(bd, "MAX_RESIDUAL_TO_NOISE", 0.1)
    check = free_decay_check(diag)
    assert all(not check[t]["valid"] and not check[t].get("body_decay") for t in pb.channels)
    assert all("the body's free decay leaves" in check[t]["why_not"] for t in pb.channels
               if "why_not" in check[t] and check[t]["why_not"] and "waveform" not in check[t]["why_not"])


@pytest.mark.parametrize("signal_to_noise, valid, body", [(5.0, True, False), (2.0, False, False), (5.0, False, True)])
def test_a_small_decay_is_a_check_where_its_residual_is_the_noise(corners, signal_to_noise, valid, body):
    """White noise added to RL until its free decay stands 5x (2x) above it: one damped mode then explains the
    decay only to R² ~ 1 - 1/25 (1 - 1/4), below MIN_DECAY_R2, but its residual is the noise (the noise before
    the impact, the closed form's reference), so at 5x the decay still checks the joint fit, with an interval
    that holds the rig's truth; buried at 2x it does not.  Where RR moves from the first impact on (a 2 Hz body
    motion at 10x its noise), a body carries the hubs and the 5x decay does not count either, and says so."""
    import numpy as np

    from identification.diagnose import free_decay
    from identification.identify.waveform import identify_waveform
    from identification.recording import STANDARD_GRAVITY
    from identification.recording.preprocess import preprocess

    run, pb, start, fit = corners
    rec = pb.rec
    mass = rec.wheel_load_N["RL"] / STANDARD_GRAVITY
    sig = preprocess(rec, ["RL"], cutoff_hz=pb.cutoff_hz, min_peaks=1)["RL"]
    wave = identify_waveform(sig, mass)
    window = (sig.time_s >= wave.window_s[0]) & (sig.time_s <= wave.window_s[1])
    sigma = float(np.std(sig.raw_m_s2[window])) / signal_to_noise
    x = rec.accel_m_s2["RL"] + np.random.default_rng(3).normal(0.0, sigma, rec.time_s.size)
    accel = {**rec.accel_m_s2, "RL": x}
    if body:
        from identification.identify.waveform import noise_before

        rr = rec.accel_m_s2["RR"]
        sway = 10 * np.sqrt(2) * noise_before(rec.time_s, rr, pb.first_impact_s) * \
            np.sin(2 * np.pi * 2.0 * (rec.time_s - pb.first_impact_s))
        accel["RR"] = rr + np.where(rec.time_s >= pb.first_impact_s, sway, 0.0)
    noisy = dataclasses.replace(rec, accel_m_s2=accel)
    diag = _diagnosis(dataclasses.replace(pb, rec=noisy), start, fit, fit)
    entry = free_decay_check(diag)["RL"]
    assert entry["r2"] < free_decay.MIN_DECAY_R2
    assert entry["residual_to_noise"] == pytest.approx(1.0, abs=0.05)
    assert entry["signal_to_noise"] == pytest.approx(signal_to_noise, rel=0.1)
    assert entry["valid"] is valid
    if valid:
        truth = run.truth["tires"]["RL"]
        assert entry["k_ci"][0] <= truth["k"] <= entry["k_ci"][1] and entry["c_ci"][0] <= truth["c"] <= entry["c_ci"][1]
    elif body:
        assert entry["moves_before_impact"]["RR"] > free_decay.MOVES_BEFORE_IMPACT
        assert "a body the diagnosis did not name carries this decay" in entry["why_not"]
    else:
        assert entry["why_not"].startswith("the free decay is no damped sinusoid")


def test_a_later_hub_moves_before_its_own_impact_only_on_a_body(corners):
    """On the rig's independent corners every later channel is quiet (its noise) until its own impact; on its
    rigid tractor the rear hubs move with the front impact first, beyond MOVES_BEFORE_IMPACT, so no collapsed
    tire's decay and no noise-level decay counts there."""
    from identification.diagnose.free_decay import MOVES_BEFORE_IMPACT, moves_before_impact

    run, pb, start, fit = corners
    quiet = moves_before_impact(pb)
    assert {"RL", "RR"} <= set(quiet) and all(0.7 < v < 1.3 for v in quiet.values())
    rigid = run_rig(("axle_coupling",), {"duration_s": 4.0, "speed_kmh": 10.0}, seed=8)
    moved = moves_before_impact(TractorProblem.from_recording(rigid.recording))
    assert min(moved["RL"], moved["RR"]) > MOVES_BEFORE_IMPACT
