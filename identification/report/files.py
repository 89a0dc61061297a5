"""Which file of a report folder is which: the recommended tire files under the plainest names, the rest
in folders that say what they are.

A report folder holds, per recording ``<rec>`` and tire ``<T>``:

* ``fmu/<rec>_<T>.fmu`` - the recommended tire: the whole-tractor diagnosis' extended tire (its k and c
  are the verdict's; its built-in test cleat off);
* ``fmu/point_contact/<rec>_<T>.fmu`` - a plain spring ∥ damper (point contact) of the same recommended
  k and c, for an importer without the extended tire's inputs;
* ``params/<rec>.json`` - the recommended k and c of the recording's tires with their 95 % intervals, an
  ``identify --json`` document (for ``cleatfmu export`` and ``ride --compare params=FILE``);
* ``fmu/not_recommended/<method>/<rec>_<T>.fmu`` and ``params/not_recommended/<method>/<rec>_<T>.json`` -
  the one-corner fit alone (``waveform``, or ``paper`` where the waveform fit failed), shown for
  comparison and not to be used.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

from .._files import TEMP_SUFFIXES, atomic_write_texts, json_text, publish_files, temp_prefix

__all__ = ["POINT_CONTACT", "NOT_RECOMMENDED", "FOLDERS", "recommended_fmu", "point_contact_fmu",
           "recommended_params", "not_recommended_fmu", "not_recommended_params", "write_recommended_files",
           "file_counts", "remove_staging", "FIGURES_STAGING", "REPORT_ENTRIES", "replace_refusal"]

#: Subfolder (of ``fmu/``) of the plain spring-damper FMUs of the recommended k and c.
POINT_CONTACT = "point_contact"
#: Subfolder (of ``fmu/`` and ``params/``) of the files that are not recommended.
NOT_RECOMMENDED = "not_recommended"
#: The folders a report run creates (relative to the report folder), outermost first.
FOLDERS = ("fmu", f"fmu/{POINT_CONTACT}", f"fmu/{NOT_RECOMMENDED}", f"fmu/{NOT_RECOMMENDED}/waveform",
           "params", f"params/{NOT_RECOMMENDED}", f"params/{NOT_RECOMMENDED}/waveform")
_STANDARD_GRAVITY = 9.80665


def recommended_fmu(stem: str, tire: str) -> str:
    """``fmu/<stem>_<tire>.fmu``: the recommended (extended) tire FMU, relative to the report folder."""
    return f"fmu/{stem}_{tire}.fmu"


def point_contact_fmu(stem: str, tire: str) -> str:
    """``fmu/point_contact/<stem>_<tire>.fmu``: the plain spring-damper FMU of the recommended k and c."""
    return f"fmu/{POINT_CONTACT}/{stem}_{tire}.fmu"


def recommended_params(stem: str) -> str:
    """``params/<stem>.json``: the recommended k and c of every tire of a recording."""
    return f"params/{stem}.json"


def not_recommended_fmu(stem: str, tire: str, method: str) -> str:
    """``fmu/not_recommended/<method>/<stem>_<tire>.fmu``: the one-corner fit's point-contact FMU."""
    return f"fmu/{NOT_RECOMMENDED}/{method}/{stem}_{tire}.fmu"


def not_recommended_params(stem: str, tire: str, method: str) -> str:
    """``params/not_recommended/<method>/<stem>_<tire>.json``: the one-corner fit's ``identify`` entry."""
    return f"params/{NOT_RECOMMENDED}/{method}/{stem}_{tire}.json"


def _params_document(rec, stem: str, diagnosis: dict) -> dict:
    """The recommended k, c of every diagnosed tire as an ``identify --json`` document."""
    tires = {}
    for tire, t in diagnosis["tires"].items():
        mass = rec.wheel_load_N[tire] / _STANDARD_GRAVITY
        tires[tire] = {"k": t["k"], "c": t["c"], "k_ci": list(t["k_ci"]), "c_ci": list(t["c_ci"]),
                       "mass": mass, "method": "joint diagnosis",
                       "effects": list(diagnosis["effects"]), "nrmse": t["nrmse_after"],
                       "noise_nrmse": t["noise_nrmse"],
                       "extended_fmu": Path(recommended_fmu(stem, tire)).name,
                       "note": "recommended k and c: the whole-tractor diagnosis' (the extended FMU carries them "
                               "with the effects named)"}
    return {"recording": Path(rec.source).name, "speed_kmh": rec.speed_kmh, "method": "joint diagnosis",
            "tires": tires}


def write_recommended_files(rec, stem: str, diagnosis: dict, out_dir) -> list[dict]:
    """Write ``params/<stem>.json`` and the point-contact FMUs of the recommended k and c (as one set).

    Parameters
    ----------
    rec : Recording
        The diagnosed recording (its name, speed and wheel loads).
    stem : str
        The recording's name in the report.
    diagnosis : dict
        The ``diagnose --json`` document of the recording.
    out_dir : path-like
        The report folder (``fmu/point_contact/`` and ``params/`` exist).

    Returns
    -------
    list of dict
        One entry per FMU written: ``file`` (relative to the report folder), ``kind``, ``role``,
        ``recommended``.
    """
    from ..fmu.export import export_fmu

    out = Path(out_dir)
    params = out / recommended_params(stem)
    atomic_write_texts({params: json_text(_params_document(rec, stem, diagnosis)) + "\n"})
    entries, built = [], {}
    with tempfile.TemporaryDirectory(prefix=temp_prefix("pointcontact")) as tmp:
        for tire in diagnosis["tires"]:
            staged = Path(tmp) / f"{stem}_{tire}.fmu"
            export_fmu(params, staged, tire=tire, backend="native")
            built[out / point_contact_fmu(stem, tire)] = staged
            entries.append({"file": point_contact_fmu(stem, tire), "kind": "point_contact", "recommended": True,
                            "role": "plain spring ∥ damper (point contact) of the recommended k and c, for an "
                                    "importer without the extended tire's inputs (no footprint, lift-off or "
                                    "cleat enveloping)"})
        publish_files(built)
    return entries


def file_counts(out_dir) -> dict:
    """How many FMUs and parameter files each part of a report folder holds (for the closing lines)."""
    out = Path(out_dir)

    def count(folder: Path, pattern: str) -> int:
        return sum(1 for p in folder.glob(pattern) if p.is_file()) if folder.is_dir() else 0

    return {"fmu": count(out / "fmu", "*.fmu"), "point_contact": count(out / "fmu" / POINT_CONTACT, "*.fmu"),
            "fmu_not_recommended": count(out / "fmu" / NOT_RECOMMENDED, "*/*.fmu"),
            "params": count(out / "params", "*.json"),
            "params_not_recommended": count(out / "params" / NOT_RECOMMENDED, "*/*.json"),
            "campaign": count(out / "fmu" / "campaign", "*.fmu")}


def remove_staging(out_dir) -> list[Path]:
    """Remove the staging files a killed run left in a report folder (``.NAME.*.tmp`` of the atomic writes,
    ``.NAME.*.part`` of the FMU builds, ``.NAME.*.previous`` backups, the figures' staging folder); return
    them."""
    removed = []
    staging = Path(out_dir) / FIGURES_STAGING
    if staging.is_dir():
        import shutil
        removed.append(staging)
        shutil.rmtree(staging, ignore_errors=True)
    for sub in ("", "tables", *FOLDERS, "fmu/not_recommended/paper", "params/not_recommended/paper"):
        folder = Path(out_dir) / sub
        if not folder.is_dir():
            continue
        for path in folder.iterdir():
            if path.name.startswith(".") and path.name.endswith(TEMP_SUFFIXES) and path.is_file():
                path.unlink(missing_ok=True)
                removed.append(path)
    return removed


#: Staging folder of the figures while a batch runs (each result's figures go to disk as it arrives).
FIGURES_STAGING = ".figures-staging"

#: What a report folder holds at its top.
REPORT_ENTRIES = ("report.html", "summary.json", "tables", "fmu", "params", "figures", FIGURES_STAGING)
_SUMMARY_MARK = b'"format": "cleatfmu-report-summary/'


def replace_refusal(folder) -> str | None:
    """Whether an existing folder may be replaced whole by a new report (the run swaps its new set in).

    Parameters
    ----------
    folder : path-like
        The existing output folder.

    Returns
    -------
    str or None
        None when it is empty, holds a report (its ``summary.json``), or holds only what a report writes
        (an older run's leftovers); else why not, in one line naming an entry a report does not write (it
        would be lost).
    """
    folder = Path(folder)
    try:
        with (folder / "summary.json").open("rb") as fh:
            if _SUMMARY_MARK in fh.read(256):
                return None
    except OSError:
        pass
    for entry in sorted(folder.iterdir()):
        name = entry.name
        if name in REPORT_ENTRIES or (name.startswith(".") and name.endswith(TEMP_SUFFIXES)):
            continue
        return (f"is not a report folder ({name} is not a file a report writes, and a report replaces the "
                f"whole folder): give a new or empty folder")
    return None


def bias(value: float, reference: float) -> float:
    """value / reference − 1 (NaN without a reference)."""
    return value / reference - 1.0 if reference else math.nan
