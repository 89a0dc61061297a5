"""The report's ride: the diagnosed tractor on ISO 8608 roads, expected ratings per parameter set.

:func:`report_ride` runs it for a recording (in the worker), :func:`ride_section` renders it.
"""

from __future__ import annotations

import html
from pathlib import Path

from ..errors import InputError

__all__ = ["static_source", "report_ride", "ride_section"]


def static_source(path) -> dict:
    """The static stiffness of a compression test for the report's ride (``report --static``): the file's
    name, its eq. 18 k with the 95 % interval and R² (:func:`identification.identify.static.static_stiffness_file`;
    InputError for a file that is not one)."""
    from ..identify.static import static_stiffness_file

    result = static_stiffness_file(path)
    return {"file": Path(path).name, "path": str(path), "k_N_per_m": result.k_N_per_m,
            "k_ci95_N_per_m": list(result.k_ci95_N_per_m), "r2": result.r2,
            "local_slope_range": result.local_slope_range}


def report_ride(rep, rec, diag, static: dict | None) -> None:
    """The diagnosed tractor on the report's roads with the paper's, the final and (with a compression test)
    a static parameter set: expected values over REPORT_RIDE's realisations, into ``rep.ride`` and
    ``rep.figures["ride"]`` (a failure into ``rep.errors``)."""
    from ..comfort.ride import REPORT_RIDE, ride_comparison
    from .plots import plot_ride, png_bytes

    names = list(REPORT_RIDE["names"])
    static_name = None if static is None else f"static={static['k_N_per_m']!r}"
    if static_name is not None:
        names.append(static_name)
    try:
        runs, rep.ride = ride_comparison(rec, names, road_class=REPORT_RIDE["road_class"],
                                         seed=REPORT_RIDE["seed"], duration_s=REPORT_RIDE["duration_s"],
                                         realisations=REPORT_RIDE["realisations"], tires=REPORT_RIDE["tires"],
                                         diagnosis=diag)
    except (InputError, ValueError) as exc:
        rep.errors.append(f"ride: {getattr(exc, 'problem', exc)}")
        return
    if static_name is not None:           # the set is named for its source, not for a long number
        runs = {("static" if n == static_name else n): r for n, r in runs.items()}
        rep.ride["sets"] = {("static" if n == static_name else n): v for n, v in rep.ride["sets"].items()}
        rep.ride["static"] = {k: v for k, v in static.items() if k != "path"}
    rep.figures["ride"] = png_bytes(plot_ride(runs, road_class=REPORT_RIDE["road_class"],
                                              speed_m_s=rep.ride["speed_m_s"],
                                              expected={n: v["expected"] for n, v in rep.ride["sets"].items()}))


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _versus_final(d: dict) -> str:
    """' Expected a_w against the final set's, paired on the same roads: paper +2.8 % (+2.1 … +3.5 %), ...'
    (empty without a final set or with one road)."""
    sets = d["sets"]
    parts = []
    for name, r in sets.items():
        ratio = r["expected"].get("a_w_ratio_to_final")
        if name == "final" or ratio is None or ratio["mean_interval"] is None:
            continue
        lo, hi = ratio["mean_interval"]
        parts.append(f'{_e(name)} {100 * (ratio["mean"] - 1):+.1f} % ({100 * (lo - 1):+.1f} … '
                     f'{100 * (hi - 1):+.1f} %)')
    if not parts:
        return ""
    return (" Expected a_w against the final set's, paired on the same roads (the ratio's mean and its 95 % "
            "interval; the road-to-road scatter cancels): " + ", ".join(parts) + ".")


def _interval(e: dict, key: str) -> str:
    lo, hi = e[key]
    return f"{lo:.3f}–{hi:.3f}"


def _static_note(d: dict) -> str:
    s = d.get("static")
    if s is None:
        return (" No static set: no compression test was given (<code>cleatfmu report --static "
                "COMPRESSION.csv</code>).")
    lo, hi = s["k_ci95_N_per_m"]
    return (f' The <code>static</code> set is the compression test <code>{_e(s["file"])}</code>: k_static '
            f'{s["k_N_per_m"] / 1e3:.1f} kN/m (95 % {lo / 1e3:.1f}–{hi / 1e3:.1f}, R² {s["r2"]:.4f}; eq. 18) on all '
            'four tires, with the final set\'s c.')


def _contact_note(d: dict) -> str:
    warnings = [f'{_e(n)}: {_e(v["expected"]["contact"]["warning"])}' for n, v in d["sets"].items()
                if v["expected"]["contact"]["warning"]]
    lifted = [n for n, v in d["sets"].items() if v["expected"]["contact"]["lift_off_rides"]]
    if warnings:
        return '<p class="bad">' + "; ".join(warnings) + "</p>"
    if lifted:
        return (f'<p class="note">Tires pulled on some roads with {_e(", ".join(lifted))}: those rides were rated '
                'with the lift-off law.</p>')
    return ""


def ride_section(d: dict, image_html: str = "") -> str:
    """The diagnosed tractor on ISO 8608 roads with each parameter set: expected ISO 2631-1 ratings.

    Parameters
    ----------
    d : dict
        A recording's ride (``ride --json``'s document, with ``static`` when a compression test was given).
    image_html : str
        The ride figure's ``<img>``, placed under the table.
    """
    road = d["road"]
    rows = []
    for name, r in d["sets"].items():
        e = r["expected"]
        rows.append(f'<tr><td class="l">{_e(name)}</td><td>{"/".join(f"{v / 1e3:.0f}" for v in r["k"].values())}'
                    f'</td><td>{e["a_w"]["mean"]:.3f}</td><td>{_interval(e["a_w"], "mean_interval")}</td>'
                    f'<td>{_interval(e["a_w"], "single_ride_interval")}</td><td>{e["psd"]["a_w"]:.3f}</td>'
                    f'<td>{e["vdv"]["mean"]:.2f}</td><td>{e["mtvv"]["mean"]:.3f}</td>'
                    f'<td>{e["vector_sum_health"]["mean"]:.3f}</td></tr>')
    return (f'<h4>Ride comfort: the tractor on ISO 8608 class {_e(road["class"])} roads</h4>'
            f'<p>The {_e(d["body"]["source"])} at {d["speed_m_s"] * 3.6:.3g} km/h for {d["duration_s"]:g} s on '
            f'{road["realisations"]} realisations of the road (seeds from {road["seed"]}), once per tire parameter '
            f'set, tires {_e(d["tires"])} (the lift-off law where the linear one pulls). The "seat" is the point '
            f'of the body {d["seat"]["x_m"]:.2f} m behind the front axle and {d["seat"]["height_m"]:.2f} m above '
            'the axles, rated by ISO 2631-1: floor values, without seat suspension or cushion. Each rating is the '
            'expected value over the roads with the 95 % interval of that mean; one ride on one road scatters '
            'over the single-ride interval. The PSD column is the a_w the road spectrum gives through the '
            f'linear model\'s frequency response (a check of the mean).{_versus_final(d)}{_static_note(d)}</p>'
            + _contact_note(d) +
            '<table><tr><th class="l">set</th><th>k FL/FR/RL/RR, kN/m</th><th>a_w (Wk), m/s²</th>'
            '<th>95 % of the mean</th><th>one ride, 95 %</th><th>a_w from the PSD</th><th>VDV, m/s^1.75</th>'
            f'<th>MTVV, m/s²</th><th>vector sum x, y, z (health), m/s²</th></tr>{"".join(rows)}</table>'
            + image_html)


