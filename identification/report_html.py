"""The batch report: one self-contained HTML file (figures embedded as PNG data URIs).

Sections (each an ``<section id=...>``): ``summary``, ``table4`` (the paper's
Table 4 for every speed and tire), ``waveform`` (waveform fits with 95 %
intervals), ``tire-<recording>-<tire>`` (Figure 9a/9b, the co-simulated FMU
against the measurement, the diagnosis with evidence and gains, before/after
overlays), ``fmus`` (every FMU written, with its validation) and ``timings``.
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
        errors = [f"{t.tire}: {e}" for t in r.tires for e in t.errors]
        status = '<span class="ok">processed</span>' if not errors else '<span class="bad">partly failed</span>'
        effects = "; ".join(f"{t.tire}: " + (", ".join(t.diagnosis["effects"]) or "none")
                            for t in r.tires if t.diagnosis)
        detail = _e("; ".join(errors)) if errors else f"{r.speed_kmh:.4g} km/h, {r.sample_rate_hz:.6g} Hz, " \
                                                       f"effects found — {_e(effects)}"
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
    d = t.diagnosis
    if d is not None:
        effects = ", ".join(d["effects"]) or "none — the point-contact model explains the data to within noise"
        out.append(f'<p>Diagnosis: <b>{_e(effects)}</b>. NRMSE with FMUs co-simulated in fmpy: point contact '
                   f'<b>{d["nrmse_before"]:.1%}</b> → extended <b>{d["nrmse_after"]:.1%}</b> '
                   f'(fitting model and FMU agree to {d["agreement"]:.1e}). '
                   f'k {d["k"] / 1e3:.1f} kN/m ({d["k_ci"][0] / 1e3:.1f}–{d["k_ci"][1] / 1e3:.1f}), '
                   f'c {d["c"] / 1e3:.2f} kN·s/m ({d["c_ci"][0] / 1e3:.2f}–{d["c_ci"][1] / 1e3:.2f}).</p>')
        for name in d["effects"]:
            out.append(f'<div class="effect"><b>{_e(name)}</b>: {_e(d["evidence"].get(name, ""))}</div>')
        rows = "".join(f'<tr><td class="l">{_e(n)}</td><td>{v["value"]:.5g}</td><td class="l">{_e(v["unit"])}</td>'
                       f'<td>{v["ci"][0]:.5g} – {v["ci"][1]:.5g}</td></tr>' for n, v in d["parameters"].items())
        out.append('<table><tr><th class="l">parameter</th><th>value</th><th class="l">unit</th><th>95 % interval</th>'
                   f'</tr>{rows}</table>')
        if "diagnosis" in t.figures:
            out.append(_img(t.figures["diagnosis"], f"{r.stem} {t.tire} diagnosis"))
    out.append("</section>")
    return "".join(out)


def _fmus(result: BatchResult) -> str:
    rows = []
    for r, t in _tires(result):
        for f in t.fmus:
            ok = not f.get("problems")
            verdict = '<span class="ok">validate_fmu: no problem</span>' if ok else \
                '<span class="bad">' + _e("; ".join(f["problems"])) + "</span>"
            rows.append(f'<tr><td class="l"><code>{_e(f["file"])}</code></td><td class="l">{_e(f["kind"])}</td>'
                        f'<td class="l">{_e(f["role"])}</td><td class="l">{verdict}</td></tr>')
    return ('<section id="fmus"><h2>Exported FMUs</h2><p class="note">FMI 2.0 co-simulation, built with pythonfmu: '
            'the importing machine needs Python 3.</p><table><tr><th class="l">file</th><th class="l">kind</th>'
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
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
            f'<style>{_CSS}</style></head><body><h1>{_e(title)}</h1><p class="note">cleatfmu {__version__}, {stamp}. '
            'Hub accelerations in m/s², gravity excluded; all comparisons after the zero-phase 100 Hz low-pass.</p>'
            f'{_summary(result)}{_table4(result)}{_waveform(result)}'
            f'<section id="tires"><h2>Tires: decay, co-simulation, diagnosis</h2>{tires}</section>'
            f'{_fmus(result)}{_timings(result, extra)}</body></html>\n')


def write_report(result: BatchResult, *, title: str = "cleatfmu report", extra: dict | None = None) -> Path:
    """Write ``report.html`` and ``summary.json`` into the batch's output folder; return the report's path."""
    out = Path(result.out_dir)
    summary = {"recordings": [{"source": r.source, "ok": r.ok, "error": r.error,
                               "tires": {t.tire: {"paper": t.paper, "waveform": t.waveform, "simulate": t.simulate,
                                                  "diagnosis": t.diagnosis, "fmus": t.fmus, "errors": t.errors}
                                         for t in r.tires}} for r in result.recordings],
               "failures": result.failures, "seconds": result.seconds, "stage_seconds": result.timings}
    atomic_write_texts({out / "report.html": render_report(result, title=title, extra=extra),
                        out / "summary.json": json.dumps(summary, indent=1, default=float) + "\n"})
    return out / "report.html"
