"""The diagnosis against the free decay alone: never worse than the simple fit it extends.

Where a hub rings as an independent corner (the diagnosis names no body coupling) with a linear tire
(no friction, no progressive stiffness: the decay's shape is then the damped sinusoid, and the fit
explains its window to R² >= :data:`MIN_DECAY_R2`), the waveform fit of its free decay
(:func:`identification.waveform.identify_waveform`) gives k and c from the part of the record that
needs the least of the model: the tire on flat ground.  The joint fit's k and c
must agree with it within their joint 95 % interval, √(h_joint² + h_decay²) (h the half-widths).
Where the joint fit's k or c lies outside the free decay's own 95 % interval, the joint fit was pulled
by what its model gets wrong in the impact (a cleat shape, a footprint, an acquisition chain): the
tire's k and c are then the free decay's (``"k_source": "free_decay"``; the extended model keeps its
own in ``parameters``, as its FMUs carry them), each interval the free decay's stretched to hold the
joint fit's estimate too, and a warning says so, by how much (and in joint half-widths where the two
intervals do not even overlap so far).  The tire's values are never further from the free decay
than its interval allows.
"""

from __future__ import annotations

import math

from ..errors import InputError
from ..preprocess import preprocess
from ..recording import STANDARD_GRAVITY
from ..waveform import identify_waveform

__all__ = ["free_decay_check", "reported", "BODY_EFFECTS", "SHAPE_EFFECTS"]

#: Named, these make the free decay a body's mode, not the tire's.
BODY_EFFECTS = ("axle_coupling", "roll_coupling", "front_axle_pivot")
#: The waveform fit must explain its window to this R² to count as the free decay of a linear corner (below
#: it: the tire still on the cleat, a progressive tire or a coupled body the diagnosis did not name).
MIN_DECAY_R2 = 0.985
#: Named, these make the decay's shape other than a damped sinusoid (a steady line rides on it).
SHAPE_EFFECTS = ("friction_damping", "nonlinear_stiffness", "periodic_disturbance")


def free_decay_check(diag) -> dict:
    """Per channel: the free decay's k and c beside the joint fit's, and whether they agree.

    Returns ``{tire: {"valid": bool, "why_not": str | None, "k", "k_ci", "c", "c_ci", "k_apart",
    "c_apart", "agree": bool, "reason": str | None}}`` (``k_apart``: |Δk| over the joint half-width).
    """
    pb = diag.problem
    rec = pb.rec
    out = {}
    named = [e for e in diag.effects if e in BODY_EFFECTS + SHAPE_EFFECTS]
    for tire in pb.channels:
        if named:
            out[tire] = {"valid": False, "why_not": f"{', '.join(named)} named: the free decay is not a "
                                                    f"linear tire's under a corner mass"}
            continue
        try:
            sig = preprocess(rec, [tire], cutoff_hz=pb.cutoff_hz, min_peaks=1)[tire]
            wave = identify_waveform(sig, rec.wheel_load_N[tire] / STANDARD_GRAVITY, source=rec.source)
        except InputError as exc:
            out[tire] = {"valid": False, "why_not": f"no waveform fit: {exc.problem}"}
            continue
        if not wave.r2 >= MIN_DECAY_R2:   # a forced response, a progressive or a coupled hub: no damped sinusoid
            out[tire] = {"valid": False, "why_not": f"the free decay is no damped sinusoid (R² {wave.r2:.3f} < "
                                                    f"{MIN_DECAY_R2})"}
            continue
        fin = diag.final
        entry = {"valid": True, "why_not": None, "k": float(wave.k), "c": float(wave.c),
                 "k_ci": [float(v) for v in wave.k_ci], "c_ci": [float(v) for v in wave.c_ci]}
        sentences = []
        for q in ("k", "c"):
            est, (lo, hi) = fin.params[f"{q}_{tire}"], fin.ci[f"{q}_{tire}"]
            h_joint = max(est - lo, hi - est) if math.isfinite(hi) else math.inf
            h_decay = (entry[f"{q}_ci"][1] - entry[f"{q}_ci"][0]) / 2
            joint = math.hypot(h_joint, h_decay)
            apart = abs(est - entry[q]) / joint if joint > 0 else math.inf
            entry[f"{q}_apart"] = float(apart)
            entry[f"{q}_outside_decay"] = bool(not (entry[f"{q}_ci"][0] <= est <= entry[f"{q}_ci"][1]))
            if apart > 1:
                sentences.append(f"{q} {100 * (est / entry[q] - 1):+.1f} % from the free decay's "
                                 f"({apart:.1f} joint half-widths)")
        entry["agree"] = not sentences
        entry["prefer"] = entry["k_outside_decay"] or entry["c_outside_decay"]
        entry["reason"] = None
        if sentences:
            left = diag.unexplained.get(tire)
            where = (f"it leaves {left['share']:.0%} of the signal unexplained in {left['window'][0]:.2f}-"
                     f"{left['window'][1]:.2f} s" if left else "its residual is at the noise floor, so the "
                                                                 "decay's own model may be the one that misses")
            entry["reason"] = (f"{tire}: the joint fit's {' and '.join(sentences)}: the impact pulls the joint "
                               f"fit ({where})")
        if entry["prefer"]:
            entry["reason"] = ((entry["reason"] + "; ") if entry["reason"] else f"{tire}: ") + \
                (f"k and c are the free decay's (k {entry['k'] / 1e3:.1f} kN/m, c {entry['c'] / 1e3:.3f} kN s/m): "
                 f"the joint fit's lie outside its interval (k {100 * (fin.params[f'k_{tire}'] / entry['k'] - 1):+.1f} "
                 f"%, c {100 * (fin.params[f'c_{tire}'] / entry['c'] - 1):+.1f} %), which is stretched to hold them")
        out[tire] = entry
    return out


def reported(value: float, ci, check: dict, q: str) -> tuple[float, list]:
    """The tire's value and interval of quantity `q` ('k' or 'c'): the joint fit's, or, where the joint fit's k
    or c lies outside the free decay's interval, the free decay's with its interval stretched to hold the
    joint fit's estimate too."""
    if not check.get("valid") or not check.get("prefer"):
        return float(value), [float(v) for v in ci]
    lo, hi = check[f"{q}_ci"]
    return float(check[q]), [float(min(value, lo)), float(max(value, hi))]
