"""Road input of the virtual rig: the cleat (point contact or enveloped) and lug passing.

The vertical road input r_i(t) (m) under tire i is the cleat height averaged
over the tire footprint, weighted by a parabolic contact-pressure
distribution of length ℓ:

    r(s) = H · [P(w − s) − P(−s)],   P = cumulative pressure distribution,

where s = v (t − t_i) is the position of the contact centre past the cleat's
leading edge and w the cleat width.  With ℓ = 0 this is the paper's point
contact: a rectangular pulse of height H and duration w / v, whose edges are
steps (the damper then delivers an impulse c·ΔH, handled by the solver).
With ℓ > 0 the tire feels the cleat for (ℓ + w) / v, and never a step.

Lug passing adds A sin(2π f t + φ) per tire (periodic_disturbance).

A cleat `profile` other than the rectangle (:class:`identification.recording.cleat.CleatProfile`, bevelled or
piecewise linear) replaces the pulse: under a point contact the road is the profile itself (steps
only at its vertical edges, a finite rate v dz/dx on its slopes), under a footprint its parabolic
average (:meth:`~identification.recording.cleat.CleatProfile.averaged`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RoadInput"]


class RoadInput:
    """Road height and rate under the four tires.

    Parameters
    ----------
    arrival_s : array_like, shape (4,)
        Time the contact centre of each tire reaches its cleat's leading edge, s.
    speed_m_s, height_m, width_m : float
        Driving speed, cleat height and width.
    footprint_m : array_like, shape (4,)
        Footprint length per tire, m (0: point contact).
    lug_amplitude_m : float
        Lug-passing amplitude, m (0: none).
    lug_frequency_hz, lug_phase_rad : array_like, shape (4,)
    profile : CleatProfile, optional
        The cleat's cross-section when not the rectangle of `height_m` x `width_m`.
    """

    def __init__(self, arrival_s, speed_m_s, height_m, width_m, footprint_m,
                 lug_amplitude_m=0.0, lug_frequency_hz=(0, 0, 0, 0), lug_phase_rad=(0, 0, 0, 0), profile=None):
        self.arrival = np.asarray(arrival_s, dtype=float)
        self.v, self.h, self.w = float(speed_m_s), float(height_m), float(width_m)
        self.fp = np.asarray(footprint_m, dtype=float)
        self._env = np.flatnonzero(self.fp > 0)
        self._pc = np.flatnonzero(self.fp <= 0)
        self.lug_a = float(lug_amplitude_m)
        self.lug_w = 2 * np.pi * np.asarray(lug_frequency_hz, dtype=float)
        self.lug_phi = np.asarray(lug_phase_rad, dtype=float)
        self.profile = None if profile is None or profile.is_rectangular else profile

    def __call__(self, t, t_mid=None):
        """Road height (m) and rate (m/s), arrays of shape (4, len(t)); steps excluded from the rate.

        `t_mid` (scalar or like `t`) is a time inside the same step-free interval
        as `t`: the point-contact pulse is evaluated there, so that an interval
        ending exactly on a step sees the value it had inside.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        s = self.v * (t[None, :] - self.arrival[:, None])
        r = np.zeros_like(s)
        rd = np.zeros_like(s)
        env, pc = self._env, self._pc
        if self.profile is not None:
            for i in env:
                r[i], rd[i] = self.profile.averaged(s[i], self.fp[i])
                rd[i] *= self.v
            for i in pc:
                s_pc = s[i]
                if t_mid is not None:   # at a vertical edge ending the interval: the value inside it
                    toward = np.sign(np.broadcast_to(t_mid, t.shape) - t)
                    s_pc = s_pc + toward * 1e-9 * self.profile.width_m
                r[i] = self.profile.height(s_pc)
                rd[i] = self.v * self.profile.slope(s_pc)
            env = pc = np.array([], dtype=int)
        if env.size:
            # Parabolic pressure over the footprint: P(z) = 1/2 + 3/4 (u - u³/3), u = clip(2z/ℓ, -1, 1),
            # density 3/(2ℓ) (1 - u²); both evaluated at z = w - s and z = -s.
            length = self.fp[env][:, None]
            se = s[env]
            u1 = np.clip(2.0 * (self.w - se) / length, -1.0, 1.0)
            u0 = np.clip(-2.0 * se / length, -1.0, 1.0)
            r[env] = 0.75 * self.h * ((u1 - u1 ** 3 / 3.0) - (u0 - u0 ** 3 / 3.0))
            rd[env] = 1.5 * self.v * self.h / length * (u1 * u1 - u0 * u0)
        if pc.size:
            s_pc = s[pc] if t_mid is None else \
                self.v * (np.broadcast_to(t_mid, t.shape)[None, :] - self.arrival[pc][:, None])
            r[pc] = np.where((s_pc >= 0) & (s_pc < self.w), self.h, 0.0)
        if self.lug_a:
            ph = self.lug_w[:, None] * t[None, :] + self.lug_phi[:, None]
            r += self.lug_a * np.sin(ph)
            rd += self.lug_a * self.lug_w[:, None] * np.cos(ph)
        return r, rd

    def steps(self):
        """Point-contact road steps: list of (time s, tire index, height change m)."""
        out = []
        for i, length in enumerate(self.fp):
            if length <= 0:
                if self.profile is not None:
                    out += [(self.arrival[i] + x / self.v, i, dz) for x, dz in self.profile.steps()]
                else:
                    out += [(self.arrival[i], i, self.h), (self.arrival[i] + self.w / self.v, i, -self.h)]
        return out

    def excitation_interval(self, i: int) -> tuple[float, float]:
        """Time span in which tire i feels the cleat, s."""
        half = self.fp[i] / 2 / self.v
        return float(self.arrival[i] - half), float(self.arrival[i] + self.w / self.v + half)

    def breakpoints(self):
        """Times where the road input or its derivatives are not smooth, s (sorted)."""
        pts = set()
        xs = self.profile.vertices() if self.profile is not None else [0.0, self.w]
        for i, length in enumerate(self.fp):
            half = length / 2 / self.v
            for x in xs:
                at = self.arrival[i] + x / self.v
                pts.update((at - half, at + half) if length > 0 else (at,))
        return sorted(pts)
