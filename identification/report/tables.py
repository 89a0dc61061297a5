"""The report's tables, each built once and rendered twice: as HTML rows and as a CSV file to download.

Every table is a :class:`Table` (plain values per row, SI units named in the
column heads, plus the HTML of each row); :func:`csv_text` writes it.  The
verdict shows, where a recording has a rig truth file beside it
(``STEM.truth.json``, as the virtual rig and the embedded test days have),
the true k and c beside the estimates: the report only displays it, no
estimate depends on it.
"""

from __future__ import annotations

import csv
import html
import io
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Table", "verdict_table", "verdict_heads", "campaign_table", "CAMPAIGN_HEADS", "table4_table",
           "waveform_table", "ride_table", "csv_text",
           "read_truth", "TABLE4_HEADS", "METHODS_HEADS", "unexplained_flag"]


@dataclass
class Table:
    """One table: its CSV name (``tables/<name>.csv``), column heads, rows of values, and rows as HTML."""

    name: str
    columns: list
    rows: list = field(default_factory=list)
    html_rows: list = field(default_factory=list)

    def html(self, *, head: list | None = None, cls: str | None = None) -> str:
        """``<div class="scroll"><table>...</table></div>`` with `head` (HTML column heads, default the CSV's)
        and the table's class `cls`."""
        heads = "".join(f"<th>{h}</th>" for h in (head or [html.escape(c) for c in self.columns]))
        attr = f' class="{cls}"' if cls else ""
        return f'<div class="scroll"><table{attr}><tr>{heads}</tr>{"".join(self.html_rows)}</table></div>'


def csv_text(table: Table) -> str:
    """The table as CSV text (header row, then one row per table row; numbers in SI units as written)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(table.columns)
    writer.writerows(["" if v is None else v for v in row] for row in table.rows)
    return buf.getvalue()


def _e(x) -> str:
    return html.escape(str(x))


def _td(x, fmt: str, scale: float = 1.0, cls: str = "") -> str:
    attr = f' class="{cls}"' if cls else ""
    return f"<td{attr}>–</td>" if x is None else f"<td{attr}>{format(x * scale, fmt)}</td>"


def read_truth(source) -> dict | None:
    """The rig truth beside a recording (``STEM.truth.json``), or None (display only)."""
    path = Path(source).with_suffix(".truth.json")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        return doc if doc.get("format", "").startswith("cleat-rig-truth/") else None
    except (OSError, ValueError, AttributeError):
        return None


def _tires(result):
    for r in result.recordings:
        for t in r.tires:
            yield r, t


def _share(x: float) -> str:
    """A share of the signal as a percentage with two significant digits (never ``0.0%`` for a small one)."""
    return f"{100 * x:.2g} %" if x < 0.1 else f"{100 * x:.0f} %"


def unexplained_flag(left: dict | None, nrmse: float, noise: float) -> str:
    """The verdict cell of a tire: at the noise floor, or what is left above it in the numbers beside it."""
    if left is None:
        return '<span class="ok">at the noise floor</span>'
    from ..diagnose.wording import line_sentence       # the diagnosis' words
    return (f'<span class="warn">above the noise floor: residual {left["residual_to_noise"]:.1f}× the noise '
            f'(NRMSE {nrmse:.1%} against {noise:.1%})'
            + (f', {left["worst_span_to_noise"]:.1f}× over {left["worst_span"][0]:.2f}–{left["worst_span"][1]:.2f} s'
               if "worst_span" in left else "")
            + f'; the excess is {_share(left["share"])} of the signal energy, '
            f'{left["window"][0]:.2f}–{left["window"][1]:.2f} s'
            + (f'; {html.escape(line_sentence(left["steady_line"]))}' if left.get("steady_line") else "")
            + '; intervals conditional on the model</span>')


def _labelled(cells: list, labels: list) -> str:
    """The cells (``<td...>...</td>``) each with its column's name (``data-label``, shown on a narrow screen)."""
    return "".join(c.replace("<td", f'<td data-label="{html.escape(re.sub("<[^>]+>", "", lab))}"', 1)
                   for c, lab in zip(cells, labels))


def verdict_table(result, truths: dict) -> Table:
    """Per tire: the recommended k, c (the final model's, in the recommended FMU) with intervals, the effects
    named, the fit against the noise floor and a plain flag; the rig truth where there is one."""
    with_truth = any(truths.values())
    table = Table("verdict", ["recording", "speed_km_h", "tire", "k_N_m", "k_ci_low", "k_ci_high", "c_Ns_m",
                              "c_ci_low", "c_ci_high", "effects", "nrmse_after", "noise_nrmse", "verdict",
                              "unexplained_share", "fmu", "point_contact_fmu"]
                  + (["k_truth_N_m", "c_truth_Ns_m"] if with_truth else []))
    heads = verdict_heads(table)
    for r, t in _tires(result):
        rec = r.recommended(t.tire)
        if rec is None:
            continue
        d = r.diagnosis.diagnosis
        dt = d["tires"][t.tire]
        left = dt["unexplained"]
        effects = ", ".join(d["effects"]) or "none"
        recommended = [f["file"] for f in r.diagnosis.fmus if f.get("recommended")]
        fmu = next((f for f in recommended if f == f"fmu/{r.stem}_{t.tire}.fmu"), None)
        point = next((f for f in recommended if f.endswith(f"/{r.stem}_{t.tire}.fmu") and f != fmu), None)
        truth = (truths.get(r.source) or {}).get("tires", {}).get(t.tire)
        verdict = "at the noise floor" if left is None else "above the noise floor"
        row = [r.stem, r.speed_kmh, t.tire, rec["k"], *rec["k_ci"], rec["c"], *rec["c_ci"], effects,
               dt["nrmse_after"], dt["noise_nrmse"], verdict, None if left is None else left["share"], fmu, point]
        if with_truth:
            row += [truth["k"] if truth else None, truth["c"] if truth else None]
        table.rows.append(row)
        link = f'<a href="{_e(fmu)}">{_e(fmu.rsplit("/", 1)[-1])}</a>' if fmu else "–"
        cells = [f'<td class="l"><a href="#diagnosis-{_e(r.stem)}">{_e(r.stem)}</a></td>',
                 f'<td>{r.speed_kmh:.3g}</td>', f'<td class="l"><a href="#tire-{_e(r.stem)}-{t.tire}">{t.tire}</a></td>',
                 *_value_interval_cells(rec["k"], rec["k_ci"], ".2f"),
                 *_value_interval_cells(rec["c"], rec["c_ci"], ".3f")]
        if with_truth:
            cells += [_td(truth["k"] if truth else None, ".2f", 1e-3, "truth"),
                      _td(truth["c"] if truth else None, ".3f", 1e-3, "truth")]
        cells += [f'<td>{dt["nrmse_after"]:.1%}</td>', f'<td>{dt["noise_nrmse"]:.1%}</td>',
                  f'<td class="l">{unexplained_flag(left, dt["nrmse_after"], dt["noise_nrmse"])}</td>',
                  f'<td class="l">{link}</td>']
        table.html_rows.append(f"<tr>{_labelled(cells, heads)}</tr>")
    return table


def verdict_heads(table: Table) -> list:
    heads = ['recording', 'km/h', 'tire', 'K / kN·m⁻¹', 'K 95 %', 'C / kN·s·m⁻¹', 'C 95 %']
    if "k_truth_N_m" in table.columns:
        heads += ['K rig truth', 'C rig truth']
    return heads + ['NRMSE', 'noise NRMSE', 'verdict', 'recommended FMU']


def _value_interval_cells(value: float, ci, fallback: str) -> list:
    """A value (N/m or N s/m) and its interval as two cells in k-units: rounded as the campaign rows round
    (:func:`~identification.report.campaign.rounded_interval`: the digits the interval supports, the bounds
    outwards), so one interval reads the same wherever it is shown; `fallback` format where it is unbounded."""
    from .campaign import rounded_interval

    lo, hi = ci
    if all(math.isfinite(v) for v in (value, lo, hi)) and lo <= value <= hi and hi > lo:
        r = rounded_interval(value, lo, hi)
        return [f'<td><b>{_shown(r["value"], r["step"], 1e-3)}</b></td>',
                f'<td>{_shown(r["ci"][0], r["step"], 1e-3)}–{_shown(r["ci"][1], r["step"], 1e-3)}</td>']
    return [f'<td><b>{value / 1e3:{fallback}}</b></td>', f'<td>{lo / 1e3:{fallback}}–{hi / 1e3:{fallback}}</td>']


def _shown(x: float, step: float, scale: float) -> str:
    """`x` (already rounded to `step`) times `scale`, with the decimals of `step`."""
    return f"{x * scale:.{max(0, -round(math.log10(step * scale)))}f}"


def _scatter(p: dict, scale: float) -> str:
    """The between-run SD with two significant digits and as a share of the value ('–' for one run)."""
    sd = p["between_run_sd"]
    return "–" if sd is None else f"{sd * scale:.2g} ({100 * sd / abs(p['value']):.2g} %)"


def campaign_table(result) -> Table:
    """One row per tire and condition (:mod:`~identification.report.campaign`): the pooled k and c of its
    runs rounded to what their interval supports, the between-run scatter, where the interval comes from
    and whether the runs disagree beyond their fit intervals (Cochran's Q)."""
    from .campaign import result_conditions

    table = Table("campaign", ["tire", "vehicle", "tire_name", "speed_km_h", "speed_km_h_min", "speed_km_h_max",
                               "wheel_load_N", "inflation_pressure_kPa", "runs", "recordings", "k_N_m", "k_ci_low", "k_ci_high",
                               "k_between_run_sd_N_m", "k_q_p", "k_i2", "c_Ns_m", "c_ci_low", "c_ci_high",
                               "c_between_run_sd_Ns_m", "c_q_p", "c_i2", "runs_disagree", "interval_source",
                               "note", "fmu", "params"])
    for row in result_conditions(result):
        k, c = row["k"], row["c"]
        kr, cr = k["rounded"], c["rounded"]
        table.rows.append([row["tire"], row["names"].get("vehicle"), row["names"].get("tire"),
                           *(round(v * 3.6, 9) for v in (row["speed_m_s"], *row["speed_m_s_range"])),
                           row["wheel_load_N"],
                           None if row["inflation_pressure_Pa"] is None else row["inflation_pressure_Pa"] / 1e3,
                           row["runs"], " ".join(row["recordings"]), kr["value"], *kr["ci"], k["between_run_sd"],
                           k["q_p"], k["i2"], cr["value"], *cr["ci"], c["between_run_sd"], c["q_p"], c["i2"],
                           row["runs_disagree"], row["interval_source"], row["note"],
                           *((row["files"] or {}).get(key) for key in ("fmu", "params"))])
        if row["runs"] == 1:
            source = '<span class="warn">one run: no repeatability measured</span> (its fit interval only)'
        else:
            agree = [(f'<span class="warn">{n}: runs disagree beyond their fit intervals' if p["runs_disagree"]
                      else f'<span class="ok">{n}: runs agree within their fit intervals')
                     + f' (Q p {"< 0.0001" if p["q_p"] < 1e-4 else "= " + format(p["q_p"], ".2g")}, '
                     f'I² {100 * p["i2"]:.0f} %)</span>' for n, p in (("K", k), ("C", c))]
            source = (f'between-run scatter of {row["runs"]} runs (random-effects mean, HKSJ)<br>'
                      + "<br>".join(agree))
        names = " ".join(_e(v) for v in row["names"].values())
        speeds = row["speed_m_s_range"]
        kpa = "" if row["inflation_pressure_Pa"] is None else f' · {row["inflation_pressure_Pa"] / 1e3:.3g} kPa'
        cells = [f'<td class="l">{row["tire"]}{" " + names if names else ""}{kpa}</td>',
                 f'<td>{row["speed_m_s"] * 3.6:.3g}' + (f' ({speeds[0] * 3.6:.3g}–{speeds[1] * 3.6:.3g})'
                                                         if speeds[1] > speeds[0] else "") + "</td>",
                 f'<td class="l" title="{_e(" ".join(row["recordings"]))}">{row["runs"]}</td>',
                 f'<td><b>{_shown(kr["value"], kr["step"], 1e-3)}</b></td>',
                 f'<td>{_shown(kr["ci"][0], kr["step"], 1e-3)}–{_shown(kr["ci"][1], kr["step"], 1e-3)}</td>',
                 f'<td>{_scatter(k, 1e-3)}</td>', f'<td><b>{_shown(cr["value"], cr["step"], 1e-3)}</b></td>',
                 f'<td>{_shown(cr["ci"][0], cr["step"], 1e-3)}–{_shown(cr["ci"][1], cr["step"], 1e-3)}</td>',
                 f'<td>{_scatter(c, 1e-3)}</td>', f'<td class="l">{source}</td>',
                 '<td class="l">' + (f'<a href="{_e(row["files"]["fmu"])}">FMU</a>, <a href="{_e(row["files"]["params"])}">'
                                     'params</a>' if row["files"] else "") + '</td>']
        table.html_rows.append(f"<tr>{_labelled(cells, CAMPAIGN_HEADS)}</tr>")
    return table


CAMPAIGN_HEADS = ['tire', 'km/h', 'runs', 'K / kN·m⁻¹', 'K 95 %', 'K between-run SD', 'C / kN·s·m⁻¹', 'C 95 %',
                  'C between-run SD', 'interval from', 'pooled files']


def _flipped(r) -> list:
    """The channels the joint fit found upside down after the conditioning (the per-tire methods used them
    as recorded)."""
    d = r.diagnosis.diagnosis if r.diagnosis is not None else None
    chosen = ((d or {}).get("sign_test") or {}).get("chosen")
    return [c for c in str(chosen).split("+") if c in ("FL", "FR", "RL", "RR")] if chosen else []


def table4_table(result) -> Table:
    """The paper's Table 4 for every speed and tire."""
    table = Table("table4", ["speed_km_h", "recording", "tire", "T_s", "zeta", "delta", "omega_n_rad_s", "k_N_m",
                             "c_Ns_m", "r2", "peaks", "channel_sign"])
    for r, t in sorted(_tires(result), key=lambda rt: (rt[0].speed_kmh or 0, rt[1].tire)):
        p = t.paper
        flipped = t.tire in _flipped(r)
        sign = "upside down (found by the joint fit; used as recorded here)" if flipped else "as recorded"
        if p is None:
            table.rows.append([r.speed_kmh, r.stem, t.tire] + [None] * 8 + [sign])
            table.html_rows.append(f'<tr><td>{r.speed_kmh:.4g}</td><td class="l">{_e(r.stem)}</td>'
                                   f'<td class="l">{t.tire}</td><td class="l bad" colspan="8">not identified</td></tr>')
            continue
        table.rows.append([r.speed_kmh, r.stem, t.tire, p["T"], p["zeta"], p["delta"], p["omega_n"], p["k"], p["c"],
                           p["r2"], p["n_peaks"], sign])
        mark = (' <span class="bad" title="the joint fit found this channel upside down">⚠ channel upside down: '
                'computed from it as recorded</span>') if flipped else ""
        table.html_rows.append(
            f'<tr><td>{r.speed_kmh:.4g}</td><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}{mark}</td>'
            f'<td>{p["T"]:.3f}</td><td>{p["zeta"]:.3f}</td><td>{p["delta"]:.3f}</td>'
            f'<td>{p["omega_n"]:.2f}</td><td>{p["k"] / 1e3:.2f}</td><td>{p["c"] / 1e3:.2f}</td>'
            f'<td>{p["r2"]:.2f}</td><td>{p["n_peaks"]}</td></tr>')
    return table


TABLE4_HEADS = ['speed / km·h⁻¹', 'recording', 'tire', 'T / s', 'ζ', 'δ', 'ω<sub>n</sub> / rad·s⁻¹', 'K / kN·m⁻¹',
                'C / kN·s·m⁻¹', 'R²', 'peaks']


def waveform_table(result) -> Table:
    """The methods side by side per tire: the paper's, the waveform fit (with its intervals) and the final."""
    table = Table("methods", ["recording", "tire", "k_paper_N_m", "k_waveform_N_m", "k_waveform_ci_low",
                              "k_waveform_ci_high", "k_final_N_m", "c_paper_Ns_m", "c_waveform_Ns_m",
                              "c_final_Ns_m", "waveform_r2"])
    for r, t in _tires(result):
        p, w, f = t.paper, t.waveform, r.recommended(t.tire)
        table.rows.append([r.stem, t.tire, p and p["k"], w and w["k"], w and w["k_ci"][0], w and w["k_ci"][1],
                           f and f["k"], p and p["c"], w and w["c"], f and f["c"], w and w["r2"]])
        ci = "–" if w is None else f'{w["k_ci"][0] / 1e3:.2f} – {w["k_ci"][1] / 1e3:.2f}'
        table.html_rows.append(
            f'<tr><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}</td>'
            + _td(p and p["k"], ".2f", 1e-3) + _td(w and w["k"], ".2f", 1e-3) + f"<td>{ci}</td>"
            + _td(f and f["k"], ".2f", 1e-3, "final") + _td(p and p["c"], ".3f", 1e-3) + _td(w and w["c"], ".3f", 1e-3)
            + _td(f and f["c"], ".3f", 1e-3, "final") + _td(w and w["r2"], ".4f") + "</tr>")
    return table


METHODS_HEADS = ['recording', 'tire', 'K paper', 'K waveform', 'K waveform 95 %', 'K final', 'C paper',
                 'C waveform', 'C final', 'waveform R²']


def ride_table(result) -> Table:
    """Every recording's ride per parameter set: expected a_w, VDV, MTVV over the road realisations with
    the 95 % interval of the mean and of one ride, the PSD's a_w, and the first road's a_w."""
    table = Table("ride", ["recording", "road_class", "realisations", "speed_m_s", "set", "k_FL_N_m", "k_FR_N_m",
                           "k_RL_N_m", "k_RR_N_m", "a_w_mean_m_s2", "a_w_mean_lo", "a_w_mean_hi", "a_w_one_ride_lo",
                           "a_w_one_ride_hi", "a_w_psd_m_s2", "vdv_mean_m_s175", "mtvv_mean_m_s2",
                           "vector_sum_health_mean_m_s2", "a_w_first_road_m_s2", "tire_law", "static_source"])
    for r in result.recordings:
        d = r.diagnosis.ride if r.diagnosis is not None else None
        if d is None:
            continue
        for name, s in d["sets"].items():
            e = s["expected"]
            table.rows.append([r.stem, d["road"]["class"], d["road"]["realisations"], d["speed_m_s"], name,
                               *s["k"].values(), e["a_w"]["mean"], *e["a_w"]["mean_interval"],
                               *e["a_w"]["single_ride_interval"], e["psd"]["a_w"], e["vdv"]["mean"],
                               e["mtvv"]["mean"], e["vector_sum_health"]["mean"], s["a_w"], d["tires"],
                               d["static"]["file"] if name == "static" and d.get("static") else ""])
    return table
