"""The batch report: one self-contained HTML file (figures embedded as PNG data URIs) and its tables as CSV.

The first screen is the verdict (``recommended``, :mod:`~identification.report.verdict`): per tire the
recommended k and c (the final model's, those in the recommended FMU) with intervals, the effects named
with every warning of the run beside them, the fit against the noise floor and a plain flag when something
is left above it, and which file to take (:mod:`~identification.report.files`); then a table of contents, a "how to read this" box,
k and c against speed, and the sections ``summary``, ``table4`` (the paper's
Table 4), ``waveform`` (the methods side by side), ``diagnoses`` (per
recording ``diagnosis-<recording>``: effects with evidence, body, overlays,
the ride comfort), ``tires`` (``tire-<recording>-<tire>``: Figure 9a/9b, the
co-simulated one-corner FMU and why it is not recommended), ``fmus`` and ``timings``.  Every table is
also written as ``tables/<name>.csv`` beside ``summary.json`` (:func:`summary_document`).
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import os
import shutil
from pathlib import Path

from .. import __version__
from .._files import atomic_write_texts, json_text
from .batch import FIGURES_STAGING, BatchResult
from .campaign import result_conditions
from ..diagnose.joint_evidence import interval_text
from ..diagnose.wording import effects_sentence
from .files import not_recommended_params, point_contact_fmu, recommended_fmu, recommended_params
from .tables import (METHODS_HEADS, TABLE4_HEADS, campaign_table, csv_text, read_truth, ride_table, table4_table,
                     verdict_table, waveform_table)
from .ride import ride_section
from .verdict import agreement_text, fmus_section, not_recommended_reason, verdict_section

__all__ = ["render_report", "write_report"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:2em auto;max-width:1150px;
color:#1d2733;line-height:1.45;padding:0 1em}
h1{font-size:1.7em;margin-bottom:.2em}h2{border-bottom:2px solid #3a6ea5;padding-bottom:.2em;margin-top:2em}
h3{margin-top:1.6em;color:#3a6ea5}table{border-collapse:collapse;margin:.6em 0 1.2em;font-size:.92em}
th,td{border:1px solid #c9d3de;padding:.3em .6em;text-align:right}th{background:#e8eff7}
td.l,th.l{text-align:left}.ok{color:#1c7c3a;font-weight:600}.bad{color:#b3261e;font-weight:600}.warn{color:#8a5a00}
.note{color:#556;font-size:.9em}img{max-width:100%;border:1px solid #dde3ea;margin:.4em 0}
.effect{background:#fff6e0;border-left:4px solid #e0a800;padding:.4em .8em;margin:.4em 0}
code{background:#eef2f6;padding:0 .25em;border-radius:3px}
.scroll{overflow-x:auto;max-width:100%}td.truth{color:#5a6b7d;font-style:italic}td.final{font-weight:600}
nav.toc{background:#f4f7fa;border:1px solid #dde3ea;padding:.5em 1em;margin:1em 0}nav.toc a{margin-right:1em}
.howto{background:#f4f7fa;border-left:4px solid #3a6ea5;padding:.5em 1em;margin:1em 0;font-size:.92em}
.howto dt{font-weight:600}.howto dd{margin:0 0 .3em 1em}
@media (max-width:900px){body{padding:0 .4em}table{font-size:.8em}th,td{padding:.2em .3em}}
@media (max-width:700px){table.verdict,table.verdict tbody,table.verdict tr,table.verdict td{display:block}
table.verdict tr:first-child{display:none}table.verdict tr{border:1px solid #c9d3de;margin:0 0 .6em;padding:.2em}
table.verdict td{border:0;text-align:left;padding:.1em .3em}
table.verdict td::before{content:attr(data-label) ": ";font-weight:600;color:#556}}
@media print{body{max-width:none;margin:0;font-size:10pt}nav.toc,.downloads{display:none}
img{max-width:100%;page-break-inside:avoid}h2{page-break-after:avoid}tr{page-break-inside:avoid}
a{color:inherit;text-decoration:none}}
"""


def _e(x) -> str:
    return html.escape(str(x))


#: Largest batch whose figures are embedded in the report; a larger one links them (``figures/*.png``),
#: so that neither the page nor the process writing it grows with the batch.
EMBED_MAX_RECORDINGS = 20


def _img(png, alt: str) -> str:
    """An image: PNG bytes or a staged file embedded as a data URI, a file under ``figures/`` linked."""
    if isinstance(png, Path):
        if png.parent.name == "figures":
            return f'<img alt="{_e(alt)}" loading="lazy" src="figures/{_e(png.name)}">'
        png = png.read_bytes()
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def _summary(result: BatchResult) -> str:
    rows = []
    for r in result.recordings:
        if not r.ok:
            rows.append(f'<tr><td class="l">{_e(Path(r.source).name)}</td><td class="l bad">failed</td>'
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
        warned = (d or {}).get("warnings") or []
        if warned:      # what the conditioning and the diagnosis warned of (cleatfmu: warning: ... on the CLI)
            detail += "".join(f'<br><span class="warn">warning: {_e(w)}</span>' for w in warned)
        rows.append(f'<tr><td class="l">{_e(Path(r.source).name)}</td><td class="l">{status}</td>'
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


def _toc(result: BatchResult) -> str:
    parts = [('recommended', 'verdict'), ('howto', 'how to read this'), ('speed', 'k, c vs speed'),
             ('summary', 'recordings'), ('table4', "paper's Table 4"), ('waveform', 'methods side by side'),
             ('diagnoses', 'diagnoses and ride comfort'), ('tires', 'tires'), ('fmus', 'FMUs'), ('timings', 'run')]
    links = " ".join(f'<a href="#{a}">{_e(b)}</a>' for a, b in parts)
    tires = " ".join(f'<a href="#tire-{_e(r.stem)}-{t.tire}">{_e(r.stem)} {t.tire}</a>' for r, t in _tires(result))
    return f'<nav class="toc"><b>Contents</b>: {links}<br><span class="note">Tires: {tires}</span></nav>'


_HOWTO = ('<section id="howto"><h2>How to read this</h2><dl class="howto">'
          '<dt>k, c</dt><dd>Tire vertical stiffness (N/m, shown kN/m) and damping (N·s/m, shown kN·s/m) of the '
          'point-contact spring ∥ damper at the static load.</dd>'
          '<dt>95 % interval</dt><dd>From the joint fit (sandwich covariance, with the move of the estimates when '
          'the time step is halved); valid if the model is right. Within one run only: sensor noise and model '
          'error, not the scatter from test to test.</dd>'
          '<dt>pooled interval</dt><dd>Over repeated runs of one condition: the random-effects mean\'s 95 % '
          'interval, which holds the between-run scatter; "runs disagree" when Cochran\'s Q says they scatter '
          'beyond their fit intervals (p &lt; 0.05).</dd>'
          '<dt>NRMSE</dt><dd>RMS of measured − simulated over the RMS of the measured hub acceleration, after the '
          'zero-phase 100 Hz low-pass.</dd>'
          '<dt>noise NRMSE</dt><dd>The NRMSE the measurement noise alone would give: a fit at the noise floor '
          'scores about this; "at the noise floor" means within 1.5× it.</dd>'
          '<dt>above the noise floor</dt><dd>A channel whose residual stays above 1.5× its noise: the ratio, the '
          'share of the signal energy beyond the noise and the window where it sits; its intervals are '
          'conditional on the model.</dd>'
          '<dt>effects</dt><dd>What the four-corner point-contact model misses, named by forward selection '
          '(BIC, ≥ 25 % of the residual removed, a physical check each).</dd>'
          '<dt>paper / waveform / final</dt><dd>The paper\'s method reads k from the first two peaks of one damped '
          'sinusoid; the waveform fit uses the whole free decay of the same one-corner model; the final model fits '
          'every channel at once under the body with the named effects. Body cross-talk, footprint and lift-off '
          'bias the first two, which is why they differ from the final values.</dd>'
          '<dt>a_w, VDV</dt><dd>ISO 2631-1 frequency-weighted (Wk) RMS acceleration and vibration dose value at '
          'the seat, on an ISO 8608 road. The "seat" is a point of the rigid body (the cab floor under the seat): '
          'the model has no seat suspension or cushion, so these are floor values, not the occupant\'s.</dd>'
          '</dl></section>')


def _speed(figure: bytes | None) -> str:
    if figure is None:
        return ""
    return ('<section id="speed"><h2>k and c against speed</h2><p class="note">Recommended (final) values with '
            'their 95 % intervals, beside the paper\'s and the waveform values (and the rig truth where known).</p>'
            + _img(figure, "k and c against speed") + "</section>")


def _diagnosis_section(r) -> str:
    rep = r.diagnosis
    out = [f'<section id="diagnosis-{_e(r.stem)}"><h3>{_e(r.stem)}: whole-tractor diagnosis</h3>']
    for err in rep.errors:
        out.append(f'<p class="bad">{_e(err)}</p>')
    d = rep.diagnosis
    if d is not None:
        body = d["body"]
        effects = effects_sentence(d)
        speed = body["speed_m_s"]
        delay = "" if speed["from_delay"] is None else \
            f', {speed["from_delay"] * 3.6:.2f} km/h from the front/rear delay'
        indices = "; ".join(f'{name.replace("_", " ")} '
                            + interval_text(body[name]["value"], *body[name]["ci"], sep="–")
                            for name in ("pitch_index", "roll_index", "pivot_index") if body.get(name))
        out.append(f'<p>Effects the four-corner model misses: <b>{_e(effects)}</b>. Front axle {body["front_axle"]}'
                   f'{"; " + indices if indices else ""}. Speed {speed["sidecar"] * 3.6:.2f} km/h (sidecar){delay}. '
                   + agreement_text(d["agreement"])
                   + f'; diagnosis {d["seconds"]:.1f} s'
                   + (f' (and {d["compile_seconds"]:.1f} s compiling the model\'s code, once per install)'
                      if d.get("compile_seconds") else "")
                   + f'. Intervals: {_e(d["intervals"])}.</p>')
        for name in d["effects"]:
            out.append(f'<div class="effect"><b>{_e(name)}</b>: {_e(d["evidence"].get(name, ""))}</div>')
        if "diagnosis" in rep.figures:
            out.append(_img(rep.figures["diagnosis"], f"{r.stem} whole-tractor diagnosis"))
        if "impacts" in rep.figures:
            out.append(_img(rep.figures["impacts"], f"{r.stem} impacts"))
    if rep.ride is not None:
        out.append(ride_section(rep.ride, _img(rep.figures["ride"], f"{r.stem} ride comfort")
                                if "ride" in rep.figures else ""))
    out.append("</section>")
    return "".join(out)


def _tire_section(r, t) -> str:
    out = [f'<section id="tire-{_e(r.stem)}-{t.tire}"><h3>{_e(r.stem)} · {t.tire}</h3>']
    for err in t.errors:
        out.append(f'<p class="bad">{_e(err)}</p>')
    if r.recommended(t.tire) is not None:
        out.append(f'<p class="note">Recommended: <a href="{recommended_fmu(r.stem, t.tire)}">'
                   f'<code>{recommended_fmu(r.stem, t.tire)}</code></a> (k and c in '
                   f'<a href="{recommended_params(r.stem)}"><code>{recommended_params(r.stem)}</code></a>; plain '
                   f'spring-damper: <a href="{point_contact_fmu(r.stem, t.tire)}"><code>'
                   f'{point_contact_fmu(r.stem, t.tire)}</code></a>).</p>')
    fmu = next((f["file"] for f in t.fmus if not f.get("recommended")), None)
    if fmu is not None:
        method = "waveform" if t.waveform else "paper"
        params = not_recommended_params(r.stem, t.tire, method)
        out.append(f'<p class="warn">This corner\'s own fit, <a href="{_e(fmu)}"><code>{_e(fmu)}</code></a> '
                   f'(<a href="{_e(params)}"><code>{_e(params)}</code></a>), is '
                   f'{_e(not_recommended_reason(r, t))}.</p>')
    if "decay" in t.figures:
        out.append(_img(t.figures["decay"], f"{r.stem} {t.tire} decay"))
    s = t.simulate
    if s is not None:
        out.append(f'<p>Point-contact FMU co-simulated with fmpy: NRMSE <b>{s["nrmse"]:.1%}</b>, R² {s["r2"]:.3f}; '
                   f'k<sub>FMU</sub> {s["k_fmu"] / 1e3:.1f} kN/m, re-identified {s["k_reidentified"] / 1e3:.1f} kN/m; '
                   f'the misfit sits mostly in the <b>{_e(s["worst_window"].replace("_", " "))}</b> window.</p>')
        out += [f'<p class="warn">warning: {_e(w)}</p>' for w in s.get("warnings") or []]
        out.append(_img(t.figures.get("comparison", b""), f"{r.stem} {t.tire} co-simulation")
                   if "comparison" in t.figures else "")
    out.append("</section>")
    return "".join(out)


def _timings(result: BatchResult, extra: dict | None) -> str:
    total = sum(result.timings.values()) or 1.0
    rows = "".join(f'<tr><td class="l">{_e(k)}</td><td>{v:.1f}</td><td>{v / total:.0%}</td></tr>'
                   for k, v in sorted(result.timings.items(), key=lambda kv: -kv[1]))
    more = "".join(f"<li>{_e(k)}: {_e(v)}</li>" for k, v in (extra or {}).items())
    return (f'<section id="timings"><h2>Run</h2><p>Wall time {result.seconds:.1f} s. CPU time per stage, summed over '
            f'the parallel jobs:</p><table><tr><th class="l">stage</th><th>s</th><th>share</th></tr>{rows}</table>'
            f'<ul class="note">{more}</ul></section>')


def render_report(result: BatchResult, *, title: str = "cleatfmu report", extra: dict | None = None,
                  tables: dict | None = None, speed_png: bytes | None = None) -> str:
    """The report as an HTML string (`tables` and `speed_png` as :func:`write_report` builds them)."""
    tables = tables if tables is not None else build_tables(result, {})
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    tires = "".join(_tire_section(r, t) for r, t in _tires(result))
    diagnoses = "".join(_diagnosis_section(r) for r in result.recordings if r.diagnosis is not None)
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1"><title>{_e(title)}</title>'
            f'<style>{_CSS}</style></head><body><h1>{_e(title)}</h1><p class="note">cleatfmu {__version__}, {stamp}. '
            'Hub accelerations in m/s², gravity excluded; all comparisons after the zero-phase 100 Hz low-pass.</p>'
            f'{verdict_section(result, tables)}{_toc(result)}{_HOWTO}{_speed(speed_png)}{_summary(result)}'
            '<section id="table4"><h2>Stiffness and damping by the paper\'s method (Table 4)</h2>'
            '<p class="note">T and δ from the first two peaks, ζ and ω<sub>n</sub> by eqs. 7-8, K = m ω<sub>n</sub>²,'
            ' C by the exponential fit through the first peak (eqs. 16-17), R² of the semi-log regression.</p>'
            f'{tables["table4"].html(head=TABLE4_HEADS)}</section>'
            '<section id="waveform"><h2>The methods side by side (kN/m, kN·s/m)</h2><p class="note">The paper\'s '
            'method and the waveform fit model one corner; the final model, every channel under the body with the '
            'named effects (see "how to read this").</p>'
            f'{tables["methods"].html(head=METHODS_HEADS)}</section>'
            f'<section id="diagnoses"><h2>Whole-tractor diagnoses</h2>{diagnoses}</section>'
            f'<section id="tires"><h2>Tires: decay, point-contact co-simulation</h2>{tires}</section>'
            f'{fmus_section(result)}{_timings(result, extra)}</body></html>\n')


def build_tables(result: BatchResult, truths: dict) -> dict:
    """Every table of the report, by CSV name."""
    tables = [verdict_table(result, truths), campaign_table(result), table4_table(result), waveform_table(result),
              ride_table(result)]
    return {t.name: t for t in tables}


def _speed_png(result: BatchResult, truths: dict) -> bytes | None:
    """k and c against speed per tire (final with intervals, paper, waveform, truth), or None (one speed)."""
    points = []
    for r, t in _tires(result):
        rec = r.recommended(t.tire)
        if rec is None or r.speed_kmh is None:
            continue
        truth = (truths.get(r.source) or {}).get("tires", {}).get(t.tire) or {}
        points.append({"tire": t.tire, "speed_kmh": r.speed_kmh, "final": rec, "truth": truth,
                       "paper": t.paper or {}, "waveform": t.waveform or {}})
    if len({p["speed_kmh"] for p in points}) < 2:
        return None
    from .plots import plot_k_c_vs_speed, png_bytes
    return png_bytes(plot_k_c_vs_speed(points))


def write_report(result: BatchResult, *, title: str = "cleatfmu report", extra: dict | None = None) -> Path:
    """Write ``report.html``, ``summary.json`` and ``tables/*.csv`` into the batch's output folder, as one set;
    return the report's path."""
    out = Path(result.out_dir)
    truths = {r.source: read_truth(r.source) for r in result.recordings}
    tables = build_tables(result, truths)
    summary = summary_document(result)
    staging = out / FIGURES_STAGING
    if len(result.recordings) > EMBED_MAX_RECORDINGS and staging.is_dir():
        _publish_figures(result, staging, out / "figures")
    page = render_report(result, title=title, extra=extra, tables=tables, speed_png=_speed_png(result, truths))
    (out / "tables").mkdir(exist_ok=True)
    atomic_write_texts({out / "report.html": page,
                        out / "summary.json": json_text(summary, indent=1, default=float) + "\n",
                        **{out / "tables" / f"{name}.csv": csv_text(t) for name, t in tables.items()}})
    shutil.rmtree(staging, ignore_errors=True)
    return out / "report.html"


def _files_of(r) -> dict:
    """The recommended files of a recording that has them (paths relative to the report folder)."""
    fmus = {f["file"] for f in (r.diagnosis.fmus if r.diagnosis is not None else [])}
    tires = [t.tire for t in r.tires if r.recommended(t.tire) is not None]
    return {"recommended_fmus": {t: recommended_fmu(r.stem, t) for t in tires if recommended_fmu(r.stem, t) in fmus},
            "point_contact_fmus": {t: point_contact_fmu(r.stem, t) for t in tires
                                   if point_contact_fmu(r.stem, t) in fmus},
            "params": recommended_params(r.stem) if tires else None}


def summary_document(result: BatchResult) -> dict:
    """``summary.json``: every number (SI units), and per recording its name, its recommended files and its
    diagnosis (the body ``simulate``/``ssp``/``ride --body summary.json`` take for that recording)."""
    recordings = []
    for r in result.recordings:
        files = _files_of(r)
        tires = {}
        for t in r.tires:
            rec = r.recommended(t.tire)
            if rec is not None:
                rec = dict(rec, fmu=files["recommended_fmus"].get(t.tire),
                           point_contact_fmu=files["point_contact_fmus"].get(t.tire))
            tires[t.tire] = {"recommended": rec, "paper": t.paper, "waveform": t.waveform, "simulate": t.simulate,
                             "fmus": t.fmus, "errors": t.errors}
        recordings.append({"name": r.stem, "source": r.source, "ok": r.ok, "error": r.error,
                           "conditions": r.conditions, **files,
                           "diagnosis": r.diagnosis.diagnosis if r.diagnosis is not None else None,
                           "diagnosis_fmus": r.diagnosis.fmus if r.diagnosis is not None else [],
                           "diagnosis_errors": r.diagnosis.errors if r.diagnosis is not None else [],
                           "ride": r.diagnosis.ride if r.diagnosis is not None else None, "tires": tires})
    return {"format": "cleatfmu-report-summary/1",
            "use": "per recording, recommended_fmus (fmu/<recording>_<TIRE>.fmu) carry the recommended k and c; "
                   "'cleatfmu simulate fmu --body summary.json REC.csv' (also ssp, ride --body) takes the "
                   "recording's diagnosis from here",
            "recordings": recordings, "campaign": result_conditions(result),
            "failures": result.failures, "seconds": result.seconds,
            "stage_seconds": result.timings}


def _publish_figures(result: BatchResult, staging: Path, target: Path) -> None:
    """Move the staged figures to ``figures/`` (replacing an earlier run's) and point the reports at them."""
    if target.exists():
        shutil.rmtree(target)
    os.replace(staging, target)
    for r in result.recordings:
        for rep in list(r.tires) + ([r.diagnosis] if r.diagnosis is not None else []):
            for key, path in rep.figures.items():
                if isinstance(path, Path):
                    rep.figures[key] = target / path.name
