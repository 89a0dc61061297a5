"""Where the linear tire law leaves its validity on a ride: tension, and lost contact with the lift-off law.

The paper's tire law is linear and bilateral: on a rough road a tire that would leave the ground pulls the
hub down instead (a negative force).  :func:`episodes` counts how often and how long each tire's force is
in tension (linear law) or zero (the law's lift-off option, ``unilateral``: the tire never pulls, and
carries no load once it has left the ground).  ``cleatfmu ride`` runs every ride with the linear law,
counts its tension, and where a tire pulls (``--tires auto``, the default) runs the ride again with the
lift-off law, whose seat acceleration is then the rating's; :func:`contact_summary` gathers a set's
counts over the road realisations and words the warning.

The warning threshold :data:`LOST_CONTACT_WARN_SHARE` (1 % of the ride on some tire): beyond it the seat's
vibration is shaped by the tire's landings, which the tire law (no tire mass; a footprint, where the
diagnosis fitted one, only averages the road) represents only roughly; ISO 8608 class D at 15 km/h already reaches 0.2-1.3 %
with the embedded day's tires, class E at 10 km/h 4-8 %.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TIRE_MODES", "LOST_CONTACT_WARN_SHARE", "episodes", "contact_summary"]

#: Values of ``ride --tires``: ``auto`` (lift-off law where the linear one pulls), ``linear``, ``lift-off``.
TIRE_MODES = ("auto", "linear", "lift-off")
#: Share of a ride a tire may be off the ground (or pulling, with the linear law) before ``ride`` warns.
LOST_CONTACT_WARN_SHARE = 0.01


def episodes(mask, step_s: float, *, force_n=None, load_n: float | None = None) -> dict:
    """How often and how long a condition holds on a sampled ride (one tire).

    Parameters
    ----------
    mask : array_like of bool
        The condition per sample (tension, or lost contact).
    step_s : float
        Sampling interval, s.
    force_n : array_like, optional
        The tire force, N (compressive positive), for the largest pull.
    load_n : float, optional
        The static wheel load, N: the largest pull is given as a multiple of it.

    Returns
    -------
    dict
        ``share`` (fraction of the samples), ``episodes`` (runs of consecutive samples), ``longest_s`` and
        ``mean_s`` (their durations, s; 0 without any), and with `force_n` and `load_n` ``largest_pull``
        (−min F / W, 0 when the force never pulls).
    """
    m = np.asarray(mask, dtype=bool)
    edges = np.diff(np.concatenate(([0], m.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    lengths = (ends - starts) * float(step_s)
    out = {"share": float(m.mean()) if m.size else 0.0, "episodes": int(starts.size),
           "longest_s": float(lengths.max()) if lengths.size else 0.0,
           "mean_s": float(lengths.mean()) if lengths.size else 0.0}
    if force_n is not None and load_n:
        out["largest_pull"] = float(max(0.0, -np.min(force_n)) / load_n)
    return out


def contact_summary(per_ride: list, tires, threshold: float = LOST_CONTACT_WARN_SHARE) -> dict:
    """A parameter set's contact over its rides on the realisations (JSON-ready).

    Parameters
    ----------
    per_ride : list of dict
        Each ride's ``contact`` (``law``, ``tension`` per tire, and ``lost_contact`` per tire when the
        lift-off law ran).
    tires : sequence of str
    threshold : float
        The share beyond which the warning is worded.

    Returns
    -------
    dict
        ``lift_off_rides`` (rides run with the lift-off law), per tire the mean and largest ``tension_share``
        (linear law), the longest tension episode and largest pull, the mean and largest
        ``lost_contact_share`` (lift-off law; a ride without tension counts 0), the longest time off the ground
        ``longest_lost_contact_s`` and the mean number of times per ride ``lost_contact_episodes`` (a ride
        without tension counts 0), and ``warning`` (one line,
        or None): the largest mean share of lost contact (or of tension, with the linear law only) above
        `threshold`.
    """
    n = len(per_ride)
    lift = [r for r in per_ride if r["law"] == "lift-off"]
    doc = {"rides": n, "lift_off_rides": len(lift), "threshold": threshold,
           "tension_share": {}, "tension_share_max": {}, "longest_tension_s": {}, "largest_pull": {},
           "lost_contact_share": {}, "lost_contact_share_max": {}, "longest_lost_contact_s": {},
           "lost_contact_episodes": {}}
    for t in tires:
        tension = [r["tension"][t]["share"] for r in per_ride]
        doc["tension_share"][t] = float(np.mean(tension))
        doc["tension_share_max"][t] = float(np.max(tension))
        doc["longest_tension_s"][t] = float(max(r["tension"][t]["longest_s"] for r in per_ride))
        doc["largest_pull"][t] = float(max(r["tension"][t].get("largest_pull", 0.0) for r in per_ride))
        lost = [r["lost_contact"][t]["share"] if "lost_contact" in r else 0.0 for r in per_ride]
        doc["lost_contact_share"][t] = float(np.mean(lost))
        doc["lost_contact_share_max"][t] = float(np.max(lost))
        landed = [r["lost_contact"][t] for r in per_ride if "lost_contact" in r]
        doc["longest_lost_contact_s"][t] = float(max((e["longest_s"] for e in landed), default=0.0))
        doc["lost_contact_episodes"][t] = float(sum(e["episodes"] for e in landed) / n) if n else 0.0
    doc["warning"] = None
    if lift:
        worst = max(tires, key=lambda t: doc["lost_contact_share"][t])
        share = doc["lost_contact_share"][worst]
        if share > threshold:
            doc["warning"] = (f"tire {worst} is off the ground {share:.1%} of the ride (lift-off law; more than "
                              f"{threshold:.0%}): landings shape the seat's vibration, which the tire law (no tire "
                              f"mass) represents only roughly")
    else:
        worst = max(tires, key=lambda t: doc["tension_share"][t])
        share = doc["tension_share"][worst]
        if share > threshold:
            doc["warning"] = (f"tire {worst} pulls the hub {share:.1%} of the ride (linear law; more than "
                              f"{threshold:.0%}): the linear tire is outside its validity, use --tires auto")
    return doc
