"""Whole-tractor co-simulation: one tire FMU instance per wheel under the body, stepped with fmpy.

The master takes the body, the cleat and the arrivals from the model record
(:class:`identification.model.TractorModel`) and steps it with the scheme of
:mod:`identification.model.stepping` - the one the fitting models run
compiled - reading each wheel's force from its FMU (one ``doStep`` per FMU
per step, one ``setReal``/``getReal`` per force).  Before the first step it
finds each tire's static height itself, from the FMU's force (as an importer
whose body includes gravity must).

:func:`simulate_tractor` is ``cleatfmu simulate FL.fmu FR.fmu RL.fmu RR.fmu
REC.csv --body DIAG.json``: four tire FMUs under the body a whole-tractor
diagnosis found (its ``diagnose --json`` document: couplings, indices,
arrivals), compared with every channel of a recording.
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .cosim import TireFmu
from .diagnose.joint_fit import UNEXPLAINED_RATIO
from .errors import InputError
from .model import Cleat, TractorModel
from .model.stepping import run_body
from .preprocess import DEFAULT_CUTOFF_HZ, lowpass
from .recording import TIRES
from .scheme import Trajectory, _equilibrium_corner

__all__ = ["run_tractor_fmus", "TractorGain", "measure_tractor_gain", "build_tractor_fmus", "tractor_fmu_paths",
           "read_body_document", "TractorSimulation", "simulate_tractor", "UNEXPLAINED_RATIO"]


def run_tractor_fmus(fmu_paths, record: TractorModel, *, start_s: float, step_s: float, n: int) -> Trajectory:
    """Co-simulate the record's body on one tire FMU per wheel (paths in the record's tire order).

    The FMUs carry their own parameters (an extended tire FMU with a built-in
    cleat places the cleat itself from the hub's longitudinal position).
    """
    paths = [Path(p) for p in fmu_paths]
    if len(paths) != len(record.tires):
        raise ValueError(f"one FMU per tire is needed ({len(record.tires)}), got {len(paths)}")
    J, mass, _ = record.body.matrices()
    inputs = record.inputs(start_s, step_s, n)
    loads = np.array([p["static_load"] for p in record.laws], dtype=float)
    tires = []
    try:
        for path, name in zip(paths, record.tires):
            tires.append(TireFmu(path, instance_name=name))
        forces, static = [], []
        for i, tire in enumerate(tires):
            tire.initialize(start_s)
            params = tire.parameters()
            force = tire.force_fn()
            forces.append(force)
            x0 = float(inputs.hub_x[i, 0])
            static.append(_equilibrium_corner(lambda z, f=force, x=x0: f(z, 0.0, x, 0.0, 0.0, 0.0), loads[i],
                                              params["unloaded_radius"], loads[i] / params["stiffness"]))
        q0, dq0 = record.initial_state(start_s, inputs.hub_x[:, 0], inputs.hub_vx[:, 0])

        def do_steps(t_n, h):
            for tire in tires:
                tire.slave.doStep(t_n, h)

        traj = run_body(forces, J=J, mass=mass, static_z=np.array(static), loads_n=loads, inputs=inputs,
                        start_s=start_s, step_s=step_s, q0=q0, dq0=dq0, before_step=do_steps)
    finally:
        for tire in tires:
            tire.close()
    if not np.all(np.isfinite(traj.force_n)):
        raise InputError(paths[0], "the co-simulation diverged (non-finite tire force)")
    return traj


def build_tractor_fmus(fit, directory, stem: str, *, description_prefix: str = "") -> list[Path]:
    """Build one extended tire FMU per wheel of a fitted whole-tractor model: ``DIR/<stem>_<TIRE>.fmu``."""
    from build_scripts import build_fmu

    model, params = fit.model, fit.params
    rec = model.problem.rec
    directory = Path(directory)
    out = []
    effects = sorted(e for e in model.effects)
    for tire in model.problem.channels:
        law = model.law(params, tire)
        path = directory / f"{stem}_{tire}.fmu"
        text = (f"{description_prefix}Extended tire {tire} identified jointly with the whole tractor from cleat "
                f"recording '{Path(rec.source).name}' at {rec.speed_kmh:.4g} km/h; effects: "
                f"{', '.join(effects) or 'none'}. Parameters: "
                + "; ".join(f"{k} = {v}" if isinstance(v, bool) else f"{k} = {v:.6g}" for k, v in law.items())
                + " (SI units).")
        build_fmu("extended_tire", path, start_values=law, description=text, backend="native",
                  provenance={"command": "cleatfmu diagnose", "tire": tire, "effects": effects,
                              "recording": Path(rec.source).name})
        out.append(path)
    return out


@dataclass(frozen=True, eq=False)
class TractorGain:
    """Per channel NRMSE of the baseline and final models as FMUs co-simulated with fmpy."""

    nrmse_before: dict
    nrmse_after: dict
    agreement: float          # max |FMU − fitting model| / max |fitting model|, final model, all channels
    fmu_paths: list
    seconds: float


def _cosim_predict(fit, paths) -> dict:
    model = fit.model
    record = model.record(fit.params)
    traj = run_tractor_fmus(paths, record, **dict(zip(("start_s", "step_s", "n"), model.grid(record))))
    return model.predict(fit.params, trajectory=traj)


def _nrmse(problem, pred: dict) -> dict:
    w = problem.window
    return {c: float(np.sqrt(np.mean((pred[c] - problem.measured[c])[w] ** 2))
                     / np.sqrt(np.mean(problem.measured[c][w] ** 2))) for c in problem.channels}


def measure_tractor_gain(diag, fmu_dir=None, *, stem: str | None = None) -> TractorGain:
    """Build the FMUs of the baseline and of the final model, co-simulate both under the body.

    With `fmu_dir` the final model's FMUs are kept there (``<stem>_<TIRE>.fmu``,
    one per tire, written together or not at all).
    """
    t0 = time.perf_counter()
    pb = diag.problem
    stem = stem or Path(pb.rec.source).stem or "tire"
    with tempfile.TemporaryDirectory(prefix="cleatfmu_tractor_") as tmp:
        base_paths = build_tractor_fmus(diag.baseline, tmp, "baseline")
        before = _cosim_predict(diag.baseline, base_paths)
        final_paths = build_tractor_fmus(diag.final, tmp, stem)
        after = _cosim_predict(diag.final, final_paths)
        kept = []
        if fmu_dir is not None:
            from ._files import publish_files
            kept = publish_files({Path(fmu_dir) / p.name: p for p in final_paths})
    fitting = diag.final.prediction
    scale = max(float(np.max(np.abs(fitting[c]))) for c in pb.channels)
    agreement = max(float(np.max(np.abs(after[c] - fitting[c]))) for c in pb.channels) / max(scale, 1e-12)
    return TractorGain(nrmse_before=_nrmse(pb, before), nrmse_after=_nrmse(pb, after), agreement=agreement,
                       fmu_paths=kept, seconds=time.perf_counter() - t0)


# ---------------------------------------------------------------------------------------------------------------
# cleatfmu simulate FL.fmu FR.fmu RL.fmu RR.fmu REC.csv --body DIAG.json

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
    try:
        text = Path(source).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(source, "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(source, f"cannot read: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(source, f"not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(doc, dict):
        raise InputError(source, "not a 'cleatfmu diagnose --json' whole-tractor document (not a JSON object)")
    return doc


def _body_settings(doc: dict, source) -> dict:
    """The body, effects and arrivals of a ``diagnose --json`` document (validated)."""
    from .diagnose.tractor import BODY_EFFECTS, EFFECTS, TIRE_EFFECTS

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


def _fmu_law(path: Path, static_load: float) -> dict:
    """The extended tire law an FMU carries, as the model record needs it (cleat handling, lugs, static load).

    Parameters the FMU does not have keep the law's defaults; a tire without
    the longitudinal inputs cannot place a cleat itself, so it gets the road.
    The static load is the body's (the recording's wheel load).
    """
    from .tire_law import EXTENDED_DEFAULTS

    law = dict(EXTENDED_DEFAULTS)
    with TireFmu(path, instance_name="probe") as fmu:
        fmu.initialize(0.0)
        params = fmu.parameters()
        longitudinal = fmu.longitudinal
    law.update({k: v for k, v in params.items() if k in EXTENDED_DEFAULTS})
    if not longitudinal:
        law["cleat_height"] = 0.0
    law["static_load"] = float(static_load)
    return law


@dataclass(frozen=True, eq=False)
class TractorSimulation:
    """Four tire FMUs co-simulated under the body against every channel of a recording."""

    recording: str
    fmus: dict                # tire -> Path
    body: dict                # the body and arrivals used
    problem: object           # TractorProblem: measured (low-passed) channels, noise, window
    predicted: dict           # tire -> sensed, low-passed co-simulated acceleration, m/s² (recording's time base)
    nrmse: dict
    noise_nrmse: dict
    step_s: float
    seconds: float

    @property
    def channels(self) -> tuple:
        return self.problem.channels

    def residual_to_noise(self, tire: str) -> float:
        return self.nrmse[tire] / self.noise_nrmse[tire]

    def unexplained(self, tire: str) -> bool:
        """The residual exceeds :data:`UNEXPLAINED_RATIO` times the noise: the model does not explain the data."""
        return self.residual_to_noise(tire) > UNEXPLAINED_RATIO

    def to_json(self) -> dict:
        return {"recording": self.recording, "fmus": {t: str(p) for t, p in self.fmus.items()},
                "body": dict(self.body),
                "tires": {t: {"nrmse": self.nrmse[t], "noise_nrmse": self.noise_nrmse[t],
                              "residual_to_noise": self.residual_to_noise(t)} for t in self.channels}}


def simulate_tractor(fmu_paths, rec, body_doc, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                     step_s: float | None = None, body_source=None) -> TractorSimulation:
    """Co-simulate four tire FMUs under a diagnosed body over a recording and compare every channel.

    Parameters
    ----------
    fmu_paths : dict or sequence or path-like
        {tire: FMU}, four FMUs, or a directory (see :func:`tractor_fmu_paths`).
    rec : Recording
        With all four channels.
    body_doc : dict or path-like
        A ``cleatfmu diagnose --json`` whole-tractor document: the body
        (``pitch_index``, ``roll_index``, ``front_axle``, ``pivot_index``)
        and each tire's cleat arrival.  The FMUs carry their own tire laws.
    cutoff_hz : float
        Low-pass cut-off of the comparison (as the diagnosis), Hz.
    step_s : float, optional
        Largest co-simulation step (default that of the diagnosis, 1 ms).
    body_source : str, optional
        Name of the document in error messages (default: its path, or ``--body``).

    Returns
    -------
    TractorSimulation
        NRMSE per channel of the sensed, low-passed co-simulated acceleration
        over the diagnosis window, the noise-only NRMSE and their ratio.
    """
    from .diagnose.tractor import DEFAULT_STEP_S, TractorFitModel, TractorProblem

    t0 = time.perf_counter()
    if isinstance(body_doc, (str, Path)):
        body_source = body_source or str(body_doc)
        body_doc = read_body_document(body_doc)
    source = body_source or "--body"
    settings = _body_settings(body_doc, source)
    paths = fmu_paths if isinstance(fmu_paths, dict) else tractor_fmu_paths(fmu_paths)
    if sorted(paths) != sorted(TIRES):
        raise InputError(None, f"one FMU per tire FL, FR, RL, RR is needed, got {', '.join(paths) or 'none'}")
    paths = {t: Path(paths[t]) for t in TIRES}
    if tuple(t for t in TIRES if t in rec.tires) != TIRES:
        raise InputError(rec.source, f"the whole-tractor simulation needs all four channels FL, FR, RL, RR; "
                                     f"the recording holds {', '.join(rec.tires)}")
    step = DEFAULT_STEP_S if step_s is None else float(step_s)
    if not step > 0:
        raise InputError("--max-step-s", f"must be > 0, got {step}")
    pb = TractorProblem.from_recording(rec, cutoff_hz=cutoff_hz, step_s=step)
    model = TractorFitModel(settings["tire_effects"] + settings["body_effects"], pb, resolve_edges=True)
    theta = dict(settings["indices"])
    try:
        body = model.body(theta)
    except ValueError as exc:
        raise InputError(source, f"not a valid body: {exc}") from None
    laws = tuple(_fmu_law(paths[t], rec.wheel_load_N[t]) for t in pb.channels)
    record = TractorModel(body=body, laws=laws, cleat=Cleat(rec.cleat_height_m, rec.cleat_width_m, rec.speed_m_s),
                          arrivals_s=tuple(settings["arrivals"][t] for t in pb.channels))
    start, h, n = model.grid(record)
    traj = run_tractor_fmus([paths[t] for t in pb.channels], record, start_s=start, step_s=h, n=n)
    predicted = model.predict(theta, trajectory=traj)
    w = pb.window
    noise = {t: float(pb.noise[t] / np.sqrt(np.mean(pb.measured[t][w] ** 2))) for t in pb.channels}
    used = {"document": str(source), "diagnosed_recording": settings["recording"],
            "front_axle": settings["front_axle"],
            "pitch_index": theta.get("pitch_index"), "roll_index": theta.get("roll_index"),
            "pivot_index": theta.get("pivot_index"), "kind": body.kind,
            "effects": settings["tire_effects"] + settings["body_effects"],
            "arrival_s": {t: settings["arrivals"][t] for t in pb.channels},
            "stagger_s": settings["shared"].get("stagger"), "delay_s": settings["shared"].get("delay"),
            "builtin_cleat": {t: bool(record.builtin_cleat(i)) for i, t in enumerate(pb.channels)}}
    return TractorSimulation(recording=rec.source, fmus=paths, body=used, problem=pb, predicted=predicted,
                             nrmse=_nrmse(pb, predicted), noise_nrmse=noise, step_s=h,
                             seconds=time.perf_counter() - t0)
