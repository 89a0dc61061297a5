"""A diagnosis with its gain measured by co-simulating the extended FMUs: the Python API under ``cleatfmu
diagnose`` (and the batch's), and what the diagnosis has to warn of."""

from __future__ import annotations

from ..errors import InputError
from ..recording.preprocess import DEFAULT_CUTOFF_HZ

__all__ = ["run_diagnosis", "run_tractor_diagnosis", "diagnosis_warnings"]


def run_diagnosis(rec, tire: str, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, fmu_dir=None, workers: int = 1,
                  progress=None):
    """Diagnose one tire: the joint diagnosis restricted to its channel and, when recorded, the same side's
    other axle (the pair that can tell a pitching half-tractor from two corners); (TractorDiagnosis,
    TractorGain), the tire's results under ``f"k_{tire}"``, ``f"c_{tire}"``.  The commands use the whole
    tractor (:func:`run_tractor_diagnosis`)."""
    if tire not in rec.tires:
        raise InputError(rec.source, f"tire {tire} is not in the recording (it has {', '.join(rec.tires)})")
    pair = ("R" if tire[0] == "F" else "F") + tire[1]
    channels = [t for t in rec.tires if t in (tire, pair)]
    return run_tractor_diagnosis(rec, cutoff_hz=cutoff_hz, fmu_dir=fmu_dir, workers=workers, progress=progress,
                                 channels=channels)


def run_tractor_diagnosis(rec, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, fmu_dir=None, stem: str | None = None,
                          workers: int = 1, progress=None, strict: bool = True, channels=None):
    """Diagnose every channel jointly and measure the gain with one FMU per tire: (TractorDiagnosis, TractorGain).

    With `fmu_dir` the extended FMUs are kept there as ``<stem>_<TIRE>.fmu`` (`stem`: the recording's); FMUs
    that cannot start are then an error unless `strict` is off (then none is kept, and a warning says why).
    """
    from ..fmu.tractor_cosim import measure_tractor_gain
    from .joint_select import diagnose_tractor

    diag = diagnose_tractor(rec, cutoff_hz=cutoff_hz, workers=workers, progress=progress, channels=channels)
    if progress is not None:
        progress("FMU co-simulation")
    try:
        gain = measure_tractor_gain(diag, fmu_dir, stem=stem, strict=strict)
    except OSError as exc:
        raise InputError(fmu_dir, f"cannot write: {exc.strerror or exc}") from None
    return diag, gain


#: The warning of a recording whose sidecar declares no acquisition chain (the joint fit's models then take an
#: ideal sensor; the free-decay methods do not model the chain and need none).
NO_ACQUISITION = ("the sidecar declares no acquisition chain (anti-alias filter, high-pass): the joint fit's models "
                  "take an ideal sensor, the mean acceleration over each sample; a filter they do not know leaves "
                  "a residual at the impacts (about 5x the noise on point-contact tires) and can bias k and c: "
                  "declare it under \"acquisition\" (docs/guide/recordings.md)")


def _refit_sentence(refit: dict) -> str:
    """The warning of a refit at the fitted delay's speed, with the impact onsets' speed where they confirm it
    or not (:func:`~identification.diagnose.joint_result.refit_confirmed`)."""
    from .joint_result import refit_confirmed

    delay, sidecar, onsets = refit["from_delay_m_s"], refit["sidecar_m_s"], refit.get("from_onsets_m_s")
    text = (f"the fitted front/rear delay gives {delay * 3.6:.3g} km/h, the sidecar {sidecar * 3.6:.3g} km/h "
            f"({100 * (delay / sidecar - 1):+.1f} %): fitted again at the delay's speed")
    doubt = ("a model that misfits the impacts can move its delay, and k and c were fitted at that speed (check "
             "the sidecar's speed)")
    if onsets is None:
        return text + f"; no side has both impact onsets to confirm it: {doubt}"
    if refit_confirmed(refit):
        return text + f" (the impact onsets give {onsets * 3.6:.3g} km/h)"
    return (text + f"; the impact onsets give {onsets * 3.6:.3g} km/h ({100 * (delay / onsets - 1):+.1f} % from the "
                   f"delay's), so the recording does not confirm it: {doubt}")


def diagnosis_warnings(diag, gain) -> list[str]:
    """What the diagnosis itself has to warn of (one sentence each): a cleat profile its footprint models
    approximate, the sensor signs it settled, a refit at the fitted delay's speed, a baseline whose FMUs
    could not start.  The conditioning's warnings come
    before it (:func:`identification.recording.window.focus`)."""
    from .joint_signs import AS_RECORDED, UNDONE

    out = [NO_ACQUISITION] if diag.problem.rec.acquisition is None else []
    profile = diag.problem.rec.cleat_profile
    if profile is not None and not profile.builtin_exact:
        out.append(f"a footprint model carries the cleat_profile as the trapezoid of the same height, width and "
                   f"area (bevel {profile.builtin_bevel_m * 1e3:.3g} mm); the point-contact models ride the "
                   f"profile itself")
    signs = diag.extra.get("sign_test")
    if signs and "chosen" in signs:
        chosen = signs["chosen"]
        kept = (diag.problem.rec.conditioning or {}).get("flipped")
        what = (f"the signs as the conditioning left them ({'/'.join(kept)} corrected)" if chosen == AS_RECORDED
                and kept else
                "every sensor as recorded (a pivoting axle or a carried impact)" if chosen == AS_RECORDED else
                f"{chosen.split()[0]} as recorded (the conditioning's sign correction undone: its first "
                f"excursion was carried across by the body)" if chosen.endswith(UNDONE) else
                f"{chosen} reads upside down (sign corrected)")
        out.append(f"the signs of {'/'.join(signs['open'])} tested in the joint fit: {what}, by a BIC margin of "
                   f"{signs['margin']:.1f} over the next hypothesis")
    elif signs:
        out.append(f"the signs of {'/'.join(signs['open'])} not tested: {signs['skipped']}")
    refit = diag.extra.get("speed_refit")
    if refit:
        out.append(_refit_sentence(refit))
    out += [note for note in (gain.note, gain.final_note) if note]
    for check in (diag.extra.get("free_decay") or {}).values():
        if check.get("reason"):
            out.append(check["reason"])
    return out
