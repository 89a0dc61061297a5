"""The virtual rig against an independent linear solution (python-control), and its convergence."""

import ast
from pathlib import Path

import control
import numpy as np
import pytest
from scipy import signal

from identification.rig import run_rig

FS = 1000.0
# 7.2 km/h = 2 m/s puts both cleat edges and the rear arrival on the 1 kHz sample grid,
# so the reference can be built from impulse responses sampled on that grid.
EXACT = {"speed_kmh": 7.2, "sensor.noise_m_s2": 0.0}


def control_reference(run, tire, *, aa_order, aa_hz, hp_hz):
    """Hub acceleration of the point-contact corner through the sensor chain, by python-control.

    The corner's transfer from road rate ṙ to hub acceleration is s(cs + k)/(ms² + cs + k);
    a rectangular cleat is ṙ = H δ(t - t1) - H δ(t - t2).
    """
    tt = run.truth["tires"][tire]
    m, k, c = tt["mass"], tt["k"], tt["c"]
    sys = control.ss(control.tf([c, k, 0.0], [m, c, k]))
    if aa_order:
        _, p, g = signal.buttap(aa_order)
        wc = 2 * np.pi * aa_hz
        sys = control.series(sys, control.ss(control.zpk([], p * wc, g * wc ** aa_order)))
    if hp_hz:
        sys = control.series(sys, control.ss(control.tf([1.0, 0.0], [1.0, 2 * np.pi * hp_hz])))
    if not aa_order:  # without a filter the impulse itself is not sampled
        sys = control.ss(sys.A, sys.B, sys.C, np.zeros_like(sys.D))
    n = run.recording.time_s.size
    resp = np.asarray(control.impulse_response(sys, np.arange(n) / FS).outputs).ravel()
    H = run.truth["parameters"]["cleat.height_m"]
    t1 = tt["arrival_s"]
    t2 = t1 + run.truth["parameters"]["cleat.width_m"] / (run.truth["parameters"]["speed_kmh"] / 3.6)
    y = np.zeros(n)
    for t_edge, sign in ((t1, 1.0), (t2, -1.0)):
        j = int(round(t_edge * FS))
        assert abs(j / FS - t_edge) < 1e-9
        y[j:] += sign * H * resp[: n - j]
    return y, (int(round(t1 * FS)), int(round(t2 * FS)))


def nrmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


@pytest.mark.parametrize("chain", [dict(aa_order=4, hp_hz=0.05), dict(aa_order=6, hp_hz=0.5),
                                   dict(aa_order=0, hp_hz=0.0)])
def test_baseline_matches_python_control(chain):
    run = run_rig((), dict(EXACT, **{"sensor.aa_order": chain["aa_order"], "sensor.highpass_hz": chain["hp_hz"]}))
    for tire in ("FL", "FR", "RL", "RR"):
        ref, edges = control_reference(run, tire, aa_hz=FS / 4, **chain)
        meas = run.recording.accel_m_s2[tire]
        if chain["aa_order"] == 0:  # the value exactly on a step is one-sided: skip those two samples
            keep = np.ones(ref.size, bool)
            keep[list(edges)] = False
            ref, meas = ref[keep], meas[keep]
        err = nrmse(meas, ref)
        assert err <= 0.005  # the acceptance floor
        assert err < 1e-5, (tire, err)  # what the solver actually achieves


def test_convergence_of_sensor_grid_and_integrator():
    errors = {}
    for over in (1, 2, 4, 8):
        run = run_rig((), dict(EXACT, **{"solver.oversample": over, "solver.rtol": 1e-11}))
        ref, _ = control_reference(run, "FL", aa_order=4, aa_hz=FS / 4, hp_hz=0.05)
        errors[over] = nrmse(run.recording.accel_m_s2["FL"], ref)
    # first-order hold: error ~ h², a factor ~4 per halving
    for a, b in ((1, 2), (2, 4), (4, 8)):
        assert errors[b] < errors[a] / 3, errors
    tol_err = {}
    for rtol in (1e-5, 1e-7, 1e-9, 1e-11):
        run = run_rig((), dict(EXACT, **{"solver.oversample": 16, "solver.rtol": rtol, "sensor.aa_order": 0,
                                         "sensor.highpass_hz": 0.0}))
        ref, edges = control_reference(run, "RL", aa_order=0, aa_hz=0, hp_hz=0)
        keep = np.ones(ref.size, bool)
        keep[list(edges)] = False
        tol_err[rtol] = nrmse(run.recording.accel_m_s2["RL"][keep], ref[keep])
    values = [tol_err[r] for r in (1e-5, 1e-7, 1e-9, 1e-11)]
    assert all(b < a for a, b in zip(values, values[1:])), tol_err
    assert values[-1] < 1e-8


def test_lift_off_events_converge():
    """Contact-loss instants and the response converge as the tolerance tightens."""
    runs = {rtol: run_rig(("lift_off",), {"sensor.noise_m_s2": 0.0, "solver.rtol": rtol})
            for rtol in (1e-6, 1e-8, 1e-10, 1e-12)}
    ref = runs[1e-12]
    loss_ref = np.array(ref.truth["tires"]["FL"]["contact_loss_s"])
    assert loss_ref.shape[0] >= 1
    prev = np.inf
    for rtol in (1e-6, 1e-8, 1e-10):
        loss = np.array(runs[rtol].truth["tires"]["FL"]["contact_loss_s"])
        assert loss.shape == loss_ref.shape
        err = float(np.max(np.abs(loss - loss_ref)))
        assert err <= prev
        prev = err
    assert prev < 1e-7
    diff = np.abs(runs[1e-10].accel_true_m_s2 - ref.accel_true_m_s2).max()
    assert diff < 1e-5


def test_rig_shares_no_model_code_with_the_pipeline():
    """The rig may use the recording format, errors and file writing - nothing else of the package.

    The format includes the sidecar's cleat profile (``identification.recording.cleat``), whose geometry
    ``tests/test_cleat_profile.py`` checks against independent references (np.interp, quadrature,
    python-control)."""
    allowed = {"errors", "recording", "_files", "cleat"}
    rig_dir = Path(__file__).parents[1] / "identification" / "rig"
    for path in rig_dir.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level >= 2:
                top = (node.module or "").split(".")[0]
                assert top in allowed, f"{path.name} imports identification.{node.module}"
            if isinstance(node, ast.Import) or (isinstance(node, ast.ImportFrom) and node.level == 0):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module]
                assert not any(n and n.startswith("identification") for n in names), path.name
