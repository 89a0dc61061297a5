"""One answer per tire and test condition over a campaign of repeated runs.

A batch may hold several runs of one tire under one condition (the cleat-test paper's Table 4: several runs
per speed).  Each run's joint diagnosis gives k and c with a 95 % interval from its own fit: sensor noise
and model error inside that run.  Test-to-test scatter (the tire's temperature, the line driven, the
cleat's position, the driver's speed) is not in it: the paper's repeated runs scatter by about ±8 %, while
one run's interval is a fraction of a percent wide.  This module pools the runs of a condition into one
value per tire with an interval that holds that scatter.

**Estimator** (:func:`pool_runs`): the random-effects mean of the runs, each run i an estimate y_i with a
within-run variance v_i = s_i² and the condition's between-run variance τ² (DerSimonian & Laird 1986,
Controlled Clinical Trials 7:177-188).  τ² by restricted maximum likelihood (REML; Viechtbauer 2005,
J. Educ. Behav. Stat. 30:261-293; Fisher scoring), the mean μ weighted by
w_i = 1/(v_i + τ²), and its interval by Hartung-Knapp-Sidik-Jonkman (Hartung & Knapp 2001, Stat. Med.
20:3875-3889; Sidik & Jonkman 2002, Stat. Med. 21:3153-3159):

    μ ± t(0.975, n-1) · sqrt(q / Σ w_i),   q = max(1, Σ w_i (y_i - μ)² / (n - 1)),

with the ``max(1, ·)`` of Knapp & Hartung (2003, Stat. Med. 22:2693-2710; Röver, Knapp & Friede 2015,
BMC Med. Res. Methodol. 15:99) so that a few runs that happen to agree closely never give an interval
narrower than their fit intervals allow.  Why this one: a campaign has 2-5 runs per condition, where the
DerSimonian-Laird interval with a normal quantile covers far below 95 % (it ignores that τ² is estimated
from n-1 degrees of freedom), and the HKSJ interval with a t quantile on n-1 degrees of freedom is near
nominal (IntHout, Ioannidis & Borm 2014, BMC Med. Res. Methodol. 14:25).  When the runs' fit intervals
are much narrower than their scatter (the usual case: ±0.05 % against ±8 %), the weights are equal and
the interval is exactly the t interval of the runs' mean, mean ± t(0.975, n-1) · SD/√n, whose coverage is
exact for normal scatter; for three runs it always holds every run.

**Disagreement**: Cochran's Q = Σ (y_i - ȳ)²/v_i about the fixed-effect mean ȳ, on n-1 degrees of
freedom (Cochran 1954, Biometrics 10:101-129), and I² = max(0, (Q - (n-1))/Q) (Higgins & Thompson 2002,
Stat. Med. 21:1539-1558).  The runs *disagree beyond their intervals* when P(χ²(n-1) > Q) < 0.05: their
fit intervals then understate the uncertainty, and only the pooled interval is to be used.

**Conditions** (:func:`group_runs`): runs of one condition share the tire position, the speed (every
run within 0.5 km/h of the group's slowest, :data:`SPEED_TOLERANCE_KMH`), the static wheel load of that
tire (within 2 % of the group's first run, :data:`LOAD_RTOL`), its inflation pressure (the sidecar's
``inflation_pressure_kPa``, within 5 % of the group's first run, :data:`PRESSURE_RTOL`; a run without one
is only pooled with runs without one) and what the sidecars name: a sidecar key
``"vehicle"`` or ``"tire"`` (free text; ``"tire"`` may be an object per position, ``{"FL": "380/85 R 28"}``)
keeps runs of differently named vehicles or tires apart, and a run without a name is only pooled with
runs without one.  The cleat and the description are not compared.  A condition of one run keeps that
run's own interval and says "one run: no repeatability measured".

**Rounding** (:func:`supported_step`): the pooled value and interval are shown to the digits the
interval supports: two significant digits of its half-width, the bounds rounded outwards.

Everything is SI inside (N/m, N·s/m, m/s); kN/m only where it is displayed.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["pool_runs", "reml_tau2", "supported_step", "rounded_interval", "condition_names", "group_runs",
           "campaign_conditions", "batch_runs", "result_conditions", "NAME_KEYS", "SPEED_TOLERANCE_KMH", "LOAD_RTOL", "PRESSURE_RTOL",
           "ONE_RUN", "LEVEL"]

#: Sidecar keys that name what was tested: runs naming a different vehicle or tire are never pooled.
NAME_KEYS = ("vehicle", "tire")
#: Runs within this of the group's slowest run are at one speed, km/h.
SPEED_TOLERANCE_KMH = 0.5
#: Runs whose static wheel load is within this fraction of the group's first run's are at one load.
LOAD_RTOL = 0.02
#: Runs whose inflation pressure is within this fraction of the group's first run's are at one pressure (a
#: field gauge reads to a few kPa; a tire at 80 kPa and at 120 kPa is two conditions).
PRESSURE_RTOL = 0.05
#: What a condition of one run says about its interval.
ONE_RUN = "one run: no repeatability measured"
#: Confidence level of every interval.
LEVEL = 0.95
#: Significance of Cochran's Q test below which the runs disagree beyond their intervals.
DISAGREE_P = 0.05


def reml_tau2(y, v, *, tol: float = 1e-12, max_iter: int = 10_000) -> float:
    """The between-run variance τ² by restricted maximum likelihood.

    Parameters
    ----------
    y : array_like, shape (n,)
        The runs' estimates (n >= 2).
    v : array_like, shape (n,)
        Their within-run variances (> 0).
    tol : float
        Relative change of τ² at which the iteration stops.
    max_iter : int
        Iterations at most.

    Returns
    -------
    float
        τ² >= 0, in the square of `y`'s unit.

    Notes
    -----
    Fisher scoring for the restricted likelihood (Viechtbauer 2005), started at the
    DerSimonian-Laird estimate: τ² ← max(0, Σ w²((y - μ)² - v)/Σ w² + 1/Σ w), w = 1/(v + τ²),
    μ = Σ w y/Σ w.  With equal v it is max(0, s² - v), s² the runs' sample variance.
    """
    y, v = np.asarray(y, float), np.asarray(v, float)
    w = 1.0 / v
    mean = np.sum(w * y) / np.sum(w)
    q = np.sum(w * (y - mean) ** 2)
    tau2 = max(0.0, (q - (len(y) - 1)) / (np.sum(w) - np.sum(w ** 2) / np.sum(w)))    # DerSimonian-Laird
    for _ in range(max_iter):
        w = 1.0 / (v + tau2)
        mean = np.sum(w * y) / np.sum(w)
        new = max(0.0, float(np.sum(w ** 2 * ((y - mean) ** 2 - v)) / np.sum(w ** 2) + 1.0 / np.sum(w)))
        if abs(new - tau2) <= tol * (tau2 + float(np.min(v))):
            return new
        tau2 = new
    return tau2


def pool_runs(estimates, std_errors, *, level: float = LEVEL) -> dict:
    """The random-effects mean of repeated runs with its HKSJ interval, the scatter and Cochran's Q.

    Parameters
    ----------
    estimates : array_like, shape (n,)
        One estimate per run (e.g. k, N/m).
    std_errors : array_like, shape (n,)
        Each run's within-run standard error (its 95 % half-width / 1.96), > 0 and finite.
    level : float
        Confidence level.

    Returns
    -------
    dict
        ``n``; ``value`` μ and ``ci`` [low, high] (for n = 1 the run's value ± z·s); ``between_run_sd`` τ
        (None for one run); ``tau2``; ``se`` the HKSJ standard error; ``t_quantile`` and ``df``;
        ``within_only`` the fixed-effect mean of the fit intervals alone, ``{"value", "ci"}`` (normal
        quantile: what the runs' intervals say if there were no test-to-test scatter); ``q``, ``q_p``,
        ``i2`` (None for one run); ``runs_disagree`` (Q's p < 0.05); ``source`` "between-run scatter"
        or "within-run only".

    Raises
    ------
    ValueError
        No estimate, lengths that differ, or a standard error that is not positive and finite.

    Notes
    -----
    The module's docstring gives the method, its references and why it was chosen.
    """
    from scipy import stats

    y = np.asarray(estimates, float).ravel()
    s = np.asarray(std_errors, float).ravel()
    if y.size == 0 or y.shape != s.shape:
        raise ValueError("pool_runs: one standard error per estimate, at least one estimate")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(s)) and np.all(s > 0)):
        raise ValueError("pool_runs: estimates finite and standard errors positive and finite")
    n = y.size
    z = float(stats.norm.ppf(0.5 + level / 2))
    v = s ** 2
    w_fe = 1.0 / v
    fe = float(np.sum(w_fe * y) / np.sum(w_fe))
    fe_half = z / math.sqrt(float(np.sum(w_fe)))
    within = {"value": fe, "ci": [fe - fe_half, fe + fe_half]}
    if n == 1:
        return {"n": 1, "value": fe, "ci": within["ci"], "between_run_sd": None, "tau2": None,
                "se": float(s[0]), "t_quantile": None, "df": 0, "within_only": within, "q": None, "q_p": None,
                "i2": None, "runs_disagree": False, "source": "within-run only"}
    df = n - 1
    q = float(np.sum(w_fe * (y - fe) ** 2))
    tau2 = reml_tau2(y, v)
    w = 1.0 / (v + tau2)
    mean = float(np.sum(w * y) / np.sum(w))
    q_hk = max(1.0, float(np.sum(w * (y - mean) ** 2)) / df)
    se = math.sqrt(q_hk / float(np.sum(w)))
    t = float(stats.t.ppf(0.5 + level / 2, df))
    q_p = float(stats.chi2.sf(q, df))
    return {"n": n, "value": mean, "ci": [mean - t * se, mean + t * se], "between_run_sd": math.sqrt(tau2),
            "tau2": tau2, "se": se, "t_quantile": t, "df": df, "within_only": within, "q": q, "q_p": q_p,
            "i2": max(0.0, (q - df) / q) if q > 0 else 0.0, "runs_disagree": q_p < DISAGREE_P,
            "source": "between-run scatter"}


def supported_step(half_width: float, digits: int = 2) -> float:
    """The rounding step an interval of `half_width` supports: its `digits`-th significant digit."""
    if not (half_width > 0 and math.isfinite(half_width)):
        raise ValueError(f"supported_step: half-width {half_width!r} is not positive and finite")
    return 10.0 ** (math.floor(math.log10(half_width)) - (digits - 1))


def rounded_interval(value: float, low: float, high: float, digits: int = 2) -> dict:
    """`value` rounded to the step its interval supports, the bounds rounded outwards to the same step.

    Returns
    -------
    dict
        ``{"value", "ci": [low, high], "step"}``, rounded (the step a power of ten).
    """
    step = supported_step(max(value - low, high - value), digits)
    exp = round(math.log10(step))
    nd = max(0, -exp)

    def snap(x, how):
        return round(how(round(x / step, 9)) * step, nd)
    return {"value": snap(value, round), "ci": [snap(low, math.floor), snap(high, math.ceil)], "step": step}


def condition_names(extra: dict, tire: str | None = None) -> dict:
    """What a recording's sidecar names (``vehicle``, ``tire``; :data:`NAME_KEYS`), for one position.

    Parameters
    ----------
    extra : dict
        The sidecar's keys beyond the format's (:attr:`~identification.recording.Recording.extra`).
    tire : str, optional
        Position: a ``"tire"`` object per position gives this position's entry.

    Returns
    -------
    dict
        The names present, as text.
    """
    out = {}
    for key in NAME_KEYS:
        value = (extra or {}).get(key)
        if isinstance(value, dict):
            value = value.get(tire) if tire is not None else value
        if value is not None:
            out[key] = str(value)
    return out


def _alike(value, ref, rtol: float) -> bool:
    """Both undeclared, or both declared and within `rtol` of `ref`."""
    if value is None or ref is None:
        return value is None and ref is None
    return abs(value - ref) <= rtol * ref


def group_runs(runs: list) -> list[list]:
    """Runs of one condition together (the rule in the module's docstring).

    Parameters
    ----------
    runs : list of dict
        Each with ``tire``, ``speed_kmh``, ``wheel_load_N`` (or None), ``names`` (dict) and optionally
        ``pressure_Pa`` (the tire's inflation pressure, or None).

    Returns
    -------
    list of list of dict
        The groups, each in increasing speed; groups by names, tire position (FL, FR, RL, RR) and speed.
    """
    order = {t: i for i, t in enumerate(("FL", "FR", "RL", "RR"))}
    groups: list[list] = []
    for run in sorted(runs, key=lambda r: (sorted(r["names"].items()), order.get(r["tire"], 9), r["tire"],
                                           r["speed_kmh"])):
        for g in groups:
            first = g[0]
            if (run["tire"] == first["tire"] and run["names"] == first["names"]
                    and run["speed_kmh"] - first["speed_kmh"] <= SPEED_TOLERANCE_KMH + 1e-9
                    and _alike(run["wheel_load_N"], first["wheel_load_N"], LOAD_RTOL)
                    and _alike(run.get("pressure_Pa"), first.get("pressure_Pa"), PRESSURE_RTOL)):
                g.append(run)
                break
        else:
            groups.append([run])
    return groups


def _pooled(runs: list, key: str) -> dict:
    from scipy import stats

    z = float(stats.norm.ppf(0.5 + LEVEL / 2))
    values = [r[key] for r in runs]
    # each run's standard error from its 95 % interval's width (floored at 1e-9 of the value)
    ses = [max((r[f"{key}_ci"][1] - r[f"{key}_ci"][0]) / (2 * z), 1e-9 * abs(r[key])) for r in runs]
    out = pool_runs(values, ses)
    if len(runs) == 1:          # one run keeps its own interval, as its fit gave it
        out["ci"] = [float(b) for b in runs[0][f"{key}_ci"]]
    out["runs"] = values
    out["rounded"] = rounded_interval(out["value"], *out["ci"])
    return out


def _note(n: int) -> str:
    if n == 1:
        return (f"{ONE_RUN}: the interval is the run's own fit (sensor noise and model error within the run), "
                "without test-to-test scatter")
    return (f"{n} runs: random-effects mean (REML between-run variance, Hartung-Knapp-Sidik-Jonkman "
            f"interval, t on {n - 1} degree(s) of freedom): the interval holds the between-run scatter")


def result_conditions(result) -> list[dict]:
    """A batch's campaign conditions: as the batch wrote their pooled files (``result.campaign``), else
    computed from its runs (``files`` None)."""
    if getattr(result, "campaign", None) is not None:
        return result.campaign
    return [dict(row, files=None) for row in campaign_conditions(batch_runs(result))]


def batch_runs(result) -> list[dict]:
    """The runs of a batch (:class:`~identification.report.batch.BatchResult`): one per recording and tire
    with a recommended k and c, in :func:`campaign_conditions`' form."""
    runs = []
    for r in result.recordings:
        if not r.ok or r.speed_kmh is None:
            continue
        for t in r.tires:
            rec = r.recommended(t.tire)
            if rec is None:
                continue
            load = (r.wheel_load_N or {}).get(t.tire)
            pressure = ((r.conditions or {}).get("inflation_pressure_Pa") or {}).get(t.tire)
            runs.append({"recording": r.stem, "tire": t.tire, "speed_kmh": float(r.speed_kmh),
                         "wheel_load_N": None if load is None else float(load),
                         "pressure_Pa": None if pressure is None else float(pressure),
                         "names": condition_names(r.names, t.tire), "k": rec["k"], "k_ci": list(rec["k_ci"]),
                         "c": rec["c"], "c_ci": list(rec["c_ci"])})
    return runs


def campaign_conditions(runs: list) -> list[dict]:
    """Per condition (tire, speed, load, pressure, names) the pooled k and c: one row per tire and condition.

    Parameters
    ----------
    runs : list of dict
        One per recording and tire with a recommended k and c: ``recording``, ``tire``, ``speed_kmh``,
        ``wheel_load_N`` (N or None), ``pressure_Pa`` (optional, Pa or None), ``names``
        (:func:`condition_names`), ``k``, ``k_ci``, ``c``, ``c_ci``
        (N/m, N·s/m).

    Returns
    -------
    list of dict
        Per condition: ``tire``, ``names``, ``speed_m_s`` (the runs' mean) and ``speed_m_s_range``,
        ``wheel_load_N`` and ``inflation_pressure_Pa`` (means, None where undeclared), ``runs`` (their number), ``recordings``, ``k`` and ``c``
        (:func:`pool_runs`'s document with the runs' ``runs`` values and the ``rounded`` value and
        interval), ``interval_source`` ("between-run scatter" or "within-run only"), ``runs_disagree``
        (k or c) and ``note`` (where the interval comes from, in words).
    """
    out = []
    for group in group_runs(runs):
        speeds = [r["speed_kmh"] / 3.6 for r in group]
        loads = [r["wheel_load_N"] for r in group if r["wheel_load_N"] is not None]
        pressures = [r["pressure_Pa"] for r in group if r.get("pressure_Pa") is not None]
        k, c = _pooled(group, "k"), _pooled(group, "c")
        out.append({"tire": group[0]["tire"], "names": dict(group[0]["names"]),
                    "speed_m_s": float(np.mean(speeds)), "speed_m_s_range": [min(speeds), max(speeds)],
                    "wheel_load_N": float(np.mean(loads)) if loads else None,
                    "inflation_pressure_Pa": float(np.mean(pressures)) if pressures else None, "runs": len(group),
                    "recordings": [r["recording"] for r in group], "k": k, "c": c,
                    "interval_source": k["source"], "runs_disagree": k["runs_disagree"] or c["runs_disagree"],
                    "note": _note(len(group))})
    return out
