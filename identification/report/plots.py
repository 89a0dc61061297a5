"""Figures (matplotlib, headless): the paper's Figure 9a/9b and measured-vs-simulated overlays.

Every function draws into a new figure and returns it; :func:`save_png` writes
it atomically.  Units are on every axis.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .._files import atomic_write_bytes

__all__ = ["figure", "save_png", "png_bytes", "plot_decay", "plot_log_peaks", "plot_comparison", "plot_diagnosis",
           "plot_tractor_diagnosis", "plot_impact_zooms", "plot_ride", "plot_k_c_vs_speed",
           "plot_static", "plot_third_octave"]


def figure(nrows=1, ncols=1, *, size=(9.0, 4.0), **kwargs):
    """A new figure with the non-interactive Agg backend."""
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(nrows, ncols, figsize=size, **kwargs)
    return fig, axes


#: Colours of a figure's PNG palette: line plots on white need few, and a palette PNG is about a quarter of
#: a true-colour one (the demo report: 2.3 MB of figures become 0.6 MB).
PNG_COLOURS = 32


def png_bytes(fig, dpi: int = 110) -> bytes:
    """The figure as palette PNG bytes (PNG_COLOURS colours, no dithering); the figure is closed."""
    import matplotlib.pyplot as plt
    from PIL import Image

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    image = Image.open(io.BytesIO(buf.getvalue())).convert("RGB")
    out = io.BytesIO()
    image.quantize(colors=PNG_COLOURS, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(
        out, format="png", optimize=True)
    return out.getvalue()


def save_png(fig, path, dpi: int = 110) -> Path:
    """Write the figure to `path` (all or nothing); the figure is closed.  A file that cannot be written (a full
    disk) is an InputError naming `path`, not an error of stdout."""
    from ..errors import InputError

    path = Path(path)
    data = png_bytes(fig, dpi)
    try:
        atomic_write_bytes({path: data})
    except OSError as exc:
        raise InputError(path, f"cannot write: {exc.strerror or exc}") from None
    return path


def _decay_curve(ax, sig, decay_rate, style, label):
    t1, a1 = sig.peak_times_s[0], sig.peak_values_m_s2[0]
    tt = np.linspace(t1, sig.window_end_s, 200)
    ax.plot(tt, a1 * np.exp(decay_rate * (tt - t1)), style, lw=1.2, label=label)


def plot_decay(ax, sig, decay_rate, *, label="measured", color="C0", t_span=None):
    """Paper Fig. 9a: filtered acceleration, the peaks used and the fitted decay curve."""
    t = sig.time_s
    lo, hi = t_span or (sig.impact_s - 0.1, sig.window_end_s + 0.1)
    sel = (t >= lo) & (t <= hi)
    ax.plot(t[sel], sig.filtered_m_s2[sel], color=color, lw=0.9, label=f"{label} (low-pass)")
    ax.plot(sig.peak_times_s, sig.peak_values_m_s2, "o", mfc="none", color=color, label=f"{label} peaks")
    _decay_curve(ax, sig, decay_rate, "--", f"{label} decay curve")
    ax.set_xlabel("time / s")
    ax.set_ylabel("hub acceleration / (m/s²)")
    ax.grid(alpha=0.3)


def plot_log_peaks(ax, sig, decay_rate, *, label="measured", color="C0"):
    """Paper Fig. 9b: ln(peak) against time and the regression through the first peak."""
    t, y = sig.peak_times_s, np.log(sig.peak_values_m_s2)
    ax.plot(t, y, "o", color=color, label=f"{label} ln(peak)")
    ax.plot(t, y[0] + decay_rate * (t - t[0]), "--", color=color, label=f"fit, slope {decay_rate:.3f} 1/s")
    ax.set_xlabel("time / s")
    ax.set_ylabel("ln(peak / (m/s²))")
    ax.grid(alpha=0.3)


_WINDOW_COLORS = {"impact": "#f4c27a", "free_decay": "#bfe3bf", "other_axle": "#c9c3f0"}


def _limit_to(ax, measured, factor=1.6):
    """Scale the y axis to the measurement; model spikes beyond it run off the plot, which the label says (in
    words that cannot be read as a saturated sensor: the measurement itself is inside the axis)."""
    top = factor * float(np.max(np.abs(measured))) if np.size(measured) else 1.0
    lo, hi = ax.get_ylim()
    if hi > top or lo < -top:
        ax.set_ylim(-top, top)
        # inside the axis, once: as a second line of the y label it ran beyond a short panel's height, over
        # its neighbours' labels
        if not any(getattr(text, "_limit_note", False) for text in ax.texts):
            note = ax.text(0.005, 0.02, _LIMIT_NOTE.format(factor=factor), transform=ax.transAxes, fontsize=7,
                           color="0.3", ha="left", va="bottom",
                           bbox={"facecolor": "white", "alpha": 0.7, "edgecolor": "none", "pad": 1.0})
            note._limit_note = True


#: The note of an axis scaled to the measurement while the model runs beyond it.
_LIMIT_NOTE = "axis ±{factor:g}× the measured peak; model peaks beyond it"


def plot_comparison(cmp, *, title: str | None = None):
    """Measured vs co-simulated hub acceleration with both decay curves, and the residual per window."""
    fig, (ax, ax_r) = figure(2, 1, size=(10.0, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    t = cmp.time_s
    meas, sim = cmp.measured_signal, cmp.simulated_signal
    lo = min(w.start_s for w in cmp.windows.values()) - 0.05
    hi = t[-1]
    sel = (t >= lo) & (t <= hi)
    ax.plot(t[sel], cmp.measured_m_s2[sel], color="C0", lw=0.9, label="measured (low-pass)")
    ax.plot(t[sel], cmp.simulated_m_s2[sel], color="C3", lw=0.9, label="co-simulated FMU (low-pass)")
    ax.plot(meas.peak_times_s, meas.peak_values_m_s2, "o", mfc="none", color="C0", label="measured peaks")
    ax.plot(sim.peak_times_s, sim.peak_values_m_s2, "x", color="C3", label="simulated peaks")
    _decay_curve(ax, meas, -cmp.decay_rate_measured, "C0--",
                 f"measured decay, {cmp.decay_rate_measured:.3f} 1/s")
    _decay_curve(ax, sim, -cmp.decay_rate_simulated, "C3--",
                 f"simulated decay, {cmp.decay_rate_simulated:.3f} 1/s")
    ax.set_ylabel("hub acceleration / (m/s²)")
    _limit_to(ax, cmp.measured_m_s2[sel])
    ax.set_title(title or f"{cmp.tire}: NRMSE {cmp.nrmse:.1%}, R² {cmp.r2:.3f}, "
                          f"k_FMU {cmp.k_fmu / 1e3:.1f} kN/m, c_FMU {cmp.c_fmu / 1e3:.2f} kN·s/m")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2, loc="upper right")
    ax_r.plot(t[sel], cmp.simulated_m_s2[sel] - cmp.measured_m_s2[sel], color="k", lw=0.7, label="residual")
    for name, w in cmp.windows.items():
        color = _WINDOW_COLORS.get(name, "#dddddd")
        ax.axvspan(max(w.start_s, lo), w.end_s, color=color, alpha=0.35, lw=0)
        ax_r.axvspan(max(w.start_s, lo), w.end_s, color=color, alpha=0.35, lw=0,
                     label=f"{name.replace('_', ' ')}: NRMSE {w.nrmse:.0%}, {w.misfit_share:.0%} of misfit")
    ax_r.legend(fontsize=7, loc="upper right", ncol=2)
    ax_r.set_xlabel("time / s")
    ax_r.set_ylabel("sim − meas / (m/s²)")
    _limit_to(ax_r, cmp.measured_m_s2[sel])
    ax_r.grid(alpha=0.3)
    return fig


def plot_diagnosis(diag, *, nrmse_before=None, nrmse_after=None, title: str | None = None):
    """Measured vs point-contact and extended models, the residuals, and the effects named."""
    pb = diag.problem
    t = pb.rec.time_s
    w = pb.window
    fig, (ax, ax_r) = figure(2, 1, size=(10.0, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    before = diag.baseline.nrmse if nrmse_before is None else nrmse_before
    after = diag.final.nrmse if nrmse_after is None else nrmse_after
    label = " + ".join(diag.effects) or "no effect named"
    ax.plot(t[w], pb.measured[w], color="C0", lw=1.0, label="measured (low-pass)")
    ax.plot(t[w], diag.baseline.prediction[w], color="C7", lw=0.9, ls="--",
            label=f"point contact, NRMSE {before:.1%}")
    ax.plot(t[w], diag.final.prediction[w], color="C3", lw=0.9, label=f"extended ({label}), NRMSE {after:.1%}")
    ax.set_ylabel("hub acceleration / (m/s²)")
    _limit_to(ax, pb.measured[w])
    ax.set_title(title or f"{pb.tire}: effects found: {label}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    ax_r.plot(t[w], (diag.baseline.prediction - pb.measured)[w], color="C7", lw=0.7, label="point contact − measured")
    ax_r.plot(t[w], (diag.final.prediction - pb.measured)[w], color="C3", lw=0.7, label="extended − measured")
    ax_r.set_xlabel("time / s")
    ax_r.set_ylabel("residual / (m/s²)")
    _limit_to(ax_r, pb.measured[w])
    ax_r.grid(alpha=0.3)
    ax_r.legend(fontsize=8, loc="upper right")
    return fig


def plot_tractor_diagnosis(diag, *, nrmse_before=None, nrmse_after=None):
    """Every channel: measured vs the four-corner baseline and the final whole-tractor model."""
    pb = diag.problem
    t, w = pb.rec.time_s, pb.window
    n = len(pb.channels)
    fig, axes = figure(n, 1, size=(10.0, 2.3 * n + 0.8), sharex=True, squeeze=False)
    before = nrmse_before or diag.baseline.nrmse
    after = nrmse_after or diag.final.nrmse
    label = " + ".join(diag.effects) or "no effect named"
    for ax, ch in zip(axes[:, 0], pb.channels):
        ax.plot(t[w], pb.measured[ch][w], color="C0", lw=1.0, label=f"{ch} measured (low-pass)")
        ax.plot(t[w], diag.baseline.prediction[ch][w], color="C7", lw=0.8, ls="--",
                label=f"corners, NRMSE {before[ch]:.1%}")
        ax.plot(t[w], diag.final.prediction[ch][w], color="C3", lw=0.8, label=f"final, NRMSE {after[ch]:.1%}")
        left = diag.unexplained.get(ch)
        if left:
            ax.axvspan(*left["window"], color="#f4c27a", alpha=0.35,
                       label=f"unexplained {left['share']:.1%} of the signal")
        finish_channel_axis(ax, pb.measured[ch][w])
    return finish_channel_figure(fig, axes, f"{Path(pb.rec.source).name}: effects found: {label}")


def plot_impact_zooms(diag, *, before_s: float = 0.1, after_s: float = 0.4):
    """Every channel around its own wheel's cleat impact: measured vs the four corners and the final model
    (the full-length overlays squeeze an impact into a few pixels)."""
    pb = diag.problem
    t = pb.rec.time_s
    arrivals = diag.final.model.arrivals(diag.final.params)
    n = len(pb.channels)
    cols = 2 if n > 1 else 1
    rows = (n + cols - 1) // cols
    fig, axes = figure(rows, cols, size=(11.0, 2.6 * rows + 0.6), squeeze=False)
    for ax, ch in zip(axes.flat, pb.channels):
        sel = (t >= arrivals[ch] - before_s) & (t <= arrivals[ch] + after_s)
        ax.plot(t[sel], pb.measured[ch][sel], color="C0", lw=1.2, label=f"{ch} measured")
        ax.plot(t[sel], diag.baseline.prediction[ch][sel], color="C7", lw=0.9, ls="--", label="corners")
        ax.plot(t[sel], diag.final.prediction[ch][sel], color="C3", lw=0.9, label="final")
        ax.axvline(arrivals[ch], color="k", lw=0.6, ls=":")
        peak = float(np.max(np.abs(pb.measured[ch][sel]))) if sel.any() else 1.0
        ax.set_ylim(-1.3 * peak, 1.3 * peak)
        ax.set_title(f"{ch}: its cleat at {arrivals[ch]:.3f} s (dotted)", fontsize=8)
        ax.set_xlabel("time / s")
        ax.set_ylabel("m/s²")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle(f"{Path(pb.rec.source).name}: impacts", fontsize=9)
    fig.tight_layout()
    return fig


def finish_channel_axis(ax, measured) -> None:
    """One channel's axis of a per-channel figure: units, y scaled to the measurement, grid, legend."""
    ax.set_ylabel("m/s²")
    _limit_to(ax, measured)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")


def finish_channel_figure(fig, axes, title: str):
    """A per-channel figure's title (on top) and time axis (at the bottom); returns the figure."""
    axes[0, 0].set_title(title, fontsize=9)
    axes[-1, 0].set_xlabel("time / s")
    return fig


def plot_ride(runs, *, road_class: str, speed_m_s: float, expected: dict | None = None):
    """The seat's vertical acceleration (the first road's first 10 s) and a_w (Wk) per parameter set.

    With `expected` (set name -> the ``expected`` entry of ``ride --json``) the bars are the expected a_w over
    the road realisations with the 95 % interval of that mean, a thin line spans the single-ride 95 %
    interval, and a dot marks the first road's ride; without it the bars are that ride's a_w.
    """
    fig, (ax, bx) = figure(1, 2, size=(11.0, 3.8), gridspec_kw={"width_ratios": [3, 1]})
    for i, (name, r) in enumerate(runs.items()):
        window = r.time_s < r.time_s[0] + 10.0
        ax.plot(r.time_s[window], r.seat_m_s2[window], lw=0.8, color=f"C{i}", label=name)
        e = (expected or {}).get(name)
        if e is None or e["a_w"]["mean_interval"] is None:     # one road: no interval, its ride's a_w
            bx.bar(i, r.comfort.a_w, color=f"C{i}")
            continue
        a = e["a_w"]
        lo, hi = a["mean_interval"]
        bx.bar(i, a["mean"], yerr=[[a["mean"] - lo], [hi - a["mean"]]], capsize=4, color=f"C{i}", alpha=0.8)
        bx.vlines(i + 0.25, *a["single_ride_interval"], color="k", lw=1.0)
        bx.plot(i + 0.25, r.comfort.a_w, "k.", ms=5)
    ax.set_xlabel("time / s")
    ax.set_ylabel("seat vertical acceleration / m/s²")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"ISO 8608 class {road_class} road, {speed_m_s * 3.6:.3g} km/h (the first road's first 10 s)")
    bx.set_xticks(range(len(runs)), list(runs), rotation=30, ha="right", fontsize=8)
    n = next(iter(expected.values()))["realisations"] if expected else 1
    if n > 1:
        bx.set_title(f"expected over {n} roads (95 %);\n| one ride's 95 %, · first road", fontsize=8)
    bx.set_ylabel("a_w (Wk) / m/s²")
    fig.tight_layout()
    return fig


def plot_k_c_vs_speed(points):
    """k and c against speed per tire: the final values with their 95 % intervals, the paper's and the waveform
    values, and the rig truth where known.

    Parameters
    ----------
    points : list of dict
        ``tire``, ``speed_kmh``, ``final`` ({"k", "c", "k_ci", "c_ci"}), ``paper``, ``waveform`` and ``truth``
        (dicts with ``k`` and ``c``, possibly empty).
    """
    fig, axes = figure(1, 2, size=(11.0, 3.8))
    tires = sorted({p["tire"] for p in points}, key=["FL", "FR", "RL", "RR"].index)
    for i, tire in enumerate(tires):
        pts = sorted((p for p in points if p["tire"] == tire), key=lambda p: p["speed_kmh"])
        v = np.array([p["speed_kmh"] for p in pts]) + 0.08 * (i - 1.5)      # side by side, not on top
        for ax, q, scale in ((axes[0], "k", 1e-3), (axes[1], "c", 1e-3)):
            y = np.array([p["final"][q] for p in pts]) * scale
            lo = y - np.array([p["final"][f"{q}_ci"][0] for p in pts]) * scale
            hi = np.array([p["final"][f"{q}_ci"][1] for p in pts]) * scale - y
            ax.errorbar(v, y, yerr=[lo, hi], fmt="o-", color=f"C{i}", ms=4, capsize=3,
                        label=f"{tire} final" if q == "k" else None)
            for src, marker in (("paper", "x"), ("waveform", "+"), ("truth", "s")):
                vals = [(vv, p[src][q] * scale) for vv, p in zip(v, pts) if p[src].get(q) is not None]
                if vals:
                    ax.plot(*zip(*vals), marker, color=f"C{i}", ms=6, mfc="none",
                            label=(src if i == 0 and q == "k" else None))
    axes[0].set_ylabel("k / kN·m⁻¹")
    axes[1].set_ylabel("c / kN·s·m⁻¹")
    for ax in axes:
        ax.set_xlabel("speed / km·h⁻¹")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def plot_static(result):
    """Force against deformation with the fitted line, and the local slope along the loading branch.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (Agg backend); write it with :func:`identification.report.plots.save_png`.
    """
    fig, (ax, ax2) = figure(1, 2, size=(11.0, 4.2))
    load = np.zeros(result.deformation_m.size, dtype=bool)
    load[result.first:result.stop] = True
    d_mm, f_kn = result.deformation_m * 1e3, result.force_N / 1e3
    if (~load).any():
        ax.plot(d_mm[~load], f_kn[~load], ".", color="0.6", ms=4, label="not fitted (unloading, later cycles)")
    ax.plot(d_mm[load], f_kn[load], ".", color="C0", ms=5, label="loading branch")
    x = np.array([result.deformation_m[load].min(), result.deformation_m[load].max()])
    lo, hi = result.k_ci95_N_per_m
    ax.plot(x * 1e3, (result.k_N_per_m * x + result.intercept_N) / 1e3, "-", color="C3", lw=1.5,
            label=f"fit: k = {result.k_N_per_m / 1e3:.2f} kN/m (95 %: {lo / 1e3:.2f} .. {hi / 1e3:.2f}), "
                  f"R² {result.r2:.4f}")
    ax.set_xlabel("deformation / mm")
    ax.set_ylabel("compression force / kN")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(alpha=0.3)
    ax2.errorbar(result.local_deformation_m * 1e3, result.local_slope_N_per_m / 1e3,
                 yerr=1.96 * result.local_se_N_per_m / 1e3, fmt="o", color="C0", capsize=3,
                 label="local slope dF/dD (±1.96 s.e.)")
    ax2.axhline(result.k_N_per_m / 1e3, color="C3", lw=1.2, label="k_static")
    ax2.set_xlabel("deformation / mm")
    ax2.set_ylabel("dF/dD / (kN/m)")
    ax2.legend(loc="best", fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(f"{Path(result.source).name}: static stiffness from the compression test (eq. 18)")
    fig.tight_layout()
    return fig


def plot_third_octave(bands: dict, *, title: str = ""):
    """One-third-octave band RMS (dB re 1e-6 m/s²) of weighted accelerations, one bar series per column
    (`bands`: name -> :class:`~identification.comfort.spectra.ThirdOctave` or None)."""
    fig, ax = figure(1, 1, size=(10.0, 4.0))
    shown = {name: b for name, b in bands.items() if b is not None}
    width = 0.8 / max(1, len(shown))
    for i, (name, b) in enumerate(shown.items()):
        x = np.arange(b.centre_hz.size) + (i - (len(shown) - 1) / 2) * width
        ax.bar(x, b.level_db, width=width, color=f"C{i}", label=name)
    if shown:
        first = next(iter(shown.values()))
        ax.set_xticks(range(first.centre_hz.size), first.labels, rotation=90, fontsize=7)
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel("one-third-octave band centre / Hz")
    ax.set_ylabel("weighted acceleration / dB re 1e-6 m/s²")
    ax.set_title(title or "one-third-octave bands")
    fig.tight_layout()
    return fig
