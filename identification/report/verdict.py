"""The report's first screen and its file list: the verdict with every warning beside it, which file to take,
and the FMUs with why the ones not recommended are not.

The verdict is never green over a warning it does not show: the conditioning's and the diagnosis'
warnings, and any failed stage, are listed in the verdict itself, and its status says how many there are.
"""

from __future__ import annotations

import html

from .files import NOT_RECOMMENDED, POINT_CONTACT
from .tables import CAMPAIGN_HEADS, verdict_heads

__all__ = ["recording_warnings", "verdict_section", "campaign_text", "fmus_section", "files_note",
           "not_recommended_reason",
           "agreement_text"]


def _e(x) -> str:
    return html.escape(str(x))


def recording_warnings(r) -> list[str]:
    """What a recording's conditioning and diagnosis warned of, and its failed stages (one sentence each)."""
    if not r.ok:
        return [f"not processed: {r.error}"]
    d = r.diagnosis.diagnosis if r.diagnosis is not None else None
    out = list((d or {}).get("warnings") or [])
    out += [f"{t.tire}: {e}" for t in r.tires for e in t.errors]
    out += list(r.diagnosis.errors if r.diagnosis is not None else ["not diagnosed"])
    return out


def files_note() -> str:
    """Which file to take (the verdict's last paragraph)."""
    return ('<p class="note"><b>Which file to take</b>: per tire <code>fmu/&lt;recording&gt;_&lt;TIRE&gt;.fmu</code>'
            ', the extended tire of the verdict\'s k and c (its built-in test cleat is off, '
            '<code>cleat_height</code> 0, so a ride model gets its own road); '
            f'<code>fmu/{POINT_CONTACT}/</code> holds a plain spring ∥ damper of the same k and c for an importer '
            'without the extended tire\'s inputs, <code>params/&lt;recording&gt;.json</code> the k and c with '
            f'their intervals. <code>fmu/{NOT_RECOMMENDED}/</code> and <code>params/{NOT_RECOMMENDED}/</code> '
            'hold the one-corner fits, for comparison only (<a href="#fmus">why</a>). The four tires of a '
            'recording under its diagnosed body: <code>cleatfmu simulate fmu --body summary.json '
            'REC.csv</code>.</p>')


def campaign_text(table) -> str:
    """The paragraph above the one-row-per-condition table: the grouping rule, where its intervals come from,
    and which conditions' runs disagree beyond their fit intervals."""
    from .campaign import LOAD_RTOL, PRESSURE_RTOL, SPEED_TOLERANCE_KMH

    col = {name: i for i, name in enumerate(table.columns)}
    repeated = [row for row in table.rows if row[col["runs"]] > 1]
    apart = [f'{row[col["tire"]]} at {row[col["speed_km_h"]]:.3g} km/h' for row in repeated
             if row[col["runs_disagree"]]]
    text = (f'<p><b>One answer per tire and condition</b> (same position, speed within {SPEED_TOLERANCE_KMH:g} '
            f'km/h, wheel load within {100 * LOAD_RTOL:g} %, inflation pressure within {100 * PRESSURE_RTOL:g} %, '
            'the same vehicle and tire named in the sidecar). ')
    if repeated:
        text += ('Repeated runs are pooled into a random-effects mean: its 95 % interval comes from the '
                 '<b>between-run scatter</b> (REML, Hartung-Knapp-Sidik-Jonkman, t on runs − 1 degrees of '
                 'freedom), and the values are rounded to the digits it supports. The pooled k and c of each '
                 'condition of repeated runs are written as a parameter file and a point-contact tire FMU '
                 '(<code>params/campaign/</code>, <code>fmu/campaign/</code>; linked in the table). ')
    if len(repeated) < len(table.rows):
        text += ('A condition of one run keeps its own fit interval: <b>within-run only</b> (sensor noise and '
                 'model error inside that run), <span class="warn">one run: no repeatability measured</span>. ')
    if apart:
        text += (f'<span class="warn">The runs of {len(apart)} condition(s) ({_e(", ".join(apart))}) disagree '
                 'beyond their fit intervals (Cochran\'s Q, p < 0.05): test-to-test scatter the single-run '
                 'intervals leave out; take the pooled values.</span>')
    return text + "</p>" + table.html(head=CAMPAIGN_HEADS, cls="verdict")


def verdict_section(result, tables: dict) -> str:
    """``<section id="recommended">``: the status, each recording's effects and warnings, the table."""
    table = tables["verdict"]
    conditional = any(row[12] != "at the noise floor" for row in table.rows)
    truth = "k_truth_N_m" in table.columns
    warned = {r.stem: recording_warnings(r) for r in result.recordings}
    n_warn = sum(len(w) for w in warned.values())
    campaign = tables.get("campaign")
    apart = sum(1 for row in campaign.rows if row[campaign.columns.index("runs_disagree")]) if campaign else 0
    if conditional:
        status = ('<span class="bad">Some tire keeps a residual above its noise floor: its intervals hold only if '
                  'the model is right.</span>')
    elif n_warn:
        status = (f'<span class="warn">Every tire diagnosed is fitted to within its noise floor, but the run warned '
                  f'of {n_warn} thing(s), listed under each recording below: read them before using these '
                  f'values.</span>')
    elif apart:
        status = (f'<span class="warn">Every tire diagnosed is fitted to within its noise floor, but the repeated '
                  f'runs of {apart} condition(s) disagree beyond their fit intervals: take the pooled values and '
                  f'intervals below.</span>')
    else:
        status = '<span class="ok">Every tire is fitted to within its noise floor, with no warning.</span>'
    items = []
    for r in result.recordings:
        d = r.diagnosis.diagnosis if r.diagnosis is not None else None
        head = f'{_e(r.stem)} ({r.speed_kmh:.3g} km/h): ' if r.ok else f'{_e(r.stem)}: '
        head += ("effects the four-corner model misses: <b>" + _e(d.get("summary") or ", ".join(d["effects"]) or "none")
                 + "</b>") if d is not None else '<span class="bad">no verdict</span>'
        items.append(f"<li>{head}" + "".join(f'<br><span class="warn">warning: {_e(w)}</span>'
                                             for w in warned[r.stem]) + "</li>")
    return ('<section id="recommended"><h2>Verdict: recommended stiffness and damping</h2>'
            '<p>One joint fit per recording: every channel at once under one body (heave, pitch, roll), with the '
            'effects the diagnosis named; these k and c are the ones in the recommended FMUs. ' + status
            + (' Rig truth (in italics) from the recording\'s truth file, shown for comparison only.' if truth else '')
            + f'</p><ul class="note">{"".join(items)}</ul>'
            + (campaign_text(campaign) if campaign else "")
            + '<p class="note">Per recording: each run\'s own joint fit; its intervals are <b>within-run only</b> '
              '(sensor noise and model error inside that run, not test-to-test scatter).</p>'
            + table.html(head=verdict_heads(table), cls="verdict") + files_note()
            + '<p class="downloads note">Download: <a href="summary.json">summary.json</a> · '
            + " · ".join(f'<a href="tables/{name}.csv">{name}.csv</a>' for name in tables) + '</p></section>')


def agreement_text(agreement: float | None) -> str:
    """How the extended FMUs under the body agree with the fitting model (never ``to 0.0e+00``)."""
    if agreement is None:
        return "The extended model's FMUs cannot start (see the warnings): none was kept"
    if agreement == 0.0:
        return "Extended FMUs co-simulated under the body give the fitting model's hub accelerations bit for bit"
    return (f"Extended FMUs co-simulated under the body agree with the fitting model to {agreement:.1e} of the "
            f"largest hub acceleration")


def not_recommended_reason(r, t) -> str:
    """Why a tire's one-corner FMU is not recommended: its NRMSE and k bias against the diagnosis'."""
    rec = r.recommended(t.tire)
    fit = t.waveform or t.paper
    parts = []
    if t.simulate is not None:
        parts.append(f"it reproduces the recording at NRMSE {t.simulate['nrmse']:.0%}")
    if rec is not None:
        dt = r.diagnosis.diagnosis["tires"][t.tire]
        if parts:
            parts[-1] += f" against the recommended model's {dt['nrmse_after']:.1%} (noise {dt['noise_nrmse']:.1%})"
        if fit is not None:
            parts.append(f"its k {fit['k'] / 1e3:.1f} kN/m is {100 * (fit['k'] / rec['k'] - 1):+.0f} % and its c "
                         f"{100 * (fit['c'] / rec['c'] - 1):+.0f} % against the recommended "
                         f"{rec['k'] / 1e3:.1f} kN/m, {rec['c'] / 1e3:.3f} kN·s/m")
    return ("not recommended: one corner under its own mass cannot follow a body that couples the four tires"
            + ("; " + "; ".join(parts) if parts else ""))


def fmus_section(result) -> str:
    """``<section id="fmus">``: every FMU written, recommended ones first, with its validation."""
    rows = []
    for r in result.recordings:
        listed = [(f, None) for f in (r.diagnosis.fmus if r.diagnosis is not None else [])]
        listed += [(f, t) for t in r.tires for f in t.fmus]
        for f, t in sorted(listed, key=lambda ft: not ft[0].get("recommended", False)):
            ok = not f.get("problems")
            check = '<span class="ok">validate_fmu: no problem</span>' if ok else \
                '<span class="bad">' + _e("; ".join(f["problems"])) + "</span>"
            if f.get("recommended"):
                use = '<span class="ok">recommended</span>'
            else:
                use = f'<span class="bad">{_e(not_recommended_reason(r, t))}</span>' if t is not None else \
                    '<span class="bad">not recommended</span>'
            rows.append(f'<tr><td class="l"><a href="{_e(f["file"])}"><code>{_e(f["file"])}</code></a></td>'
                        f'<td class="l">{_e(f["kind"])}</td><td class="l">{_e(f["role"])}</td>'
                        f'<td class="l">{use}</td><td class="l">{check}</td></tr>')
    return ('<section id="fmus"><h2>Exported FMUs</h2><p class="note">FMI 2.0 co-simulation, native C: binaries '
            'for linux64, win64 and darwin64 and the C sources inside; the importing machine needs no Python. '
            '"validate_fmu" checks the file\'s form only; whether to use it is the "use" column.</p>'
            '<div class="scroll"><table><tr><th class="l">file</th><th class="l">kind</th>'
            '<th class="l">content</th><th class="l">use</th><th class="l">validation</th></tr>'
            f'{"".join(rows)}</table></div></section>')
