"""The inputs of ``cleatfmu simulate`` for the whole tractor: the four tire FMUs and the body document.

:func:`tractor_fmu_paths` matches the FMU files to the tires;
:func:`read_body_document` reads a ``cleatfmu diagnose --json`` whole-tractor
document and :func:`body_settings` takes from it (validated) the body, the
effects and each tire's cleat arrival, for
:func:`identification.fmu.tractor_cosim.simulate_tractor`.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from ..recording import TIRES

__all__ = ["tractor_fmu_paths", "read_body_document", "body_settings"]


def _tire_suffix(path: Path):
    """The tire a file name ends with (``*_FL.fmu``), or None."""
    name = path.name
    return next((t for t in TIRES if name.endswith(f"_{t}.fmu")), None)


def tractor_fmu_paths(paths) -> dict:
    """The FMU of each tire, {FL, FR, RL, RR: Path}, from one directory or four paths.

    A directory must hold exactly one ``*_FL.fmu``, ``*_FR.fmu``, ``*_RL.fmu``
    and ``*_RR.fmu`` (as ``cleatfmu diagnose --fmu-dir`` writes them).  Four
    paths are matched by the same suffixes when each tire's is there once,
    else taken in FL, FR, RL, RR order (a path whose suffix names another
    tire than its place is refused).
    """
    paths = [Path(p) for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
    if len(paths) == 1 and paths[0].is_dir():
        folder = paths[0]
        found = {t: sorted(p.name for p in folder.glob(f"*_{t}.fmu") if p.is_file()) for t in TIRES}
        missing = [f"*_{t}.fmu" for t in TIRES if not found[t]]
        several = [f"{len(found[t])} *_{t}.fmu ({', '.join(found[t])})" for t in TIRES if len(found[t]) > 1]
        if missing or several:
            problems = ([f"no {', '.join(missing)}"] if missing else []) + \
                       ([f"several: {'; '.join(several)}"] if several else [])
            raise InputError(folder, "needs exactly one *_FL.fmu, *_FR.fmu, *_RL.fmu and *_RR.fmu: "
                             + "; ".join(problems))
        return {t: folder / found[t][0] for t in TIRES}
    if len(paths) != len(TIRES):
        raise InputError(None, f"give one tire FMU, four (FL FR RL RR) or one directory holding them, "
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
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(source, f"{keys} must be a finite number, got {value!r}")
    return float(value)


def read_body_document(source) -> dict:
    """Read a ``diagnose --json`` document (path) as a dict; InputError naming the file when unreadable."""
    from .._files import read_json_file

    doc = read_json_file(source)
    if not isinstance(doc, dict):
        raise InputError(source, "not a 'cleatfmu diagnose --json' whole-tractor document (not a JSON object)")
    return doc


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
