"""Sensor signs the conditioning could not settle, settled by the joint fit.

The conditioning (:mod:`identification.recording.condition`) reads a channel's sign from the first excursion of
its own impact.  Two cases are left open there:

* ``flip_ambiguous``: the two front channels start their impacts together with opposite signs and
  comparable sizes.  Either one sensor reads upside down while both wheels hit the cleat together, or a
  pivoting front axle carried one wheel's impact across to the other (the whole of it, opposite in
  sign);
* ``sign_undetermined``: no quiet stretch precedes a channel's impact (a steady vibration that never
  stops), so its first excursion has no sign.

* a channel the conditioning flipped whose diagnosis leaves it largely unexplained: at a staggered
  cleat the body carries the first side's impact to the other hub (opposite in sign) before that hub's
  own, slower impact (a footprint) rises; its "first excursion" is then the carried one (seen on the
  project's own rig: a rigid tractor, 0.27 m stagger, 0.33 m footprint, FL flipped and k 240 % off).

Only a model of the whole tractor tells these apart: the body, the pivot and the four tires must
explain all channels at once.  :func:`settle_signs` diagnoses the recording as recorded and with each
open channel's sign reversed (one at a time; an undetermined channel only when the first diagnosis
leaves it largely unexplained) and keeps the hypothesis of the lowest BIC; the others are reported
beside it (``extra["sign_test"]``), so the choice can be checked.
"""

from __future__ import annotations

import math
from dataclasses import replace

__all__ = ["open_signs", "with_sign_reversed", "with_flip_undone", "settle_signs", "UNDONE", "MAX_OPEN", "SUSPECT_SHARE", "PAIR_SHARE",
           "AS_RECORDED"]

#: At most this many open channels are tested (one diagnosis each, plus the recording as it is).
MAX_OPEN = 3
#: A channel of undetermined sign is tested reversed when the diagnosis as recorded leaves more than this
#: share of its signal unexplained.
SUSPECT_SHARE = 0.3
#: An ambiguous front pair is tested when the diagnosis as recorded leaves more than this share of either
#: channel's signal unexplained (measured: a pivot explained as recorded leaves 1e-5; a sensor upside
#: down 0.15-1.0 on one of the pair, whatever body the selection tried).
PAIR_SHARE = 0.05
#: The label of the hypothesis that every sign is as recorded (as conditioned).
AS_RECORDED = "as recorded"
#: A hypothesis ``"<channel> flip undone"``: the conditioning's sign correction of that channel undone.
UNDONE = "flip undone"


def open_signs(rec) -> tuple[list[str], list[str]]:
    """The channels whose sign the conditioning left open: (ambiguous, undetermined), in recording order."""
    doc = rec.conditioning or {}
    return ([c for c in rec.tires if c in doc.get("flip_ambiguous", [])],
            [c for c in rec.tires if c in doc.get("sign_undetermined", [])])


def _negated(rec, channel: str, flipped: list, warnings: list):
    """`rec` with `channel`'s acceleration negated and its conditioning's ``flipped`` and ``warnings`` replaced,
    no longer listing the channels it left open."""
    doc = dict(rec.conditioning or {})
    doc["flipped"], doc["warnings"] = flipped, warnings
    doc.pop("flip_ambiguous", None)
    doc.pop("sign_undetermined", None)
    accel = {c: (-x if c == channel else x) for c, x in rec.accel_m_s2.items()}
    return replace(rec, accel_m_s2=accel, conditioning=doc)


def with_sign_reversed(rec, channel: str, reason: str):
    """`rec` with `channel`'s acceleration negated, its conditioning saying so (``flipped``) and no longer
    listing the channels it left open."""
    doc = rec.conditioning or {}
    return _negated(rec, channel, [*doc.get("flipped", []), channel],
                    [*doc.get("warnings", []), f"channel {channel}: {reason}; sign corrected"])


def with_flip_undone(rec, channel: str):
    """`rec` with the conditioning's sign correction of `channel` undone (the channel as recorded)."""
    doc = rec.conditioning or {}
    kept = [w for w in doc.get("warnings", []) if not (w.startswith(f"channel {channel}: ")
                                                       and w.endswith("sign corrected"))]
    return _negated(rec, channel, [c for c in doc.get("flipped", []) if c != channel],
                    kept + [f"channel {channel}: the joint fit explains the channels best with this sensor as "
                            f"recorded (its impact's first excursion was carried across by the body): the "
                            f"conditioning's sign correction undone"])


def _bic(diag) -> float:
    """The BIC of a diagnosis' final model (as the forward selection counts it)."""
    pb, fin = diag.problem, diag.final
    n = int(pb.window.sum()) * len(pb.channels)
    return diag.extra["n_eff"] * math.log(fin.weighted_sse() / n) + len(fin.model.names) * math.log(
        diag.extra["n_eff"])


def _suspect(diag, channel: str, share: float) -> bool:
    """Whether the diagnosis leaves more than `share` of the channel's signal unexplained."""
    left = diag.unexplained.get(channel)
    return left is not None and left["share"] > share


def settle_signs(rec, diagnose_once, tick=None):
    """The diagnosis of `rec` under the sign hypothesis of the lowest BIC, where the conditioning left one open.

    The recording is diagnosed as recorded first.  The hypotheses tested beside it, one diagnosis each,
    reverse one channel: each of an ambiguous front pair when the diagnosis as recorded leaves more than
    :data:`PAIR_SHARE` of either's signal unexplained (a pivoting axle it explains is left alone), each
    channel of undetermined sign that it leaves with more than :data:`SUSPECT_SHARE` unexplained
    (a rear channel whose impact rises out of the body's motion is undetermined but usually explained),
    and each channel the conditioning flipped that it leaves with more than :data:`SUSPECT_SHARE`
    unexplained (that flip undone: ``"<channel> flip undone"``).

    Parameters
    ----------
    rec : Recording
        Focused and conditioned.
    diagnose_once : callable
        ``diagnose_once(rec) -> TractorDiagnosis``: one forward selection.
    tick : callable, optional
        ``tick(label)`` before each hypothesis tested.

    Returns
    -------
    TractorDiagnosis
        With ``extra["sign_test"]`` when hypotheses were tested: the open channels, each hypothesis' BIC,
        the chosen one (a channel name, or :data:`AS_RECORDED`) and its margin over the next best; or, when
        more than :data:`MAX_OPEN` channels were open, ``"skipped"`` saying why.
    """
    ambiguous, undetermined = open_signs(rec)
    tick = tick or (lambda label: None)
    first = diagnose_once(rec)
    if not any(_suspect(first, c, PAIR_SHARE) for c in ambiguous):
        ambiguous = []          # the signs as recorded explain the pair (a pivoting axle): nothing to test
    channels = ambiguous + [c for c in undetermined if c not in ambiguous and _suspect(first, c, SUSPECT_SHARE)]
    flipped = [c for c in rec.tires if c in (rec.conditioning or {}).get("flipped", [])]
    undo = [c for c in flipped if c not in channels and _suspect(first, c, SUSPECT_SHARE)]
    if not channels and not undo:
        return first
    if len(channels) + len(undo) > MAX_OPEN:
        first.extra["sign_test"] = {"open": channels + undo, "skipped": f"{len(channels) + len(undo)} channels "
                                                                        f"open, more than {MAX_OPEN}: left as "
                                                                        f"conditioned"}
        return first
    runs = {AS_RECORDED: first}
    for c in channels:
        tick(f"signs: {c} reversed")
        reason = ("the joint fit explains the channels best with this sensor read upside down (its impact's "
                  "first excursion could not tell)")
        runs[c] = diagnose_once(with_sign_reversed(rec, c, reason))
    for c in undo:
        tick(f"signs: {c} as recorded")
        runs[f"{c} {UNDONE}"] = diagnose_once(with_flip_undone(rec, c))
    bic = {label: float(_bic(d)) for label, d in runs.items()}
    order = sorted(bic, key=bic.get)
    chosen = runs[order[0]]
    chosen.extra["sign_test"] = {"open": channels + undo, "bic": bic, "chosen": order[0],
                                 "margin": float(bic[order[1]] - bic[order[0]])}
    return chosen
