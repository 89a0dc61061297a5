"""The tire parameter sets a ride compares, from a whole-tractor recording: ``final``, ``paper``,
``waveform``, ``static=K``, ``fmu=DIR``, ``params=FILE``, ``map=FILE`` (:func:`parameter_sets`), and the check of
their names (:func:`check_set_names`).  :mod:`identification.comfort.ride` re-exports both."""

from __future__ import annotations

import math

from ..errors import InputError
from ..identify.tire_map import map_set
from ..model.tractor import Body
from ..recording import FRONT_TIRES

__all__ = ["parameter_sets", "check_set_names"]


def _documented_body(rec, body_doc, source) -> tuple:
    """The body and the final k, c of a whole-tractor document (``diagnose --json``, or a report's
    ``summary.json`` and its entry of `rec`): (Body, (k, c), how)."""
    from ..fmu.simulate_inputs import body_settings, diagnosis_of, read_body_document
    from ..recording import TIRES

    source = str(source or body_doc)
    doc = read_body_document(body_doc) if not isinstance(body_doc, dict) else body_doc
    doc = diagnosis_of(doc, source, rec.source)
    settings = body_settings(doc, source)
    idx = settings["indices"]
    try:
        final = ({t: float(doc["tires"][t]["k"]) for t in TIRES}, {t: float(doc["tires"][t]["c"]) for t in TIRES})
    except (KeyError, TypeError, ValueError):
        raise InputError(source, "not a 'cleatfmu diagnose --json' whole-tractor document: tires.<TIRE>.k and "
                                 ".c of FL, FR, RL, RR needed") from None
    footprint = {}
    if "enveloping" in (doc.get("effects") or []):
        try:
            footprint = {t: float(doc["tires"][t]["parameters"]["footprint"]["value"]) for t in TIRES}
        except (KeyError, TypeError, ValueError):
            raise InputError(source, "names enveloping but gives no tires.<TIRE>.parameters.footprint.value") \
                from None
        if not all(0 < v < 5 for v in footprint.values()):
            raise InputError(source, f"footprint lengths must be between 0 and 5 m, got {footprint}")
    body = Body(TIRES, tuple(rec.wheel_load_N[t] for t in TIRES), rec.wheelbase_m,
                pitch="axle_coupling" in settings["body_effects"], roll="roll_coupling" in settings["body_effects"],
                pivot=settings["front_axle"] == "pivot", pitch_index=idx.get("pitch_index", 1.0),
                roll_index=idx.get("roll_index", 1.0), pivot_index=idx.get("pivot_index", 0.05))
    what = "rigid tractor" if settings["front_axle"] == "rigid" else "tractor with a pivoting front axle"
    from pathlib import PureWindowsPath

    origin = PureWindowsPath(str(settings["recording"])).name if settings["recording"] else "its recording"
    return body, final, f"{what} of {PureWindowsPath(source).name} (diagnosed from {origin})", footprint


def parameter_sets(rec, names, *, diagnosis=None, workers: int = 1, body_doc=None, speed_m_s=None) -> tuple:
    """The tractor's body and tire parameter sets to ride with, from a whole-tractor recording.

    Parameters
    ----------
    rec : Recording
        All four channels.
    names : iterable of str
        ``final`` (the joint diagnosis's named model), ``paper`` (the paper's method per tire),
        ``waveform`` (the waveform fit per tire), ``static=K`` (every tire at K N/m, e.g. a compression
        test's, with the final model's c), ``fmu=DIR`` (the k and c the four tire FMUs in DIR carry),
        ``params=FILE`` (the k and c of an ``identify --json`` document of the four tires), ``map=FILE`` (the
        k and c of a ``cleatfmu map`` tire map at `speed_m_s`).
    diagnosis : TractorDiagnosis, optional
        The recording's joint diagnosis (run when neither it nor `body_doc` is given).
    workers : int
        Processes of the diagnosis.
    body_doc : dict or path-like, optional
        A ``diagnose --json`` document or a report's ``summary.json`` (its entry of `rec`): the body and the
        final k, c are taken from it, and no diagnosis is run.
    speed_m_s : float, optional
        The ride's speed, for ``map=FILE`` (default: the recording's).

    Returns
    -------
    (Body, dict, str, dict)
        The diagnosed body (the rigid tractor with typical indices when the diagnosis named no body
        coupling), ``name -> (k, c)``, how the body was obtained, and the final model's footprint length per
        tire (m) where the diagnosis named ``enveloping`` (else empty).
    """
    from ..diagnose.joint_select import diagnose_tractor
    from ..diagnose.joint_timing import BODY_DEFAULTS
    from ..recording import TIRES

    names = check_set_names(names, recording=rec.source)
    missing = [t for t in TIRES if t not in rec.accel_m_s2]
    if missing:
        raise InputError(rec.source, f"a ride needs all four hubs; no channel {', '.join(missing)}")
    if body_doc is not None and diagnosis is None:
        body, final, how, footprint = _documented_body(rec, body_doc, None)
    else:
        diag = diagnosis or diagnose_tractor(rec, workers=workers)
        theta = diag.final.params
        body = diag.final.model.body(theta)
        how = "diagnosed " + ("rigid tractor" if body.kind == "rigid" else "tractor with a pivoting front axle")
        final = ({t: theta[f"k_{t}"] for t in TIRES}, {t: theta[f"c_{t}"] for t in TIRES})
        footprint = {t: float(theta[f"footprint_{'front' if t in FRONT_TIRES else 'rear'}"]) for t in TIRES} \
            if "enveloping" in diag.effects else {}
    if body.kind not in ("rigid", "pivot"):
        body = Body(TIRES, tuple(rec.wheel_load_N[t] for t in TIRES), rec.wheelbase_m, pitch=True, roll=True,
                    pitch_index=BODY_DEFAULTS["pitch_index"], roll_index=BODY_DEFAULTS["roll_index"])
        how = "rigid tractor with typical indices (assumed: the diagnosis named no body coupling)"
    sets = {}
    for name in names:
        if name == "final":
            sets[name] = final
        elif name.startswith("fmu="):
            sets[name] = _fmu_set(name, recording=rec.source)
        elif name.startswith("params="):
            sets[name] = _params_set(name)
        elif name.startswith("map="):
            sets[name] = map_set(name[4:], rec.speed_m_s if speed_m_s is None else speed_m_s, TIRES)[:2]
        elif name in ("paper", "waveform"):
            if name == "paper":
                from ..identify.paper import identify as method
            else:
                from ..identify.waveform import identify_waveform_recording as method
            results = method(rec, list(TIRES))
            sets[name] = ({t: results[t].k for t in TIRES}, {t: results[t].c for t in TIRES})
        else:
            k = _stiffness(name)
            sets[name] = ({t: k for t in TIRES}, final[1])
    return body, sets, how, footprint


def check_set_names(names, *, recording=None) -> list:
    """The parameter-set names of :func:`parameter_sets`, checked (InputError naming ``--compare``);
    `recording` (a path or name) picks its FMUs in a folder of several recordings' (``fmu=DIR``)."""
    names = [str(n).strip() for n in names if str(n).strip()]
    if not names:
        raise InputError("--compare", "no parameter set given")
    if len(set(names)) != len(names):
        raise InputError("--compare", f"a parameter set named twice in {','.join(names)!r}")
    for name in names:
        if name.startswith("static="):
            _stiffness(name)
        elif name.startswith("fmu="):
            _fmu_set(name, recording=recording)
        elif name.startswith("params="):
            _params_set(name)
        elif name.startswith("map="):
            from ..recording import TIRES
            map_set(name[4:], None, TIRES)
        elif name not in ("paper", "waveform", "final"):
            raise InputError("--compare", f"unknown parameter set {name!r} (paper, waveform, final, static=K, "
                                          f"fmu=DIR, params=FILE, map=FILE)")
    return names


def _fmu_set(name: str, *, recording=None) -> tuple:
    """(k, c) per tire of ``fmu=DIR``: the stiffness and damping the four tire FMUs in DIR carry (their
    start values, as exported or written by ``diagnose --fmu-dir``); in a report's ``fmu/``, those of
    `recording` (path or name)."""
    from pathlib import PureWindowsPath

    from fmpy import read_model_description

    from ..recording import TIRES
    from ..fmu.simulate_inputs import tractor_fmu_paths

    folder = name.split("=", 1)[1]
    stem = None if recording is None else PureWindowsPath(str(recording)).name.removesuffix(".csv")
    paths = tractor_fmu_paths(folder, recording=stem)
    k, c = {}, {}
    for t in TIRES:
        try:
            starts = {v.name: v.start for v in read_model_description(str(paths[t])).modelVariables}
            k[t], c[t] = float(starts["stiffness"]), float(starts["damping"])
        except Exception as exc:   # not an FMU, or not a tire FMU
            raise InputError(paths[t], f"not a cleatfmu tire FMU with stiffness and damping ({exc})") from None
        if not (math.isfinite(k[t]) and 1e4 <= k[t] <= 1e8 and math.isfinite(c[t]) and c[t] >= 0):
            raise InputError(paths[t], f"stiffness {k[t]:g} N/m, damping {c[t]:g} N s/m: not a tire's")
    return k, c


def _params_set(name: str) -> tuple:
    """(k, c) per tire of ``params=FILE``: a ``cleatfmu identify --json`` document of all four tires (either
    method), each tire's k and c checked as ``export`` checks them."""
    from ..fmu.export import read_identified
    from ..recording import TIRES

    path = name.split("=", 1)[1]
    k, c = {}, {}
    for t in TIRES:
        _, _, entry = read_identified(path, t)
        k[t], c[t] = float(entry["k"]), float(entry["c"])
    return k, c


def _stiffness(name: str) -> float:
    """K of ``static=K``: a number in N/m, or a compression test's CSV (its eq. 18 static stiffness)."""
    value = name.split("=", 1)[1]
    try:
        k = float(value)
    except ValueError:
        from pathlib import Path
        if not Path(value).is_file():
            raise InputError("--compare", f"{name!r}: static=K needs a stiffness K in N/m (e.g. static=300e3) or "
                                          f"a compression test's CSV file") from None
        from ..identify.static import static_stiffness_file
        k = static_stiffness_file(value).k_N_per_m
    if not (math.isfinite(k) and 1e4 <= k <= 1e8):
        raise InputError("--compare", f"{name!r}: a tire stiffness of 1e4 .. 1e8 N/m is expected")
    return k
