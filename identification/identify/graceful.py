"""Identification that degrades gracefully: what the data can give when the paper's rules are not met.

The paper's method needs, per channel, three free-vibration peaks above the noise, a second peak
smaller than the first and decaying peaks (:func:`identification.identify.paper.identify_paper`).  A
recording is often partly outside these rules (a tire damped so much that two peaks stand above the
noise, a rear hub still ringing from the front axle's impact).  :func:`identify_channels` then says,
per channel, which rule was not met and still gives what can be given: the waveform fit
(:func:`identification.identify.waveform.identify_waveform`) on the free decay there is, with its own 95 %
interval (wider, as fewer samples carry the decay), and points to ``cleatfmu diagnose``, which fits the
whole response of every channel.

Data that no method can use (a clipped channel, no impact, values beyond a hub's acceleration) are
still refused as the recording's problem (:class:`identification.errors.InputError`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..errors import InputError
from .paper import identify_paper
from ..recording.preprocess import DEFAULT_CUTOFF_HZ, preprocess
from ..recording import Recording

__all__ = ["Refusal", "identify_channels", "is_rule", "ADVICE"]

#: Where the paper's rules are not met, the analysis that uses every channel's whole response.
ADVICE = "cleatfmu diagnose fits every channel's whole response (impact and decay) under one body"

#: Refusals that are the paper's rules (the method's limits), not the data's defects.
_RULES = ("fewer than", "is not smaller than", "do not decay", "no free vibration between",
          "free-decay window too short", "no free-vibration peak", "no decaying oscillation", "did not converge",
          "no finite stiffness")


def is_rule(exc: InputError) -> bool:
    """Whether `exc` refuses a channel by a rule of the method (rather than for defective data)."""
    return any(r in exc.problem for r in _RULES)


@dataclass(frozen=True)
class Refusal:
    """A channel the requested method refused, and what could be given instead.

    Attributes
    ----------
    tire : str
    rule : str
        The rule not met, as a sentence naming the channel.
    fallback : WaveformResult or None
        The waveform fit on the free decay there is (None when even that failed).
    fallback_problem : str or None
        Why there is no fallback.
    """

    tire: str
    rule: str
    fallback: object | None = None
    fallback_problem: str | None = None

    def to_json(self) -> dict:
        return {"refused": self.rule,
                "fallback": None if self.fallback is None else dict(self.fallback.to_json(), method="waveform"),
                "fallback_problem": self.fallback_problem, "advice": ADVICE}

    def sentence(self) -> str:
        """One line for the text output."""
        if self.fallback is not None:
            f = self.fallback
            what = (f"waveform fit on the decay there is ({f.n_peaks} peak{'s' if f.n_peaks != 1 else ''}): "
                    f"K {f.k / 1e3:.2f} kN/m ({f.k_ci[0] / 1e3:.2f} .. {f.k_ci[1] / 1e3:.2f}), "
                    f"C {f.c / 1e3:.3f} kNs/m ({f.c_ci[0] / 1e3:.3f} .. {f.c_ci[1] / 1e3:.3f}) [95 %]")
        else:
            what = f"no waveform fit either ({self.fallback_problem})"
        return f"{self.tire}: not identified: {self.rule}; {what}; {ADVICE}"


def _problem(exc: InputError, tire: str) -> str:
    """The message of `exc` without its leading ``channel XX:``."""
    text = exc.problem
    prefix = f"channel {tire}: "
    return text[len(prefix):] if text.startswith(prefix) else text


def identify_channels(rec: Recording, tires=None, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                      method: str = "paper") -> dict:
    """Identify every requested channel; a channel outside the method's rules gets a :class:`Refusal`.

    Parameters
    ----------
    rec : Recording
    tires : sequence of str, optional
        Channels (default: all, in file order).
    cutoff_hz : float
        Low-pass cut-off, Hz.
    method : {"paper", "waveform"}

    Returns
    -------
    dict of str to PaperResult, WaveformResult or Refusal
        In the order of `tires`.

    Raises
    ------
    InputError
        Defective data (clipped, no impact, ...), or a cut-off not below Nyquist.
    """
    from .waveform import decay_misfit, identify_waveform
    from ..recording.window import focus, window_json

    if method not in ("paper", "waveform"):
        raise ValueError(f"unknown method {method!r}")
    rec = focus(rec, cutoff_hz=cutoff_hz, single_line=True)
    tires = list(rec.tires if tires is None else tires)
    window = window_json(rec)
    try:
        signals = preprocess(rec, tires, cutoff_hz=cutoff_hz, min_peaks=1)
    except InputError as exc:
        if not is_rule(exc):
            raise
        signals = {}
        for tire in tires:      # find the channels the rule refuses; the others are analysed as usual
            try:
                signals.update(preprocess(rec, [tire], cutoff_hz=cutoff_hz, min_peaks=1))
            except InputError as one:
                if not is_rule(one):
                    raise
                signals[tire] = Refusal(tire, _problem(one, tire), None, "no free decay to fit")
    out: dict = {}
    for tire in tires:
        sig = signals[tire]
        if isinstance(sig, Refusal):
            out[tire] = sig
            continue
        mass = rec.mass_kg(tire)
        try:
            if method == "paper":
                out[tire] = replace(identify_paper(sig, mass, source=rec.source, window=window),
                                    decay_misfit=decay_misfit(sig, mass))
            else:
                out[tire] = identify_waveform(sig, mass, source=rec.source, window=window)
            continue
        except InputError as exc:
            if not is_rule(exc):
                raise
            rule = _problem(exc, tire)
        fallback, problem = None, None
        if method == "paper":
            try:
                fallback = identify_waveform(sig, mass, source=rec.source, window=window)
            except InputError as exc:
                problem = _problem(exc, tire)
        else:
            problem = "the waveform fit is the fallback"
        out[tire] = Refusal(tire, rule, fallback, problem)
    return out

