"""The pooled answer of a campaign as files: per condition of repeated runs, a parameter file and a tire FMU.

Where a report holds two or more runs of one tire under one condition (:mod:`identification.report.campaign`),
its one answer per tire and condition is the random-effects mean of the runs' recommended k and c, with an
interval that holds the between-run scatter.  This module writes that answer where a simulator takes it:

* ``params/campaign/<name>.json`` - an ``identify --json`` document of the tire with the pooled k and c,
  their pooled 95 % intervals, the runs and where the interval comes from
  (``cleatfmu export`` and ``ride --compare params=FILE`` read it);
* ``fmu/campaign/<name>.fmu`` - a point-contact (spring ∥ damper) tire FMU of those k and c (native backend).

``<name>`` is ``<TIRE>_<speed>kmh`` with the condition's inflation pressure (``_<p>kPa``) and its names
(vehicle, tire) where the sidecars give them.  The pooled values come from runs whose effects may differ, so
the FMU is the plain point-contact tire: the extended tire of one run carries that run's effects.  A
condition of one run has no pooled answer (its run's files are the answer) and gets no file here.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from .._files import atomic_write_texts, json_text, make_folders, publish_files, temp_prefix

__all__ = ["CAMPAIGN", "pooled_name", "write_pooled_files", "write_campaign"]

#: Subfolder (of ``fmu/`` and ``params/``) of the pooled files.
CAMPAIGN = "campaign"
_STANDARD_GRAVITY = 9.80665


def _slug(text) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]+", "-", str(text)).strip("-")[:40]


def pooled_name(row: dict) -> str:
    """The file stem of a campaign condition (:func:`identification.report.campaign.campaign_conditions`'
    row): ``<TIRE>_<speed>kmh[_<p>kPa][_<vehicle>][_<tire name>]``."""
    parts = [row["tire"], f"{row['speed_m_s'] * 3.6:.3g}kmh"]
    if row.get("inflation_pressure_Pa") is not None:
        parts.append(f"{row['inflation_pressure_Pa'] / 1e3:.3g}kPa")
    parts += [_slug(v) for v in row["names"].values() if _slug(v)]
    return "_".join(parts)


def _params_document(row: dict) -> dict:
    k, c = row["k"], row["c"]
    load = row["wheel_load_N"]
    entry = {"k": k["value"], "c": c["value"], "k_ci": list(k["ci"]), "c_ci": list(c["ci"]),
             "method": "campaign pooled", "runs": row["runs"], "recordings": list(row["recordings"]),
             "interval_source": row["interval_source"], "runs_disagree": row["runs_disagree"],
             "k_between_run_sd": k["between_run_sd"], "c_between_run_sd": c["between_run_sd"],
             "note": row["note"]}
    if load is not None:
        entry["mass"] = load / _STANDARD_GRAVITY
    return {"recording": "campaign: " + " ".join(row["recordings"]), "speed_kmh": row["speed_m_s"] * 3.6,
            "method": "campaign pooled", "tires": {row["tire"]: entry}}


def write_pooled_files(conditions: list, out_dir) -> list:
    """Write the parameter file and the tire FMU of every condition of two or more runs (as one set).

    Parameters
    ----------
    conditions : list of dict
        :func:`identification.report.campaign.campaign_conditions`' rows.
    out_dir : path-like
        The report folder.

    Returns
    -------
    list of dict
        The rows, each with ``files``: ``{"params": ..., "fmu": ...}`` (paths relative to the report
        folder) for a condition of two or more runs, else None.
    """
    from ..fmu.export import export_fmu

    rows = [dict(row, files=None) for row in conditions]
    pooled = [row for row in rows if row["runs"] >= 2]
    if not pooled:
        return rows
    out = Path(out_dir)
    for sub in ("params", "fmu"):
        make_folders(out / sub / CAMPAIGN)
    names, params = {}, {}
    for row in pooled:
        name = pooled_name(row)
        while name in names:       # two conditions alike but for what the name leaves out
            name += "_"
        names[name] = row
        params[out / "params" / CAMPAIGN / f"{name}.json"] = json_text(_params_document(row)) + "\n"
    atomic_write_texts(params)
    built = {}
    with tempfile.TemporaryDirectory(prefix=temp_prefix("campaign")) as tmp:
        for name, row in names.items():
            staged = Path(tmp) / f"{name}.fmu"
            export_fmu(out / "params" / CAMPAIGN / f"{name}.json", staged, tire=row["tire"], backend="native")
            built[out / "fmu" / CAMPAIGN / f"{name}.fmu"] = staged
        publish_files(built)
    for name, row in names.items():
        row["files"] = {"params": f"params/{CAMPAIGN}/{name}.json", "fmu": f"fmu/{CAMPAIGN}/{name}.fmu"}
    return rows


def write_campaign(result) -> None:
    """A batch's campaign conditions with their pooled files into ``result.campaign`` (written into
    ``result.out_dir``); a condition whose files cannot be built is named in ``result.errors``."""
    from ..errors import InputError
    from .campaign import batch_runs, campaign_conditions

    conditions = campaign_conditions(batch_runs(result))
    try:
        result.campaign = write_pooled_files(conditions, result.out_dir)
    except InputError as exc:
        result.errors.append(f"campaign: pooled files: {exc.problem}")
        result.campaign = [dict(row, files=None) for row in conditions]
