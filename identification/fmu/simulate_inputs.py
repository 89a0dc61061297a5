"""The inputs of ``cleatfmu simulate`` for the whole tractor: the four tire FMUs and the body document.

:func:`tractor_fmu_paths` matches the FMU files to the tires;
:func:`read_body_document` reads a ``cleatfmu diagnose --json`` whole-tractor
document (or a report's ``summary.json``, whose recording :func:`diagnosis_of` picks) and
:func:`body_settings` takes from it (validated) the body, the
effects and each tire's cleat arrival, for
:func:`identification.fmu.tractor_cosim.simulate_tractor`.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from ..recording import TIRES

__all__ = ["tractor_fmu_paths", "read_body_document", "diagnosis_of", "body_settings"]


def _tire_suffix(path: Path):
    """The tire a file name ends with (``*_FL.fmu``), or None."""
    name = path.name
    return next((t for t in TIRES if name.endswith(f"_{t}.fmu")), None)


def tractor_fmu_paths(paths, *, recording: str | None = None) -> dict:
    """The FMU of each tire, {FL, FR, RL, RR: Path}, from one directory or four paths.

    A directory must hold exactly one ``*_FL.fmu``, ``*_FR.fmu``, ``*_RL.fmu``
    and ``*_RR.fmu`` (as ``cleatfmu diagnose --fmu-dir`` writes them), or,
    when it holds those of several recordings (a report's ``fmu/``), the
    ``<recording>_FL.fmu`` .. ``<recording>_RR.fmu`` of the `recording` named
    (the recording's file name without ``.csv``).  Four paths are matched by
    the same suffixes when each tire's is there once, else taken in FL, FR,
    RL, RR order (a path whose suffix names another tire than its place is
    refused).
    """
    paths = [Path(p) for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
    if len(paths) == 1 and paths[0].is_dir():
        folder = paths[0]
        found = {t: sorted(p.name for p in folder.glob(f"*_{t}.fmu") if p.is_file()) for t in TIRES}
        if any(len(found[t]) > 1 for t in TIRES):
            own = {t: f"{recording}_{t}.fmu" for t in TIRES} if recording else {}
            if own and all(own[t] in found[t] for t in TIRES):
                return {t: folder / own[t] for t in TIRES}
            stems = sorted({name[:-len(f"_{t}.fmu")] for t in TIRES for name in found[t]})
            if all(any(f"{s}_{t}.fmu" in found[t] for s in stems) for t in TIRES) and len(stems) > 1:
                which = f"none is {recording!r}" if recording else "name the recording"
                raise InputError(folder, f"holds the tire FMUs of {len(stems)} recordings ({', '.join(stems)}): "
                                         f"{which}; give the recording of one of them (REC.csv or --example), "
                                         f"or its four FMUs")
        missing = [f"*_{t}.fmu" for t in TIRES if not found[t]]
        several = [f"{len(found[t])} *_{t}.fmu ({', '.join(found[t])})" for t in TIRES if len(found[t]) > 1]
        if missing or several:
            problems = ([f"no {', '.join(missing)}"] if missing else []) + \
                       ([f"several: {'; '.join(several)}"] if several else [])
            raise InputError(folder, "needs exactly one *_FL.fmu, *_FR.fmu, *_RL.fmu and *_RR.fmu: "
                             + "; ".join(problems))
        return {t: folder / found[t][0] for t in TIRES}
    if len(paths) != len(TIRES):
        raise InputError(paths[0], f"give one tire FMU, four (FL FR RL RR) or one directory holding them, "
                               f"got {len(paths)} path(s)")
    tags = [_tire_suffix(p) for p in paths]
    if sorted(t for t in tags if t) == sorted(TIRES):
        return {t: p for t, p in zip(tags, paths)}
    for tire, tag, p in zip(TIRES, tags, paths):
        if tag is not None and tag != tire:
            raise InputError(p, f"named for {tag} but given in the place of {tire}: give each tire's FMU once, "
                                f"named *_FL.fmu .. *_RR.fmu, or the four in FL, FR, RL, RR order")
    return dict(zip(TIRES, paths))


def _key(doc, keys: str, source):
    """doc[k1][k2]... or InputError naming the missing key."""
    node = doc
    for i, k in enumerate(keys.split(".")):
        if not isinstance(node, dict) or k not in node:
            raise InputError(source, f"not a 'cleatfmu diagnose --json' whole-tractor document: missing key "
                                     f"{'.'.join(keys.split('.')[:i + 1])}")
        node = node[k]
    return node


def _number(value, keys: str, source) -> float:
    try:
        finite = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
    except OverflowError:                # an integer beyond the float range
        raise InputError(source, f"{keys} must be a finite number, got an integer of {len(str(value))} digits") \
            from None
    if not finite:
        raise InputError(source, f"{keys} must be a finite number, got {value!r}")
    return float(value)


def read_body_document(source) -> dict:
    """Read a ``diagnose --json`` document (path) as a dict; InputError naming the file when unreadable."""
    from .._inputs import read_json_file

    doc = read_json_file(source)
    if not isinstance(doc, dict):
        raise InputError(source, "not a 'cleatfmu diagnose --json' whole-tractor document (not a JSON object)")
    return doc


def diagnosis_of(doc: dict, source, recording=None) -> dict:
    """The whole-tractor document of `recording` in `doc`: `doc` itself (a ``diagnose --json`` document),
    or, from a report's ``summary.json``, the diagnosis of the recording of the same name.

    Parameters
    ----------
    doc : dict
        A ``cleatfmu diagnose --json`` document or a report's ``summary.json``.
    source : str
        The document's name in messages.
    recording : path-like, optional
        The recording simulated (its file name without ``.csv`` picks the summary's entry).

    Raises
    ------
    InputError
        A summary without a diagnosed recording, or of several none of which is `recording` (one line
        naming them).
    """
    if not isinstance(doc.get("recordings"), list):
        return doc
    entries = [r for r in doc["recordings"] if isinstance(r, dict) and isinstance(r.get("diagnosis"), dict)]
    names = [_stem(r.get("source")) for r in entries]
    if not entries:
        raise InputError(source, "a report summary without a diagnosed recording: no body to take")
    want = _stem(recording) if recording is not None else None
    match = [e for e, n in zip(entries, names) if n == want]
    if len(match) == 1 or len(entries) == 1:
        return (match or entries)[0]["diagnosis"]
    raise InputError(source, f"a report summary of {len(entries)} diagnosed recordings ({', '.join(names)}), "
                             f"none of them {want!r}: give the recording of one of them (REC.csv or --example)")


def _stem(path) -> str:
    """A recording's name: its file name without ``.csv`` (either path style)."""
    from pathlib import PureWindowsPath

    name = PureWindowsPath(str(path)).name
    return name[:-4] if name.lower().endswith(".csv") else name


def body_settings(doc: dict, source) -> dict:
    """The body, effects and arrivals of a ``diagnose --json`` document (validated)."""
    from ..model.fitting import BODY_EFFECTS, EFFECTS, TIRE_EFFECTS

    body = _key(doc, "body", source)
    indices = {}
    for name in ("pitch_index", "roll_index"):
        entry = _key(doc, f"body.{name}", source)
        if entry is not None:
            indices[name] = _number(_key(doc, f"body.{name}.value", source), f"body.{name}.value", source)
    front = _key(doc, "body.front_axle", source)
    if front not in ("rigid", "pivot"):
        raise InputError(source, f"body.front_axle must be 'rigid' or 'pivot', got {front!r}")
    if front == "pivot":
        entry = _key(doc, "body.pivot_index", source)
        if entry is None:
            raise InputError(source, "body.pivot_index is null but body.front_axle is 'pivot'")
        indices["pivot_index"] = _number(_key(doc, "body.pivot_index.value", source), "body.pivot_index.value",
                                         source)
    elif isinstance(body, dict) and body.get("pivot_index") is not None:
        raise InputError(source, "body.pivot_index is given but body.front_axle is 'rigid'")
    effects = _key(doc, "effects", source)
    if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
        raise InputError(source, "effects must be a list of effect names")
    unknown = [e for e in effects if e not in EFFECTS]
    if unknown:
        raise InputError(source, f"unknown effect(s) {', '.join(unknown)} (known: {', '.join(EFFECTS)})")
    implied = {"axle_coupling": "pitch_index" in indices, "roll_coupling": "roll_index" in indices,
               "front_axle_pivot": front == "pivot"}
    absent = {"axle_coupling": "body.pitch_index is null", "roll_coupling": "body.roll_index is null",
              "front_axle_pivot": "body.front_axle is 'rigid'"}
    present = {"axle_coupling": "body.pitch_index is given", "roll_coupling": "body.roll_index is given",
               "front_axle_pivot": "body.front_axle is 'pivot'"}
    for effect in BODY_EFFECTS:
        if effect in effects and not implied[effect]:
            raise InputError(source, f"effects names {effect} but {absent[effect]}")
        if implied[effect] and effect not in effects:
            raise InputError(source, f"effects lacks {effect} but {present[effect]}")
    arrivals = {t: _number(_key(doc, f"tires.{t}.parameters.arrival.value", source),
                           f"tires.{t}.parameters.arrival.value", source) for t in TIRES}
    shared = {}
    for name in ("stagger", "delay"):
        params = _key(doc, "tires.FL.parameters", source)
        entry = params.get(name) if isinstance(params, dict) else None
        if isinstance(entry, dict) and entry.get("value") is not None:
            shared[name] = _number(entry["value"], f"tires.FL.parameters.{name}.value", source)
    return {"indices": indices, "front_axle": front, "body_effects": [e for e in BODY_EFFECTS if implied[e]],
            "tire_effects": [e for e in TIRE_EFFECTS if e in effects], "arrivals": arrivals, "shared": shared,
            "recording": doc.get("recording")}
