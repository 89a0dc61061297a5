"""The whole chain over many recordings: identify, export, co-simulate, diagnose, extend, report.

One job per tire and one per recording, spread over the machine's cores:

1. **identify** (per tire) - the paper's method and the waveform fit (k, c with 95 % intervals);
2. **export** (per tire) - the point-contact tire FMU (native C) with the waveform values (the paper's if
   the fit fails): one corner alone, so not recommended (``fmu/not_recommended/<method>/``);
3. **co-simulate** (per tire) - the FMU under the corner mass over the recording's cleat, against the
   measurement;
4. **diagnose** (per recording) - every channel fitted jointly under one body
   (:func:`~identification.diagnose.joint_select.diagnose_tractor`): the effects the four-corner model
   misses, one recommended k, c per tire, what is still unexplained, one extended tire FMU per wheel
   (``fmu/<recording>_<TIRE>.fmu``: the recommended file), the gain measured by co-simulating them under
   the body with fmpy, and the recommended k, c as parameters (``params/<recording>.json``) and as plain
   spring-damper FMUs (``fmu/point_contact/``; :mod:`~identification.report.files`);
5. **figures and FMU validation** - the paper's Figure 9a/9b, the overlays, and
   ``fmpy.validation.validate_fmu`` of every FMU written.

A recording that cannot be read, or a stage that fails, is recorded with
its one-line error; the others go on.  Every stage's wall time is kept.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from .._files import atomic_write_texts, json_text
from ..errors import InputError
from .campaign import NAME_KEYS
from .files import (FIGURES_STAGING, FOLDERS, not_recommended_fmu, not_recommended_params, remove_staging,
                    write_recommended_files)

__all__ = ["TireReport", "DiagnosisReport", "RecordingReport", "BatchResult", "collect_recordings", "run_batch", "STAGES"]

STAGES = ("identify", "export", "co-simulate", "diagnose", "figures", "validate")


@dataclass
class TireReport:
    """Everything the report shows about one tire (picklable: numbers, text, PNG bytes)."""

    recording: str
    tire: str
    paper: dict | None = None
    waveform: dict | None = None
    simulate: dict | None = None
    figures: dict = field(default_factory=dict)      # name -> PNG bytes (a Path once streamed to disk)
    fmus: list = field(default_factory=list)         # {"file", "kind", "problems": [...]}
    errors: list = field(default_factory=list)       # "stage: message"
    timings: dict = field(default_factory=dict)      # stage -> s


@dataclass
class DiagnosisReport:
    """The joint diagnosis of one recording (picklable): the ``diagnose --json`` document and more."""

    recording: str
    diagnosis: dict | None = None                    # diagnose --json, NRMSEs from the FMU co-simulation
    ride: dict | None = None                         # ride --json: the tractor on a road, per parameter set
    figures: dict = field(default_factory=dict)
    fmus: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)


@dataclass
class RecordingReport:
    source: str
    stem: str
    ok: bool
    error: str | None = None
    speed_kmh: float | None = None
    sample_rate_hz: float | None = None
    conditions: dict | None = None                   # what the run was tested at (tire_map.run_conditions)
    tires: list = field(default_factory=list)        # TireReport, file order
    diagnosis: DiagnosisReport | None = None
    wheel_load_N: dict = field(default_factory=dict)  # static wheel load per channel, N (campaign conditions)
    names: dict = field(default_factory=dict)         # what the sidecar names (campaign.NAME_KEYS)

    def recommended(self, tire: str) -> dict | None:
        """The recommended k, c of a tire: the joint diagnosis's (with its intervals), else None."""
        d = self.diagnosis.diagnosis if self.diagnosis is not None else None
        if d is None or tire not in d["tires"]:
            return None
        t = d["tires"][tire]
        return {"k": t["k"], "c": t["c"], "k_ci": t["k_ci"], "c_ci": t["c_ci"], "source": "joint diagnosis",
                "conditional": t["unexplained"] is not None}


@dataclass
class BatchResult:
    recordings: list
    out_dir: Path
    seconds: float
    timings: dict                                    # stage -> total s over all jobs
    campaign: list | None = None                     # the campaign's conditions, with their pooled files
    errors: list = field(default_factory=list)       # what failed beyond the recordings (the pooled files)

    @property
    def failures(self) -> list[str]:
        """One line per failed recording or tire stage."""
        out = [f"{r.source}: {r.error}" for r in self.recordings if not r.ok] + list(self.errors)
        for r in self.recordings:
            for t in r.tires:
                out += [f"{r.source} {t.tire}: {e}" for e in t.errors]
            if r.diagnosis is not None:
                out += [f"{r.source}: {e}" for e in r.diagnosis.errors]
        return out


def collect_recordings(items) -> list[Path]:
    """The recording CSV files named by `items` (files, or folders scanned for ``*.csv``)."""
    paths: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            paths += sorted(q for q in p.glob("*.csv") if q.is_file())
        elif p.is_file():
            paths.append(p)
        elif p.exists():
            raise InputError(p, "is not a regular file (a pipe, a device or a socket)")
        else:
            raise InputError(p, "no such file or directory")
    if not paths:
        raise InputError(" ".join(map(str, items)) or None, "no recording (*.csv) found")
    return paths


def _timed(timings: dict, stage: str):
    """Add the block's time to ``timings[stage]``; what it spent compiling the model's code (a first run
    after an install) goes to ``timings["compile"]`` instead."""
    from .._compile import compile_seconds

    class _T:
        def __enter__(self):
            self.t = time.perf_counter()
            self.compiling = compile_seconds()
            self.clock = self.compiling.__enter__()

        def __exit__(self, *exc):
            self.compiling.__exit__(None, None, None)
            spent = time.perf_counter() - self.t
            timings[stage] = timings.get(stage, 0.0) + spent - self.clock.seconds
            if self.clock.seconds:
                timings["compile"] = timings.get("compile", 0.0) + self.clock.seconds
    return _T()


def _validate(path: Path) -> list[str]:
    from fmpy.validation import validate_fmu
    try:
        return [str(p) for p in validate_fmu(str(path))]
    except Exception as exc:  # a validator crash is a validation problem to show
        return [f"validation failed: {exc}"]


def process_tire(csv_path: str, stem: str, tire: str, out_dir: str) -> TireReport:
    """Run every stage for one tire (called in a worker process)."""
    from ..fmu.export import export_fmu
    from ..identify.paper import identify_paper
    from .plots import plot_comparison, plot_decay, plot_log_peaks, figure, png_bytes
    from ..recording.preprocess import preprocess
    from ..recording import read_recording
    from ..fmu.validation import simulate_recording
    from ..identify.waveform import identify_waveform
    from ..recording.window import focus, window_json

    rep = TireReport(recording=stem, tire=tire)
    rec = read_recording(csv_path)
    sig = None
    with _timed(rep.timings, "identify"):
        try:
            rec = focus(rec, announce=False)
            sig = preprocess(rec, [tire])[tire]
            paper = identify_paper(sig, rec.mass_kg(tire), source=rec.source, window=window_json(rec))
            rep.paper = dict(paper.to_json(), decay_rate=paper.decay_rate)
            rep.waveform = identify_waveform(sig, rec.mass_kg(tire), source=rec.source).to_json()
        except InputError as exc:
            rep.errors.append(f"identify: {exc.problem}")
    with _timed(rep.timings, "figures"):
        if rep.paper is not None:
            fig, (a, b) = figure(1, 2, size=(11.0, 3.8), gridspec_kw={"width_ratios": [2.2, 1]})
            plot_decay(a, sig, rep.paper["decay_rate"])
            a.set_title(f"{stem} {tire}: filtered acceleration, peaks and decay curve (cf. paper Fig. 9a)")
            a.legend(fontsize=8)
            plot_log_peaks(b, sig, rep.paper["decay_rate"])
            b.set_title(f"ln(peaks), R² {rep.paper['r2']:.3f} (Fig. 9b)")
            b.legend(fontsize=8)
            rep.figures["decay"] = png_bytes(fig)
    method = "waveform" if rep.waveform else "paper"
    fmu_path = Path(out_dir) / not_recommended_fmu(stem, tire, method)
    if rep.paper is not None:
        with _timed(rep.timings, "export"):
            params = {"recording": rec.source, "speed_kmh": rec.speed_kmh, "tires": {tire: rep.waveform or rep.paper},
                      "note": f"NOT RECOMMENDED: the {method} fit of one corner alone; the recommended k and c are "
                              f"in ../../{stem}.json"}
            params_file = Path(out_dir) / not_recommended_params(stem, tire, method)
            params_file.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_texts({params_file: json_text(params) + "\n"})
            try:
                export_fmu(params_file, fmu_path, tire=tire, backend="native")
                rep.fmus.append({"file": not_recommended_fmu(stem, tire, method), "kind": "point_contact",
                                 "recommended": False, "method": method,
                                 "role": f"point-contact tire of the {method} fit of this corner alone"})
            except InputError as exc:
                rep.errors.append(f"export: {exc.problem}")
    if fmu_path.exists():
        with _timed(rep.timings, "co-simulate"):
            try:
                cmp = simulate_recording(fmu_path, rec, tire, method="waveform" if rep.waveform else "paper")
                rep.simulate = dict(cmp.to_json(), worst_window=cmp.worst_window, alignment_s=cmp.alignment_s)
            except InputError as exc:
                rep.errors.append(f"co-simulate: {exc.problem}")
                cmp = None
        if cmp is not None:
            with _timed(rep.timings, "figures"):
                rep.figures["comparison"] = png_bytes(plot_comparison(cmp))
    with _timed(rep.timings, "validate"):
        for entry in rep.fmus:
            entry["problems"] = _validate(Path(out_dir) / entry["file"])
    return rep


def diagnose_recording(csv_path: str, stem: str, out_dir: str, static: dict | None = None) -> DiagnosisReport:
    """Diagnose every channel of a recording jointly; keep one extended FMU per tire (in a worker process).

    `static` (:func:`identification.report.ride.static_source`) adds a static-stiffness set to the ride."""
    from ..diagnose.run import diagnosis_warnings, run_tractor_diagnosis
    from .plots import plot_impact_zooms, plot_tractor_diagnosis, png_bytes
    from ..recording import read_recording

    rep = DiagnosisReport(recording=stem)
    rec = read_recording(csv_path)
    with _timed(rep.timings, "diagnose"):
        try:
            diag, gain = run_tractor_diagnosis(rec, fmu_dir=Path(out_dir) / "fmu", stem=stem, strict=False)
        except (InputError, ValueError) as exc:
            rep.errors.append(f"diagnose: {getattr(exc, 'problem', exc)}")
            return rep
    compiled = rep.timings.get("compile", 0.0)       # the first run after an install compiles the model's code
    rep.diagnosis = dict(diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after),
                         agreement=gain.agreement, seconds=max(diag.seconds - compiled, 0.0),
                         compile_seconds=compiled, fmu_seconds=gain.seconds,
                         timings={k: round(v, 3) for k, v in diag.timings().items()},
                         warnings=list((diag.problem.rec.conditioning or {}).get("warnings", []))
                         + diagnosis_warnings(diag, gain))
    role = ("recommended: extended tire, fitted jointly with the whole tractor ("
            + (", ".join(diag.effects) or "no effect") + "); built-in test cleat off (cleat_height 0)")
    for path in gain.fmu_paths:
        rep.fmus.append({"file": f"fmu/{Path(path).name}", "kind": "extended_tire", "recommended": True,
                         "role": role})
    with _timed(rep.timings, "export"):
        try:
            rep.fmus += write_recommended_files(rec, stem, rep.diagnosis, out_dir)
        except (InputError, OSError) as exc:
            rep.errors.append(f"export: {getattr(exc, 'problem', exc)}")
    with _timed(rep.timings, "figures"):
        rep.figures["diagnosis"] = png_bytes(plot_tractor_diagnosis(diag, nrmse_before=gain.nrmse_before,
                                                                    nrmse_after=gain.nrmse_after))
        rep.figures["impacts"] = png_bytes(plot_impact_zooms(diag), dpi=85)
    with _timed(rep.timings, "validate"):
        for entry in rep.fmus:
            entry["problems"] = _validate(Path(out_dir) / entry["file"])
    if len(diag.channels) == 4:
        with _timed(rep.timings, "ride"):
            from .ride import report_ride
            report_ride(rep, rec, diag, static)
    return rep


def _job(args):
    kind, *rest = args
    try:
        return diagnose_recording(*rest) if kind == "recording" else process_tire(*rest)
    except Exception as exc:  # a bug must not take the batch down; it is shown in the report
        rep = DiagnosisReport(recording=rest[1]) if kind == "recording" else TireReport(recording=rest[1],
                                                                                        tire=rest[2])
        rep.errors.append(f"internal error: {exc.__class__.__name__}: {exc}")
        return rep


def _stream_figures(rep, folder: Path) -> None:
    """Write a job result's figures into `folder` and keep only their paths (the parent's memory stays bounded)."""
    name = rep.recording if isinstance(rep, DiagnosisReport) else f"{rep.recording}_{rep.tire}"
    for key, png in list(rep.figures.items()):
        if isinstance(png, (bytes, bytearray)):
            path = folder / f"{name}_{key}.png"
            path.write_bytes(png)
            rep.figures[key] = path


def _read_all(paths, out_dir: Path, static: dict | None = None):
    """Read every recording (nothing is written): the reports, the jobs and each recording's tire order.

    Raises
    ------
    InputError
        No recording can be read (the first one's problem, and how many more failed).
    """
    from ..recording import read_recording
    from .tire_map import run_conditions

    reports, jobs, stems, order = [], [], set(), {}
    for path in paths:
        stem = Path(path).stem
        while stem in stems:
            stem += "_"
        stems.add(stem)
        try:
            rec = read_recording(path)
        except InputError as exc:
            reports.append(RecordingReport(source=str(path), stem=stem, ok=False, error=exc.problem))
            continue
        reports.append(RecordingReport(source=str(path), stem=stem, ok=True, speed_kmh=rec.speed_kmh,
                                       sample_rate_hz=rec.sample_rate_hz, wheel_load_N=dict(rec.wheel_load_N),
                                       names={k: rec.extra[k] for k in NAME_KEYS if k in rec.extra}))
        # the joint diagnoses take longest: they go first
        jobs.insert(0, ("recording", str(path), stem, str(out_dir), static))
        jobs += [("tire", str(path), stem, tire, str(out_dir)) for tire in rec.tires]
        order[stem] = list(rec.tires)
        reports[-1].conditions = run_conditions(rec)
    if reports and not jobs:
        more = f" (and {len(reports) - 1} more recording(s) that cannot be read)" if len(reports) > 1 else ""
        raise InputError(reports[0].source, reports[0].error + more)
    return reports, jobs, order


def run_batch(paths, out_dir, *, workers: int | None = None, progress: bool = True,
              scheduler: str | None = None, static: dict | None = None) -> BatchResult:
    """Process recordings into `out_dir` (fmu/, params/); the caller renders the report.

    Parameters
    ----------
    paths : list of path-like
        Recording CSV files.
    out_dir : path-like
        Output folder, created with its missing parents once the recordings are read and the executor is
        up (:func:`identification._files.make_folders`: inside an
        :class:`~identification._files.OutputFolders` block a failed run removes them again).
    workers : int, optional
        Processes (default: the machine's cores).
    progress : bool
        Progress bar on stderr, on a terminal: shown at once and redrawn every second.
    scheduler : str, optional
        Address of a Dask distributed scheduler: the jobs run on its workers
        (:class:`~identification.executors.DaskExecutor`; recordings and `out_dir` on a file system they
        share), else on `workers` local processes.  Either way each result's figures go to
        ``out_dir/.figures-staging/`` as it arrives (:func:`_stream_figures`).
    static : dict, optional
        A compression test's static stiffness (:func:`identification.report.ride.static_source`): every ride gets a ``static`` set of
        that k on all four tires.  Without it the ride has no static set.

    Returns
    -------
    BatchResult
        Every recording's report (tires in the recording's file order), the total wall time and the
        time per stage summed over the jobs.

    Raises
    ------
    InputError
        No recording can be read, an unusable scheduler, or an output folder that cannot be created;
        nothing is written then.
    """
    from .._files import make_folders

    t0 = time.perf_counter()
    out_dir = Path(out_dir)
    reports, jobs, order = _read_all(paths, out_dir, static)
    workers = max(1, min(workers or os.cpu_count() or 1, len(jobs) or 1))
    from ..executors import executor_for, ProgressBar
    figures = out_dir / FIGURES_STAGING
    results = []
    with executor_for(workers, scheduler) as executor:
        for sub in FOLDERS:
            make_folders(out_dir / sub)
        remove_staging(out_dir)
        make_folders(figures)
        with ProgressBar(len(jobs), enabled=progress) as bar:
            for rep in executor.map_unordered(_job, jobs):
                _stream_figures(rep, figures)
                results.append(rep)
                bar.update(1)
    by_stem = {r.stem: r for r in reports}
    for rep in results:
        if isinstance(rep, DiagnosisReport):
            by_stem[rep.recording].diagnosis = rep
        else:
            by_stem[rep.recording].tires.append(rep)
    for r in reports:   # results arrive in any order: the tires in the recording's file order
        r.tires.sort(key=lambda t: order[r.stem].index(t.tire))
    totals: dict = {}
    for rep in results:
        for stage, sec in rep.timings.items():
            totals[stage] = totals.get(stage, 0.0) + sec
    result = BatchResult(recordings=reports, out_dir=out_dir, seconds=time.perf_counter() - t0, timings=totals)
    from .pooled import write_campaign
    with _timed(totals, "export"):
        write_campaign(result)
    result.seconds = time.perf_counter() - t0
    return result
