"""Whole-tractor co-simulation: one tire FMU instance per wheel under the body, stepped with fmpy.

The master takes the body, the cleat and the arrivals from the model record
(:class:`identification.model.TractorModel`) and steps it with the scheme of
:mod:`identification.model.stepping` - the one the fitting models run
compiled - reading each wheel's force from its FMU (one ``doStep`` per FMU
per step, one ``setReal``/``getReal`` per force).  Before the first step it
finds each tire's static height itself, from the FMU's force (as an importer
whose body includes gravity must).  fmpy loads and sets up the FMUs; the
stepping (:func:`step_body_fmus`) calls the FMUs' functions itself, with
arguments allocated once, and skips J's zero entries.

:func:`simulate_tractor` is ``cleatfmu simulate FL.fmu FR.fmu RL.fmu RR.fmu
REC.csv --body DIAG.json``: four tire FMUs under the body a whole-tractor
diagnosis found (its ``diagnose --json`` document: couplings, indices,
arrivals), compared with every channel of a recording.
"""

from __future__ import annotations

import tempfile
import time
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .cosim import TireFmu
from .master import step_body_fmus
from ..errors import InputError
from ..model import Cleat, TractorModel
from ..model.fitting import UNEXPLAINED_RATIO
from ..recording.preprocess import DEFAULT_CUTOFF_HZ
from ..recording import TIRES
from ..model.scheme import Trajectory, _equilibrium_corner
from .simulate_inputs import body_settings, diagnosis_of, read_body_document, tractor_fmu_paths
from .._files import temp_prefix

__all__ = ["run_tractor_fmus", "step_body_fmus", "TractorGain", "measure_tractor_gain", "build_tractor_fmus",
           "TractorSimulation", "simulate_tractor", "tractor_from_fmus", "UNEXPLAINED_RATIO", "CLEAT_PARAMETERS"]


def run_tractor_fmus(fmus, record: TractorModel, *, start_s: float, step_s: float, n: int) -> Trajectory:
    """Co-simulate the record's body on one tire FMU per wheel (in the record's tire order).

    `fmus` are paths (each FMU is opened here and closed after the run) or
    open :class:`~identification.fmu.cosim.TireFmu` instances (initialized afresh
    at `start_s` here, left open).  The FMUs carry their own parameters (an
    extended tire FMU with a built-in cleat places the cleat itself from the
    hub's longitudinal position).  A tire with longitudinal inputs gets the built-in cleat of its law in the
    record (:data:`CLEAT_PARAMETERS`) set explicitly before it starts: the exported FMUs start with
    ``cleat_height`` 0.
    """
    fmus = [f if isinstance(f, TireFmu) else Path(f) for f in fmus]
    if len(fmus) != len(record.tires):
        raise ValueError(f"one FMU per tire is needed ({len(record.tires)}), got {len(fmus)}")
    cleats = [{n: record.laws[i][n] for n in CLEAT_PARAMETERS if n in record.laws[i]}
              for i in range(len(record.tires))]
    J, mass, _ = record.body.matrices()
    inputs = record.inputs(start_s, step_s, n)
    loads = np.array([p["static_load"] for p in record.laws], dtype=float)
    with ExitStack() as stack:
        tires = [f if isinstance(f, TireFmu) else stack.enter_context(TireFmu(f, instance_name=name))
                 for f, name in zip(fmus, record.tires)]
        static = []
        for i, tire in enumerate(tires):
            if tire.longitudinal:     # the record's built-in cleat, set explicitly: exported FMUs start with it off
                tire.set_start_values(cleats[i])
            tire.initialize(start_s)
            params = tire.parameters()
            force, x0 = tire.force_fn(), float(inputs.hub_x[i, 0])
            static.append(_equilibrium_corner(lambda z, f=force, x=x0: f(z, 0.0, x, 0.0, 0.0, 0.0), loads[i],
                                              params["unloaded_radius"], loads[i] / params["stiffness"]))
        q0, dq0 = record.initial_state(start_s, inputs.hub_x[:, 0], inputs.hub_vx[:, 0])
        traj = step_body_fmus(tires, J=J, mass=mass, static_z=np.array(static), loads_n=loads, inputs=inputs,
                              start_s=start_s, step_s=step_s, q0=q0, dq0=dq0)
    if not all(np.all(np.isfinite(a)) for a in (traj.force_n, traj.hub_z_m, traj.hub_vz_m_s)):
        raise InputError(tires[0].path, "the co-simulation diverged (non-finite tire force or hub motion)")
    return traj


#: The parameters of an extended tire's built-in cleat, which the co-simulations set explicitly.
CLEAT_PARAMETERS = ("cleat_height", "cleat_width", "cleat_x", "cleat_bevel")


def build_tractor_fmus(fit, directory, stem: str, *, description_prefix: str = "") -> list[Path]:
    """Build one extended tire FMU per wheel of a fitted whole-tractor model: ``DIR/<stem>_<TIRE>.fmu``.

    The built-in cleat (the test's, for a tire that envelops it) is off in the FMU: ``cleat_height`` starts
    at 0, so that a ride model gets the plain road; its width, position and bevel are kept, and the
    model description names the height to set for a run over the test's cleat.
    """
    from build_scripts import build_fmu

    model, params = fit.model, fit.params
    rec = model.problem.rec
    directory = Path(directory)
    out = []
    effects = sorted(e for e in model.effects)
    for tire in model.problem.channels:
        law = model.law(params, tire)
        test_cleat = law["cleat_height"]
        law = {**law, "cleat_height": 0.0}
        path = directory / f"{stem}_{tire}.fmu"
        text = (f"{description_prefix}Extended tire {tire} identified jointly with the whole tractor from cleat "
                f"recording '{Path(rec.source).name}' at {rec.speed_kmh:.4g} km/h; effects: "
                f"{', '.join(effects) or 'none'}. Parameters: "
                + "; ".join(f"{k} = {v}" if isinstance(v, bool) else f"{k} = {v:.6g}" for k, v in law.items())
                + " (SI units)."
                + (f" The built-in test cleat is off (cleat_height 0): set cleat_height = {test_cleat:.6g} m to "
                   f"ride the test's cleat through hub_x." if test_cleat > 0 else ""))
        build_fmu("extended_tire", path, start_values=law, description=text, backend="native",
                  provenance={"command": "cleatfmu diagnose", "tire": tire, "effects": effects,
                              "recording": Path(rec.source).name})
        out.append(path)
    return out


@dataclass(frozen=True, eq=False)
class TractorGain:
    """Per channel NRMSE of the baseline and final models as FMUs co-simulated with fmpy.

    ``note`` says why the baseline's NRMSE is its fitting model's instead (its FMUs could not start: the
    four-corner fit of a recording it cannot explain may leave a tire that carries no load), else None;
    ``final_note`` says the same of the final model (then ``agreement`` is None and no FMU is kept).
    """

    nrmse_before: dict
    nrmse_after: dict
    agreement: float | None   # max |FMU − fitting model| / max |fitting model|, final model, all channels
    fmu_paths: list
    seconds: float
    note: str | None = None
    final_note: str | None = None


def _cosim_predict(fit, paths) -> dict:
    model = fit.model
    record = model.record(fit.params)
    try:
        traj = run_tractor_fmus(paths, record, **dict(zip(("start_s", "step_s", "n"), model.grid(record))))
    except ValueError as exc:      # a fitted force law that never carries its load: say so, in one line
        raise InputError(model.problem.rec.source, f"the {fit.label} model's FMUs cannot start the "
                                                   f"co-simulation: {exc}") from None
    return model.predict(fit.params, trajectory=traj)


def _nrmse(problem, pred: dict) -> dict:
    w = problem.window
    return {c: float(np.sqrt(np.mean((pred[c] - problem.measured[c])[w] ** 2))
                     / np.sqrt(np.mean(problem.measured[c][w] ** 2))) for c in problem.channels}


def measure_tractor_gain(diag, fmu_dir=None, *, stem: str | None = None, strict: bool = True) -> TractorGain:
    """Build the FMUs of the baseline and of the final model, co-simulate both under the body.

    With `fmu_dir` the final model's FMUs are kept there (``<stem>_<TIRE>.fmu``,
    one per tire, written together or not at all).  FMUs that cannot start never cost the diagnosis:
    the NRMSE is then the fitting model's, with a note, and none is kept; only when `fmu_dir` asks for
    them and `strict` is set is it an error.
    """
    t0 = time.perf_counter()
    pb = diag.problem
    stem = stem or Path(pb.rec.source).stem or "tire"
    with tempfile.TemporaryDirectory(prefix=temp_prefix("tractor")) as tmp:
        base_paths = build_tractor_fmus(diag.baseline, tmp, "baseline")
        note = None
        try:
            before = _cosim_predict(diag.baseline, base_paths)
        except InputError as exc:      # the final model's FMUs must start; the baseline's are only the reference
            before = diag.baseline.prediction
            note = f"{exc.problem}; the four-corner NRMSE is its fitting model's"
        final_paths = build_tractor_fmus(diag.final, tmp, stem)
        final_note = None
        try:
            after = _cosim_predict(diag.final, final_paths)
        except InputError as exc:
            if fmu_dir is not None and strict:
                raise
            after = diag.final.prediction
            final_note = (f"{exc.problem}; its NRMSE is the fitting model's, and its FMUs would not start in "
                          f"an importer either")
            if diag.final.label == diag.baseline.label:   # the baseline is the final model: one warning
                note = None
        kept = []
        if fmu_dir is not None and final_note is None:
            from .._files import publish_files
            kept = publish_files({Path(fmu_dir) / p.name: p for p in final_paths})
    fitting = diag.final.prediction
    scale = max(float(np.max(np.abs(fitting[c]))) for c in pb.channels)
    agreement = None if final_note else \
        max(float(np.max(np.abs(after[c] - fitting[c]))) for c in pb.channels) / max(scale, 1e-12)
    return TractorGain(nrmse_before=_nrmse(pb, before), nrmse_after=_nrmse(pb, after), agreement=agreement,
                       fmu_paths=kept, seconds=time.perf_counter() - t0, note=note, final_note=final_note)


# ---------------------------------------------------------------------------------------------------------------
# cleatfmu simulate FL.fmu FR.fmu RL.fmu RR.fmu REC.csv --body DIAG.json

def _fmu_law(fmu: TireFmu, rec, tire: str) -> dict:
    """The extended tire law an open FMU carries, as the model record needs it (cleat handling, lugs, static
    load); the FMU is left initialized at t = 0 (the run initializes it afresh).

    Parameters the FMU does not have keep the law's defaults; a tire without
    the longitudinal inputs cannot place a cleat itself, so it gets the road.
    A tire with a footprint whose built-in cleat is off (as exported) envelops
    the recording's cleat as its built-in one (height, width and bevel of the
    recording's; the run sets them).  The static load is the body's (the
    recording's wheel load).
    """
    from ..model.tire_law import EXTENDED_DEFAULTS

    law = dict(EXTENDED_DEFAULTS)
    fmu.initialize(0.0)
    law.update({k: v for k, v in fmu.parameters().items() if k in EXTENDED_DEFAULTS})
    if not fmu.longitudinal:
        law["cleat_height"] = 0.0
    elif fmu.envelops_test_cleat():
        law.update(cleat_height=float(rec.cleat_height_m), cleat_width=float(rec.cleat_width_m),
                   cleat_bevel=0.0 if rec.cleat_profile is None else float(rec.cleat_profile.builtin_bevel_m))
    law["static_load"] = float(rec.wheel_load_N[tire])
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

    def residual_test(self, tire: str) -> dict:
        """The co-simulated residual against the noise floor, over the window and its worst stretch
        (:func:`~identification.model.fitting.residual_test`, the stretch in s)."""
        return self.problem.residual_test(self.predicted[tire], tire)

    def unexplained(self, tire: str) -> bool:
        """The residual exceeds :data:`UNEXPLAINED_RATIO` times the noise over the window, or
        :data:`~identification.model.fitting.LOCAL_RATIO` times it over its worst stretch: the model does not
        explain the data."""
        return not self.residual_test(tire)["at_noise"]

    def to_json(self) -> dict:
        return {"recording": self.recording, "fmus": {t: str(p) for t, p in self.fmus.items()},
                "body": dict(self.body),
                "tires": {t: {"nrmse": self.nrmse[t], "noise_nrmse": self.noise_nrmse[t],
                              "residual_to_noise": self.residual_to_noise(t),
                              "residual_test": self.residual_test(t)} for t in self.channels}}


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
    t0 = time.perf_counter()
    built = tractor_from_fmus(fmu_paths, rec, body_doc, cutoff_hz=cutoff_hz, step_s=step_s, body_source=body_source)
    model, pb, theta, paths, record, body, settings, source = built
    with ExitStack() as stack:  # each FMU opened once more for the run
        tires = [stack.enter_context(TireFmu(paths[t], instance_name=t)) for t in pb.channels]
        start, h, n = model.grid(record)
        traj = run_tractor_fmus(tires, record, start_s=start, step_s=h, n=n)
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


def tractor_from_fmus(fmu_paths, rec, body_doc, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                      step_s: float | None = None, body_source=None):
    """The model record of four tire FMUs under a diagnosed body over a recording (see :func:`simulate_tractor`).

    Returns (fit model, problem, body indices, {tire: FMU path}, record, body, the document's settings,
    the document's name); the record's laws are those the FMUs carry.
    """
    from ..model.fitting import DEFAULT_STEP_S, TractorFitModel, TractorProblem

    if isinstance(body_doc, (str, Path)):
        body_source = body_source or str(body_doc)
        body_doc = read_body_document(body_doc)
    source = body_source or "--body"
    settings = body_settings(diagnosis_of(body_doc, source, rec.source), source)
    paths = fmu_paths if isinstance(fmu_paths, dict) else \
        tractor_fmu_paths(fmu_paths, recording=Path(rec.source).stem)
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
    laws = []
    for t in pb.channels:   # each FMU's law
        with TireFmu(paths[t], instance_name=t) as tire:
            laws.append(_fmu_law(tire, rec, t))
    record = TractorModel(body=body, laws=tuple(laws),
                          cleat=Cleat.of(rec),
                          arrivals_s=tuple(settings["arrivals"][t] for t in pb.channels))
    return model, pb, theta, paths, record, body, settings, source
