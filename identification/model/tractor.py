"""The model record of a cleat run: body, tires, cleat and arrivals, built once and used by every stage.

Body
----
The hubs' vertical displacements from their static heights are u = J q for
generalized coordinates q with a diagonal mass matrix M; the tire forces F
(compressive positive, N) act through Jᵀ:  M q̈ = Jᵀ (F − W),  W the static
wheel loads.  The body is chosen by two couplings and the front-axle design:

==========================  =====================================================
couplings                   body
==========================  =====================================================
none                        four independent corners, q = u, M = diag(W / g)
``axle_coupling`` (pitch)   one half-tractor per side: heave and pitch
``roll_coupling`` (roll)    one axle pair per axle: heave and roll
both                        the rigid tractor: heave z, pitch θ, roll; with
                            ``front_axle_pivot`` also the front axle's roll
==========================  =====================================================

The centre of gravity follows from the static loads: a = L W_rear / ΣW behind
the front axle, b = L − a ahead of the rear one; the pitch inertia is
ρ_p M a b (ρ_p the **pitch dynamic index**; at ρ_p = 1 front and rear decouple).

**Why the track width need not be known.**  Roll enters only through the hub
displacements (s_i t/2 − y_cg) φ (s_i = +1 left, −1 right) and the roll
inertia I_r.  With the roll coordinate scaled by the half-track, w = (t/2) φ,
the displacements are (s_i − ȳ) w with ȳ = y_cg / (t/2) = Σ s_i W_i / ΣW (from
the loads alone), and the kinetic energy is I_r φ̇²/2 = ρ_r M ẇ²/2 with
ρ_r = I_r / (M (t/2)²), the **roll dynamic index**: t appears nowhere else.

**Pivoting front axle.**  The front axle rolls about a longitudinal pivot at
the track centre and carries no roll moment to the body: the pivot moves with
the body (z + a θ − ȳ w), the front hubs by ± u about it, with u = (t/2) ψ the
axle's scaled absolute roll and mass ρ_a m_f (ρ_a = I_a / (m_f (t/2)²) the
**front-axle roll index**, m_f = (W_FL + W_FR) / g).  The front tires then load
the body only through their sum; their difference rolls the axle.

Cleat and arrivals
------------------
Each tire meets its cleat (height H, width w) at its own arrival time; a
point-contact tire sees the rectangular pulse under its contact point (the
road input), a tire with a footprint knows the cleat itself and gets its
longitudinal position x = v (t − arrival).  An edge between grid points is
represented on the grid by the one point within half a step of it, with the
road at the fraction of H reached over a ramp of one step centred on the edge
and the rate ±H/h there, so the damper's impulse is exactly c H and the edge
time is a continuous parameter of the model.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from . import tire_law
from ..recording import FRONT_TIRES, STANDARD_GRAVITY, TIRES

__all__ = ["Body", "Cleat", "TractorModel", "Inputs", "cleat_inputs", "LEFT_TIRES", "side_sign"]

LEFT_TIRES = ("FL", "RL")


def side_sign(tire: str) -> float:
    """+1 for a left tire, −1 for a right one."""
    return 1.0 if tire in LEFT_TIRES else -1.0


@dataclass(frozen=True)
class Body:
    """The body the tires carry (see the module docstring).

    Parameters
    ----------
    tires : tuple of str
        The tires modelled, in :data:`identification.recording.TIRES` order.
    loads_n : tuple of float
        Static wheel loads, N, per tire.
    wheelbase_m : float
    pitch, roll, pivot : bool
        ``axle_coupling``, ``roll_coupling``, ``front_axle_pivot``.
    pitch_index, roll_index, pivot_index : float
        Dynamic indices ρ_p, ρ_r, ρ_a.
    """

    tires: tuple
    loads_n: tuple
    wheelbase_m: float
    pitch: bool = False
    roll: bool = False
    pivot: bool = False
    pitch_index: float = 1.0
    roll_index: float = 1.0
    pivot_index: float = 0.05

    def __post_init__(self):
        if list(self.tires) != [t for t in TIRES if t in self.tires] or not self.tires:
            raise ValueError(f"tires must be a non-empty subset of {TIRES} in that order, got {self.tires}")
        if len(self.loads_n) != len(self.tires) or not all(w > 0 for w in self.loads_n):
            raise ValueError("one positive static load per tire is needed")
        if (self.pitch and self.roll or self.pivot) and len(self.tires) != 4:
            raise ValueError("the rigid tractor (pitch and roll coupling, or a pivoting front axle) needs all "
                             "four tires")
        if self.pivot and not (self.pitch and self.roll):
            raise ValueError("a pivoting front axle needs the rigid tractor (pitch and roll coupling)")
        for name in ("pitch_index", "roll_index", "pivot_index"):
            if not (getattr(self, name) > 0 and math.isfinite(getattr(self, name))):
                raise ValueError(f"{name} must be finite and > 0, got {getattr(self, name)!r}")

    @property
    def kind(self) -> str:
        """``corners``, ``sides``, ``axles``, ``rigid`` or ``pivot``."""
        if self.pivot:
            return "pivot"
        if self.pitch and self.roll:
            return "rigid"
        return "sides" if self.pitch else "axles" if self.roll else "corners"

    def _load(self, tire):
        return self.loads_n[self.tires.index(tire)]

    def _groups(self):
        """Tires grouped into independent bodies (pairs or single corners)."""
        if self.pitch and not self.roll:
            pairs = (("FL", "RL"), ("FR", "RR"))
        elif self.roll and not self.pitch:
            pairs = (("FL", "FR"), ("RL", "RR"))
        else:
            pairs = ()
        groups, done = [], set()
        for pair in pairs:
            if all(t in self.tires for t in pair):
                groups.append(pair)
                done.update(pair)
        groups += [(t,) for t in self.tires if t not in done]
        return groups

    def decoupled_roll_indices(self) -> list:
        """Per axle pair of a body of axle pairs (``roll`` without ``pitch``), the roll index at which its two
        wheels move as independent corners of mass W/g: 1 - ybar^2 (ybar = (W_l - W_r) / (W_l + W_r), the
        roll coordinate's offset below)."""
        if not self.roll or self.pitch:
            raise ValueError("decoupling roll indices exist for a body of axle pairs (roll without pitch)")
        out = []
        for group in self._groups():
            if len(group) == 2:
                w0, w1 = self._load(group[0]), self._load(group[1])
                out.append(1.0 - ((w0 - w1) / (w0 + w1)) ** 2)
        return out

    def matrices(self):
        """(J, mass, coordinates): hub displacement per coordinate (tires × q), diagonal masses, names."""
        try:                                   # (a fit builds the same body for many model runs)
            J, mass, names = _matrices(self)
        except TypeError:                      # unhashable fields (lists): not cached
            J, mass, names = self._matrices()
        return J.copy(), mass.copy(), names

    def _matrices(self):
        g = STANDARD_GRAVITY
        n_t = len(self.tires)
        row = {t: i for i, t in enumerate(self.tires)}
        if self.kind in ("rigid", "pivot"):
            W = np.array(self.loads_n, dtype=float)
            total = W.sum()
            s = np.array([side_sign(t) for t in self.tires])
            front = np.array([t in FRONT_TIRES for t in self.tires])
            a = self.wheelbase_m * W[~front].sum() / total
            b = self.wheelbase_m - a
            ybar = float((s * W).sum() / total)
            mass = total / g
            cols = [np.ones(4), np.where(front, a, -b), s - ybar]
            masses = [mass, self.pitch_index * mass * a * b, self.roll_index * mass]
            names = ["heave", "pitch", "roll"]
            if self.pivot:
                cols[2] = np.where(front, -ybar, s - ybar)
                cols.append(np.where(front, s, 0.0))
                masses.append(self.pivot_index * W[front].sum() / g)
                names.append("front_axle_roll")
            return np.column_stack(cols), np.array(masses), tuple(names)
        J = np.zeros((n_t, 0))
        masses, names = [], []
        for group in self._groups():
            if len(group) == 1:
                col = np.zeros((n_t, 1))
                col[row[group[0]], 0] = 1.0
                J = np.hstack([J, col])
                masses.append(self._load(group[0]) / g)
                names.append(f"corner_{group[0]}")
                continue
            w0, w1 = self._load(group[0]), self._load(group[1])
            m = (w0 + w1) / g
            cols = np.zeros((n_t, 2))
            cols[row[group[0]], 0] = cols[row[group[1]], 0] = 1.0
            if self.pitch:   # a side: front then rear; coordinate pitch θ nose-up
                a = self.wheelbase_m * w1 / (w0 + w1)
                b = self.wheelbase_m - a
                cols[row[group[0]], 1], cols[row[group[1]], 1] = a, -b
                masses += [m, self.pitch_index * m * a * b]
                names += [f"heave_{group[0][1]}", f"pitch_{group[0][1]}"]
            else:            # an axle: left then right; coordinate roll scaled by the half-track
                ybar = (w0 - w1) / (w0 + w1)
                cols[row[group[0]], 1], cols[row[group[1]], 1] = 1.0 - ybar, -1.0 - ybar
                masses += [m, self.roll_index * m]
                names += [f"heave_{group[0][0]}", f"roll_{group[0][0]}"]
            J = np.hstack([J, cols])
        return J, np.array(masses), tuple(names)


_matrices = functools.lru_cache(maxsize=64)(Body._matrices)


@dataclass(frozen=True)
class Cleat:
    """The cleat: height and width (m) in the driving direction, crossed at `speed_m_s`, and its cross-section
    (:class:`identification.recording.cleat.CleatProfile`; None: rectangular)."""

    height_m: float
    width_m: float
    speed_m_s: float
    profile: object = None

    @classmethod
    def of(cls, rec) -> "Cleat":
        """The cleat of recording `rec`, crossed at its speed."""
        return cls(rec.cleat_height_m, rec.cleat_width_m, float(rec.speed_m_s), rec.cleat_profile)

    @property
    def duration_s(self) -> float:
        return self.width_m / self.speed_m_s


@dataclass(frozen=True, eq=False)
class Inputs:
    """Per-grid-point inputs of every tire (arrays tires × n) and the point-contact edges.

    ``road_vz`` is the road's rate: at an edge point (``edge_mask``) the ramp's rate ±H/h, which the
    stepping applies as a velocity jump; elsewhere the rate of a smooth road (zero around a cleat).
    """

    road_z: np.ndarray
    road_vz: np.ndarray
    hub_x: np.ndarray
    hub_vx: np.ndarray
    edges: tuple          # ((grid index, tire index, edge time s), ...)

    @property
    def edge_points(self) -> np.ndarray:
        return np.array(sorted({i for i, _, _ in self.edges}), dtype=np.int64)

    @property
    def edge_mask(self) -> np.ndarray:
        """True where a tire's grid point holds one of its edges (tires × n): there `road_vz` is the ramp's
        rate, applied as an impulse; elsewhere it is the smooth road's rate (zero on a cleat)."""
        mask = np.zeros(self.road_z.shape, dtype=np.bool_)
        for i, j, _ in self.edges:
            mask[j, i] = True
        return mask


def cleat_inputs(start_s: float, step_s: float, n: int, *, arrival_s: float, cleat: Cleat, external: bool,
                 x_offset_m: float = 0.0):
    """Road height, rate and longitudinal position of one tire on the grid start + i h.

    Returns (road_z, road_vz, hub_x, hub_vx, edges) with edges [(grid index,
    edge time)].  With `external` the rectangular cleat is the road under the
    contact point (each edge on the one grid point within half a step of it, see
    the module docstring); otherwise the road is flat and x = v (t − arrival) +
    `x_offset_m` lets the tire place its own cleat.
    """
    t = start_s + step_s * np.arange(n)
    road = np.zeros(n)
    rate = np.zeros(n)
    edges = _cleat_road(road, rate, t, start_s, step_s, arrival_s=arrival_s, cleat=cleat) if external else []
    x = cleat.speed_m_s * (t - arrival_s) + x_offset_m
    return road, rate, x, np.full(n, float(cleat.speed_m_s)), edges


def _cleat_road(road, rate, t, start_s: float, step_s: float, *, arrival_s: float, cleat: Cleat) -> list:
    """Write the cleat into one tire's zeroed road height and rate rows; its edges [(index, time)]."""
    n = road.size
    if cleat.profile is not None and not cleat.profile.is_rectangular:
        road[:], rate[:], edges = cleat.profile.on_grid(t, arrival_s=arrival_s, speed_m_s=cleat.speed_m_s,
                                                        step_s=step_s)
        return edges
    edges = []
    H = cleat.height_m
    if H:
        t_up, t_down = arrival_s, arrival_s + cleat.duration_s
        i_up = int(math.floor((t_up - start_s) / step_s + 0.5))
        i_down = int(math.floor((t_down - start_s) / step_s + 0.5))
        lo, hi = max(i_up + 1, 0), max(min(i_down, n), 0)
        road[lo:hi] = H
        for i_e, t_e, sign in ((i_up, t_up, 1.0), (i_down, t_down, -1.0)):
            if 0 <= i_e < n:
                frac = (t[i_e] - t_e) / step_s + 0.5          # ramp of one step centred on the edge
                road[i_e] = H * frac if sign > 0 else H * (1.0 - frac)
                rate[i_e] += sign * H / step_s
                edges.append((i_e, t_e))
        if i_up == i_down and 0 <= i_up < n:                     # a cleat shorter than one step
            road[i_up] = 0.0
    return edges


@dataclass(frozen=True, eq=False)
class TractorModel:
    """The model record: body, one extended tire law per tire, the cleat and each tire's arrival.

    Parameters
    ----------
    body : Body
    laws : tuple of dict
        Extended tire-law parameters per tire (see
        :data:`identification.model.tire_law.EXTENDED_DEFAULTS`); a law with a
        built-in cleat (``cleat_height`` > 0) places the cleat itself.
    cleat : Cleat
    arrivals_s : tuple of float
        Time each tire's contact point reaches its cleat's leading edge, s.
    """

    body: Body
    laws: tuple
    cleat: Cleat
    arrivals_s: tuple

    @property
    def tires(self) -> tuple:
        return self.body.tires

    def law_matrix(self) -> np.ndarray:
        """The laws as flat vectors (tires × :data:`identification.model.tire_law.LAW_FIELDS`)."""
        return np.array([tire_law.law_vector(p) for p in self.laws], dtype=float)

    def builtin_cleat(self, i: int) -> bool:
        return self.laws[i]["cleat_height"] > 0.0

    def grid(self, t0_s: float, t_end_s: float, max_step_s: float, sample_step_s: float | None = None):
        """(start, step, n): a uniform grid over [t0, t_end]; with `sample_step_s` its points include
        every sample time (step = sample step / integer, start a multiple of it)."""
        if sample_step_s:
            per = max(1, math.ceil(sample_step_s / max_step_s - 1e-9))
            h = sample_step_s / per
            start = math.floor(t0_s / sample_step_s) * sample_step_s
        else:
            h, start = max_step_s, t0_s
        n = int(math.ceil((t_end_s - start) / h - 1e-9)) + 1
        return start, h, n

    def inputs(self, start_s: float, step_s: float, n: int) -> Inputs:
        """Every tire's inputs on the grid (built-in cleats: flat road, x from the arrival)."""
        nt, v = len(self.laws), self.cleat.speed_m_s       # (cleat_inputs per tire, into shared rows)
        t = start_s + step_s * np.arange(n)
        road, rate = np.zeros((nt, n)), np.zeros((nt, n))
        edges = []
        for j, arr in enumerate(self.arrivals_s):
            if not self.builtin_cleat(j):
                e = _cleat_road(road[j], rate[j], t, start_s, step_s, arrival_s=arr, cleat=self.cleat)
                edges += [(i, j, t_e) for i, t_e in e]
        arrivals = np.array(self.arrivals_s, dtype=float)[:, None]
        offsets = np.array([p["cleat_x"] for p in self.laws], dtype=float)[:, None]
        x = v * (t - arrivals) + offsets
        return Inputs(road, rate, x, np.full((nt, n), float(v)), edges=tuple(sorted(edges)))

    def static_hub_z(self, hub_x0) -> np.ndarray:
        """Hub heights where every tire carries its static load at rest (closed form of the law), m."""
        out = []
        # Python floats: the law's min and max on numpy scalars took a tenth of a small model's run
        for p, x0 in zip(self.laws, np.asarray(hub_x0, dtype=float).tolist()):
            lug, _ = tire_law.lug_road(x0, p["lug_amplitude"], p["lug_pitch"], p["lug_phase"])
            deflection = tire_law.static_deflection(p["stiffness"], p["stiffness_exponent"], p["static_load"])
            if tire_law.ring_envelope_on(p):
                # exact with the cleat out of the ring's reach, as it is where a run starts
                cleat, _ = tire_law.ring_cleat(x0, deflection, p["footprint_length"], p["cleat_x"], p["cleat_height"],
                                               p["cleat_width"], deflection, p["cleat_bevel"])
            else:
                cleat, _ = tire_law.footprint_cleat(x0, p["footprint_length"], p["cleat_x"], p["cleat_height"],
                                                    p["cleat_width"], p["parabolic_pressure"], p["cleat_bevel"])
            out.append(p["unloaded_radius"] + cleat + lug - deflection)
        return np.array(out)

    def initial_state(self, start_s: float, hub_x0, hub_vx0):
        """(q, q̇) at the start: rest, or the linearized periodic steady state under lug passing.

        The static heights already hold the lugs' height at the start; the
        coordinates take the rest of the steady-state displacement (least
        squares where the body has fewer coordinates than tires).
        """
        J, mass, _ = self.body.matrices()
        q, dq = np.zeros(J.shape[1]), np.zeros(J.shape[1])
        amp = np.array([p["lug_amplitude"] for p in self.laws])
        if not amp.any():
            return q, dq
        k = np.array([p["stiffness"] for p in self.laws])
        c = np.array([p["damping"] for p in self.laws])
        wave = np.array([2 * math.pi / p["lug_pitch"] for p in self.laws])
        phase = np.array([p["lug_phase"] for p in self.laws]) + wave * (np.asarray(hub_x0) - np.asarray(hub_vx0)
                                                                        * start_s)
        omega = wave * np.asarray(hub_vx0)
        X = np.zeros(len(self.laws), dtype=complex)
        dX = np.zeros(len(self.laws), dtype=complex)
        for w in np.unique(omega[amp != 0]):
            sel = (omega == w) & (amp != 0)
            R = np.where(sel, amp * np.exp(1j * phase), 0.0)          # road phasors, sin convention
            A = J.T @ ((k + 1j * w * c)[:, None] * J) - w * w * np.diag(mass)
            Q = np.linalg.solve(A, J.T @ ((k + 1j * w * c) * R))
            e = np.exp(1j * w * start_s)
            X += J @ Q * e
            dX += J @ (1j * w * Q) * e
        lug_now = np.where(amp != 0, amp * np.sin(omega * start_s + phase), 0.0)
        q = np.linalg.lstsq(J, np.imag(X) - lug_now, rcond=None)[0]
        dq = np.linalg.lstsq(J, np.imag(dX), rcond=None)[0]
        return q, dq
