"""The batch report: one self-contained HTML file (figures embedded as PNG data URIs).

Sections (each an ``<section id=...>``): ``summary``, ``table4`` (the paper's
Table 4 for every speed and tire), ``waveform`` (waveform fits with 95 %
intervals), ``recommended`` (one k, c per tire from the joint whole-tractor
diagnosis, beside the paper's and the waveform values, with what is left
unexplained), ``diagnosis-<recording>`` (effects with evidence, body, gains,
overlays per channel), ``tire-<recording>-<tire>`` (Figure 9a/9b, the
co-simulated point-contact FMU against the measurement), ``fmus`` (every FMU
written, with its validation) and ``timings``.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
from pathlib import Path

from . import __version__
from ._files import atomic_write_texts
from .batch import BatchResult

__all__ = ["render_report", "write_report"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:2em auto;max-width:1150px;
color:#1d2733;line-height:1.45;padding:0 1em}
h1{font-size:1.7em;margin-bottom:.2em}h2{border-bottom:2px solid #3a6ea5;padding-bottom:.2em;margin-top:2em}
h3{margin-top:1.6em;color:#3a6ea5}table{border-collapse:collapse;margin:.6em 0 1.2em;font-size:.92em}
th,td{border:1px solid #c9d3de;padding:.3em .6em;text-align:right}th{background:#e8eff7}
td.l,th.l{text-align:left}.ok{color:#1c7c3a;font-weight:600}.bad{color:#b3261e;font-weight:600}
.note{color:#556;font-size:.9em}img{max-width:100%;border:1px solid #dde3ea;margin:.4em 0}
.effect{background:#fff6e0;border-left:4px solid #e0a800;padding:.4em .8em;margin:.4em 0}
code{background:#eef2f6;padding:0 .25em;border-radius:3px}
"""


def _e(x) -> str:
    return html.escape(str(x))


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def _f(x, fmt=".3g", scale=1.0) -> str:
    return "–" if x is None else format(x * scale, fmt)


def _summary(result: BatchResult) -> str:
    rows = []
    for r in result.recordings:
        if not r.ok:
            rows.append(f'<tr><td class="l">{_e(r.source)}</td><td class="l bad">failed</td>'
                        f'<td class="l">{_e(r.error)}</td></tr>')
            continue
        errors = [f"{t.tire}: {e}" for t in r.tires for e in t.errors] + \
            (r.diagnosis.errors if r.diagnosis is not None else [])
        status = '<span class="ok">processed</span>' if not errors else '<span class="bad">partly failed</span>'
        d = r.diagnosis.diagnosis if r.diagnosis is not None else None
        found = "not diagnosed" if d is None else (
            "effects found — " + (", ".join(d["effects"]) or "none") + "; " +
            ("residual above noise on " + ", ".join(t for t, v in d["tires"].items() if v["unexplained"])
             if any(v["unexplained"] for v in d["tires"].values()) else "residual at the noise floor"))
        detail = _e("; ".join(errors)) if errors else \
            f"{r.speed_kmh:.4g} km/h, {r.sample_rate_hz:.6g} Hz, {_e(found)}"
        rows.append(f'<tr><td class="l">{_e(r.source)}</td><td class="l">{status}</td>'
                    f'<td class="l">{detail}</td></tr>')
    n_bad = len(result.failures)
    verdict = ('<p class="ok">All recordings processed.</p>' if not n_bad else
               f'<p class="bad">{n_bad} failure(s): see the rows marked failed.</p>')
    return (f'<section id="summary"><h2>Summary</h2>{verdict}<table><tr><th class="l">recording</th>'
            f'<th class="l">status</th><th class="l">details</th></tr>{"".join(rows)}</table></section>')


def _tires(result: BatchResult):
    for r in result.recordings:
        for t in r.tires:
            yield r, t


def _table4(result: BatchResult) -> str:
    rows = []
    for r, t in sorted(_tires(result), key=lambda rt: (rt[0].speed_kmh or 0, rt[1].tire)):
        p = t.paper
        if p is None:
            rows.append(f'<tr><td>{r.speed_kmh:.4g}</td><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}</td>'
                        f'<td class="l bad" colspan="8">not identified</td></tr>')
            continue
        rows.append(f'<tr><td>{r.speed_kmh:.4g}</td><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}</td>'
                    f'<td>{p["T"]:.3f}</td><td>{p["zeta"]:.3f}</td><td>{p["delta"]:.3f}</td>'
                    f'<td>{p["omega_n"]:.2f}</td><td>{p["k"] / 1e3:.2f}</td><td>{p["c"] / 1e3:.2f}</td>'
                    f'<td>{p["r2"]:.2f}</td><td>{p["n_peaks"]}</td></tr>')
    return ('<section id="table4"><h2>Stiffness and damping by the paper\'s method (Table 4)</h2>'
            '<p class="note">T and δ from the first two peaks, ζ and ω<sub>n</sub> by eqs. 7-8, K = m ω<sub>n</sub>²,'
            ' C by the exponential fit through the first peak (eqs. 16-17), R² of the semi-log regression.</p>'
            '<table><tr><th>speed / km·h⁻¹</th><th class="l">recording</th><th class="l">tire</th><th>T / s</th>'
            '<th>ζ</th><th>δ</th><th>ω<sub>n</sub> / rad·s⁻¹</th><th>K / kN·m⁻¹</th><th>C / kN·s·m⁻¹</th>'
            f'<th>R²</th><th>peaks</th></tr>{"".join(rows)}</table></section>')


def _waveform(result: BatchResult) -> str:
    rows = []
    for r, t in _tires(result):
        w = t.waveform
        if w is None:
            continue
        rows.append(f'<tr><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}</td>'
                    f'<td>{w["k"] / 1e3:.2f}</td><td>{w["k_ci"][0] / 1e3:.2f} – {w["k_ci"][1] / 1e3:.2f}</td>'
                    f'<td>{w["c"] / 1e3:.3f}</td><td>{w["c_ci"][0] / 1e3:.3f} – {w["c_ci"][1] / 1e3:.3f}</td>'
                    f'<td>{w["zeta"]:.3f}</td><td>{w["r2"]:.4f}</td></tr>')
    return ('<section id="waveform"><h2>Waveform fits of the free decay (95 % confidence intervals)</h2>'
            '<table><tr><th class="l">recording</th><th class="l">tire</th><th>K / kN·m⁻¹</th><th>K interval</th>'
            '<th>C / kN·s·m⁻¹</th><th>C interval</th><th>ζ</th><th>R²</th></tr>'
            f'{"".join(rows)}</table></section>')


def _recommended(result: BatchResult) -> str:
    rows = []
    for r, t in _tires(result):
        rec = r.recommended(t.tire)
        if rec is None:
            continue
        d = r.diagnosis.diagnosis["tires"][t.tire]
        left = d["unexplained"]
        status = '<span class="ok">at the noise floor</span>' if left is None else \
            (f'<span class="bad">unexplained {left["share"]:.1%} of the signal, '
             f'{left["window"][0]:.2f}–{left["window"][1]:.2f} s</span>')
        paper = t.paper["k"] / 1e3 if t.paper else None
        wave = t.waveform["k"] / 1e3 if t.waveform else None
        rows.append(f'<tr><td class="l">{_e(r.stem)}</td><td class="l">{t.tire}</td>'
                    f'<td><b>{rec["k"] / 1e3:.2f}</b></td><td>{rec["k_ci"][0] / 1e3:.2f} – {rec["k_ci"][1] / 1e3:.2f}</td>'
                    f'<td><b>{rec["c"] / 1e3:.3f}</b></td><td>{rec["c_ci"][0] / 1e3:.3f} – {rec["c_ci"][1] / 1e3:.3f}</td>'
                    f'<td>{_f(paper, ".2f")}</td><td>{_f(wave, ".2f")}</td>'
                    f'<td>{d["nrmse_before"]:.1%} → {d["nrmse_after"]:.1%}</td><td>{d["noise_nrmse"]:.1%}</td>'
                    f'<td class="l">{status}</td></tr>')
    return ('<section id="recommended"><h2>Recommended stiffness and damping (joint whole-tractor diagnosis)</h2>'
            '<p class="note">One fit per recording: every channel at once under one body (heave, pitch, roll), with '
            'the effects the diagnosis named; 95 % intervals from the joint fit. They hold if the model is right: '
            'a tire whose residual stays above its noise floor is marked, and its intervals are conditional on the '
            'model. NRMSE of the point-contact tires and of the extended tires, both as FMUs co-simulated under the '
            'body with fmpy; "noise" is the NRMSE the measurement noise alone would give.</p>'
            '<table><tr><th class="l">recording</th><th class="l">tire</th><th>K / kN·m⁻¹</th><th>K interval</th>'
            '<th>C / kN·s·m⁻¹</th><th>C interval</th><th>K paper</th><th>K waveform</th><th>NRMSE</th>'
            f'<th>noise</th><th class="l">residual</th></tr>{"".join(rows)}</table></section>')


def _diagnosis_section(r) -> str:
    rep = r.diagnosis
    out = [f'<section id="diagnosis-{_e(r.stem)}"><h3>{_e(r.stem)}: whole-tractor diagnosis</h3>']
    for err in rep.errors:
        out.append(f'<p class="bad">{_e(err)}</p>')
    d = rep.diagnosis
    if d is not None:
        body = d["body"]
        effects = ", ".join(d["effects"]) or "none — the four-corner model explains the data to within noise"
        speed = body["speed_m_s"]
        delay = "" if speed["from_delay"] is None else \
            f', {speed["from_delay"] * 3.6:.2f} km/h from the front/rear delay'
        indices = "; ".join(f'{name.replace("_", " ")} {body[name]["value"]:.3f} '
                            f'({body[name]["ci"][0]:.3f}–{body[name]["ci"][1]:.3f})'
                            for name in ("pitch_index", "roll_index", "pivot_index") if body.get(name))
        out.append(f'<p>Effects the four-corner model misses: <b>{_e(effects)}</b>. Front axle {body["front_axle"]}'
                   f'{"; " + indices if indices else ""}. Speed {speed["sidecar"] * 3.6:.2f} km/h (sidecar){delay}. '
                   f'Extended FMUs co-simulated under the body agree with the fitting model to '
                   f'{d["agreement"]:.1e}; diagnosis {d["seconds"]:.1f} s. Intervals: {_e(d["intervals"])}.</p>')
        for name in d["effects"]:
            out.append(f'<div class="effect"><b>{_e(name)}</b>: {_e(d["evidence"].get(name, ""))}</div>')
        if "diagnosis" in rep.figures:
            out.append(_img(rep.figures["diagnosis"], f"{r.stem} whole-tractor diagnosis"))
    if rep.ride is not None:
        out.append(_ride(r.stem, rep))
    out.append("</section>")
    return "".join(out)


def _versus_final(d: dict) -> str:
    """' a_w against the final set's: paper +11 %, ...' (empty without a final set)."""
    sets = d["sets"]
    if "final" not in sets or len(sets) < 2:
        return ""
    ref = sets["final"]["a_w"]
    parts = [f'{_e(name)} {100 * (r["a_w"] / ref - 1):+.0f} %' for name, r in sets.items() if name != "final"]
    return " a_w against the final set's: " + ", ".join(parts) + "."


def _ride(stem: str, rep) -> str:
    """The diagnosed tractor on an ISO 8608 road with each parameter set: ISO 2631-1 at the seat."""
    d = rep.ride
    rows = "".join(f'<tr><td class="l">{_e(name)}</td><td>{"/".join(f"{v / 1e3:.0f}" for v in r["k"].values())}'
                   f'</td><td>{r["a_w"]:.3f}</td><td>{r["vdv"]:.3f}</td><td>{r["mtvv"]:.3f}</td>'
                   f'<td>{r["crest_factor"]:.2f}</td></tr>' for name, r in d["sets"].items())
    road = d["road"]
    return (f'<h4>Ride comfort: the tractor on an ISO 8608 class {_e(road["class"])} road</h4>'
            f'<p>The {_e(d["body"]["source"])} at {d["speed_m_s"] * 3.6:.3g} km/h for '
            f'{d["duration_s"]:g} s (road seed {road["seed"]}), once per tire parameter set; the seat '
            f'{d["seat"]["x_m"]:.2f} m behind the front axle, rated by ISO 2631-1 (Wk).{_versus_final(d)}</p>'
            '<table><tr><th class="l">set</th><th>k FL/FR/RL/RR, kN/m</th><th>a_w, m/s²</th>'
            f'<th>VDV, m/s^1.75</th><th>MTVV, m/s²</th><th>crest factor</th></tr>{rows}</table>'
            + (_img(rep.figures["ride"], f"{stem} ride comfort") if "ride" in rep.figures else ""))


def _tire_section(r, t) -> str:
    out = [f'<section id="tire-{_e(r.stem)}-{t.tire}"><h3>{_e(r.stem)} · {t.tire}</h3>']
    for err in t.errors:
        out.append(f'<p class="bad">{_e(err)}</p>')
    if "decay" in t.figures:
        out.append(_img(t.figures["decay"], f"{r.stem} {t.tire} decay"))
    s = t.simulate
    if s is not None:
        out.append(f'<p>Point-contact FMU co-simulated with fmpy: NRMSE <b>{s["nrmse"]:.1%}</b>, R² {s["r2"]:.3f}; '
                   f'k<sub>FMU</sub> {s["k_fmu"] / 1e3:.1f} kN/m, re-identified {s["k_reidentified"] / 1e3:.1f} kN/m; '
                   f'the misfit sits mostly in the <b>{_e(s["worst_window"].replace("_", " "))}</b> window.</p>')
        out.append(_img(t.figures.get("comparison", b""), f"{r.stem} {t.tire} co-simulation")
                   if "comparison" in t.figures else "")
    out.append("</section>")
    return "".join(out)


def _all_fmus(result: BatchResult):
    for r in result.recordings:
        yield from (r.diagnosis.fmus if r.diagnosis is not None else [])
        for t in r.tires:
            yield from t.fmus


def _fmus(result: BatchResult) -> str:
    rows = []
    for f in _all_fmus(result):
        ok = not f.get("problems")
        verdict = '<span class="ok">validate_fmu: no problem</span>' if ok else \
            '<span class="bad">' + _e("; ".join(f["problems"])) + "</span>"
        rows.append(f'<tr><td class="l"><code>{_e(f["file"])}</code></td><td class="l">{_e(f["kind"])}</td>'
                    f'<td class="l">{_e(f["role"])}</td><td class="l">{verdict}</td></tr>')
    return ('<section id="fmus"><h2>Exported FMUs</h2><p class="note">FMI 2.0 co-simulation, native C: binaries '
            'for linux64, win64 and darwin64 and the C sources inside; the importing machine needs no Python.</p>'
            '<table><tr><th class="l">file</th><th class="l">kind</th>'
            f'<th class="l">content</th><th class="l">validation</th></tr>{"".join(rows)}</table></section>')


def _timings(result: BatchResult, extra: dict | None) -> str:
    total = sum(result.timings.values()) or 1.0
    rows = "".join(f'<tr><td class="l">{_e(k)}</td><td>{v:.1f}</td><td>{v / total:.0%}</td></tr>'
                   for k, v in sorted(result.timings.items(), key=lambda kv: -kv[1]))
    more = "".join(f"<li>{_e(k)}: {_e(v)}</li>" for k, v in (extra or {}).items())
    return (f'<section id="timings"><h2>Run</h2><p>Wall time {result.seconds:.1f} s. CPU time per stage, summed over '
            f'the parallel jobs:</p><table><tr><th class="l">stage</th><th>s</th><th>share</th></tr>{rows}</table>'
            f'<ul class="note">{more}</ul></section>')


def render_report(result: BatchResult, *, title: str = "cleatfmu report", extra: dict | None = None) -> str:
    """The report as an HTML string."""
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    tires = "".join(_tire_section(r, t) for r, t in _tires(result))
    diagnoses = "".join(_diagnosis_section(r) for r in result.recordings if r.diagnosis is not None)
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
            f'<style>{_CSS}</style></head><body><h1>{_e(title)}</h1><p class="note">cleatfmu {__version__}, {stamp}. '
            'Hub accelerations in m/s², gravity excluded; all comparisons after the zero-phase 100 Hz low-pass.</p>'
            f'{_summary(result)}{_table4(result)}{_waveform(result)}{_recommended(result)}'
            f'<section id="diagnoses"><h2>Whole-tractor diagnoses</h2>{diagnoses}</section>'
            f'<section id="tires"><h2>Tires: decay, point-contact co-simulation</h2>{tires}</section>'
            f'{_fmus(result)}{_timings(result, extra)}</body></html>\n')


def write_report(result: BatchResult, *, title: str = "cleatfmu report", extra: dict | None = None) -> Path:
    """Write ``report.html`` and ``summary.json`` into the batch's output folder; return the report's path."""
    out = Path(result.out_dir)
    summary = {"recordings": [{"source": r.source, "ok": r.ok, "error": r.error,
                               "diagnosis": r.diagnosis.diagnosis if r.diagnosis is not None else None,
                               "diagnosis_fmus": r.diagnosis.fmus if r.diagnosis is not None else [],
                               "diagnosis_errors": r.diagnosis.errors if r.diagnosis is not None else [],
                               "ride": r.diagnosis.ride if r.diagnosis is not None else None,
                               "tires": {t.tire: {"recommended": r.recommended(t.tire), "paper": t.paper,
                                                  "waveform": t.waveform, "simulate": t.simulate, "fmus": t.fmus,
                                                  "errors": t.errors}
                                         for t in r.tires}} for r in result.recordings],
               "failures": result.failures, "seconds": result.seconds, "stage_seconds": result.timings}
    atomic_write_texts({out / "report.html": render_report(result, title=title, extra=extra),
                        out / "summary.json": json.dumps(summary, indent=1, default=float) + "\n"})
    return out / "report.html"
