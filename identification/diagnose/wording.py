"""The diagnosis' words, as every output gives them (the command line, the JSON's readers, the report).

Plain string functions over the diagnosis' JSON (:meth:`~identification.diagnose.joint_result.TractorDiagnosis.to_json`),
light to import: the report imports them without the fit's numerical code.
"""

from __future__ import annotations

__all__ = ["effects_sentence", "line_sentence", "percent"]


def percent(share: float) -> str:
    """A share as a percentage, two significant digits below 10 %, whole numbers above (never ``1e+02``)."""
    value = 100 * share
    return f"{value:.2g}" if abs(value) < 10 else f"{value:.0f}"


def line_sentence(line: dict) -> str:
    """The words for a steady line in a residual (:func:`~identification.diagnose.joint_fit.residual_line`'s dict)."""
    return (f"{percent(line['share_of_residual'])} % of that residual is a steady {line['frequency_hz']:.2f} Hz "
            f"line of {line['amplitude_m_s2']:.2g} m/s² (there before the impact too), which the model does not "
            f"explain: an engine line whose orders the sensor's filter or sampling hides, or lugs")


def effects_sentence(doc: dict) -> str:
    """What the four-corner model misses, in words: the effects named, and whether the final model still
    leaves channels above their noise floor.

    "none" alone would read as an all-clear; it is said only where every channel's residual is at its
    noise floor.  Where the model leaves channels above it, the sentence names them and the largest share
    of a channel's signal energy left, whether effects were named or not.

    Parameters
    ----------
    doc : dict
        A whole-tractor diagnosis' JSON: ``effects`` and ``tires`` (each with ``unexplained``: None or a
        dict with ``share``).
    """
    effects = list(doc.get("effects") or [])
    left = {tire: t["unexplained"] for tire, t in (doc.get("tires") or {}).items()
            if isinstance(t, dict) and t.get("unexplained")}
    if not left:
        return ", ".join(effects) if effects else \
            "none: the four-corner model explains every channel to within its noise"
    worst = max(float(v.get("share") or 0.0) for v in left.values())
    where = (f"{', '.join(left)} above the noise floor (up to {percent(worst)} % of a channel's signal "
             f"energy left)")
    if effects:
        return f"{', '.join(effects)}; the extended model still leaves {where}"
    return (f"none named, yet the four-corner model leaves {where}: something it does not model, which no "
            f"candidate effect explained")
