"""The tire map of one or more reports: the runs of their ``summary.json`` fitted over speed.

Each recording of a report contributes, per tire, one run: the recording's speed, wheel load and inflation
pressure from its sidecar (``conditions`` in ``summary.json``) and the tire's recommended k and c with their
95 % intervals (the whole-tractor diagnosis's).  :func:`identification.identify.tire_map.fit_map` fits them
over speed.  A recording whose diagnosis failed gives no run.
"""

from __future__ import annotations

import math
from pathlib import Path

from .._inputs import read_json_file
from ..errors import InputError
from ..identify.tire_map import PRESSURE_TOLERANCE, fit_map

__all__ = ["VALUES", "run_conditions", "summary_path", "runs_of_summary", "map_of_reports"]

#: What the runs' k and c are.
VALUES = ("the recommended k and c of each recording's whole-tractor diagnosis (summary.json: "
          "recordings[].tires[].recommended) with their 95 % intervals; speed, wheel load and inflation pressure "
          "from the recording's sidecar")


def run_conditions(rec) -> dict:
    """What a recording was tested at (SI units, from its sidecar): speed, wheel loads and inflation pressures
    (None where the sidecar declares none) - ``conditions`` of its entry in ``summary.json``."""
    return {"speed_m_s": rec.speed_m_s, "wheel_load_N": dict(rec.wheel_load_N),
            "inflation_pressure_Pa": None if rec.inflation_pressure_Pa is None else dict(rec.inflation_pressure_Pa)}


def summary_path(item) -> Path:
    """The ``summary.json`` of a report folder, or the file itself."""
    path = Path(item)
    if path.is_dir():
        path = path / "summary.json"
    if not path.is_file():
        raise InputError(item, "no report here: give a report folder (with summary.json) or its summary.json")
    return path


def _finite(x) -> bool:
    """A finite number (no bool; an integer beyond the float range is none)."""
    try:
        return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
    except OverflowError:
        return False


def _interval(value) -> bool:
    return isinstance(value, (list, tuple)) and len(value) == 2 and all(_finite(x) for x in value)


def runs_of_summary(path, *, pressure_kpa: float | None = None) -> list[dict]:
    """The runs (one per recording and tire with a recommended k, c) of a report's ``summary.json``.

    Parameters
    ----------
    path : path-like
        The ``summary.json``.
    pressure_kpa : float, optional
        Keep only the runs at this inflation pressure (within 5 %; runs without one are dropped).

    Raises
    ------
    InputError
        Not a report summary, or one without the runs' conditions (written before they were recorded).
    """
    doc = read_json_file(path)
    if not isinstance(doc, dict) or doc.get("format") != "cleatfmu-report-summary/1" \
            or not isinstance(doc.get("recordings"), list):
        raise InputError(path, "not a cleatfmu report summary (cleatfmu-report-summary/1)")
    runs = []
    for rec in doc["recordings"]:
        if not isinstance(rec, dict) or not rec.get("ok"):
            continue
        conditions = rec.get("conditions")
        if not isinstance(conditions, dict):
            raise InputError(path, f"recording {rec.get('name')!r} has no run conditions (speed, wheel loads): "
                                   f"the report was written by an older cleatfmu; run it again")
        pressures = conditions.get("inflation_pressure_Pa") or {}
        for tire, entry in (rec.get("tires") or {}).items():
            best = entry.get("recommended") if isinstance(entry, dict) else None
            if not best:
                continue
            run = {"recording": rec.get("name"), "report": str(path), "tire": tire,
                   "speed_m_s": conditions.get("speed_m_s"), "k": best.get("k"), "k_ci": best.get("k_ci"),
                   "c": best.get("c"), "c_ci": best.get("c_ci"),
                   "wheel_load_N": (conditions.get("wheel_load_N") or {}).get(tire),
                   "inflation_pressure_Pa": pressures.get(tire), "conditional": bool(best.get("conditional"))}
            numbers = [run[key] for key in ("speed_m_s", "k", "c", "wheel_load_N")]
            if not all(_finite(x) and x >= 0 for x in numbers) \
                    or not (_interval(run["k_ci"]) and _interval(run["c_ci"])):
                raise InputError(path, f"recording {run['recording']!r} tire {tire}: speed, k, c with intervals "
                                       f"and wheel load must be finite numbers")
            if pressure_kpa is not None and (run["inflation_pressure_Pa"] is None or
                                             abs(run["inflation_pressure_Pa"] / 1e3 / pressure_kpa - 1)
                                             > PRESSURE_TOLERANCE):
                continue
            runs.append(run)
    return runs


def map_of_reports(items, *, tires=None, pressure_kpa: float | None = None) -> dict:
    """The tire map document of the reports `items` (folders or ``summary.json`` files).

    Parameters
    ----------
    items : iterable of path-like
        Reports.
    tires : iterable of str, optional
        Map only these tires (default: every tire with runs).
    pressure_kpa : float, optional
        Map only the runs at this inflation pressure (see :func:`runs_of_summary`).

    Returns
    -------
    dict
        :func:`identification.identify.tire_map.fit_map`'s document, ``sources`` the summaries read.
    """
    paths = [summary_path(item) for item in items]
    runs = [run for path in paths for run in runs_of_summary(path, pressure_kpa=pressure_kpa)]
    if tires is not None:
        tires = set(tires)
        runs = [r for r in runs if r["tire"] in tires]
    source = str(paths[0]) if len(paths) == 1 else f"{len(paths)} reports"
    if not runs:
        which = f" at {pressure_kpa:g} kPa" if pressure_kpa is not None else ""
        raise InputError(source, f"no run with recommended k and c{which}: nothing to map")
    doc = fit_map(runs, source=source, values=VALUES)
    doc["sources"] = [str(p) for p in paths]
    return doc
