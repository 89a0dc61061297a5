"""Reference results of the default experiments of the FMU kinds.

Each kind's folder holds ``reference.csv``: the time grid of the FMU's
``DefaultExperiment``, the input signals fed to it (columns named like the
inputs) and the outputs that ``fmpy.simulate_fmu`` recorded for the FMU built
with the kind's default start values, run with the reference's start values
(``kind.json``: ``reference.start_values``, e.g. to switch options on; see
:mod:`build_scripts.runners` for the alignment of inputs and outputs).  Floats are written with ``repr``
(exact round trip), booleans as 0/1; lines starting with ``#`` are comments.

``python -m build_scripts.reference KIND`` rewrites the file after an
intended change of behaviour; before writing it checks the new result
against the kind's closed-form law (:data:`CLOSED_FORM`).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from .build import build_fmu, resolve_start_values
from .kinds import load_kind
from .runners import simulate_fmpy
from identification._files import temp_prefix

__all__ = ["INPUT_SIGNALS", "CLOSED_FORM", "read_reference", "write_reference", "reference_signals",
           "closed_form_outputs", "main"]


def _point_contact_cleat_run(t: np.ndarray, starts: dict) -> dict:
    """Prescribed hub and road motion of a tire rolling over a cleat (SI units).

    Road: a (1 - cos) bump 0.05 m high, 0.1 m long, at 7 km/h, from 0.1 s.
    Hub: at the static deflection of a 1500 kg corner mass on the kind's
    stiffness until 0.1 s, then a damped oscillation (ζ = 0.15, amplitude
    0.06 m, so that the tire lifts off) about it.
    """
    g, mass, speed = 9.80665, 1500.0, 7.0 / 3.6
    k, r0 = starts["stiffness"], starts["unloaded_radius"]
    height, length, t0 = 0.05, 0.1, 0.1
    duration = length / speed
    tau = t - t0
    on = (tau >= 0.0) & (tau <= duration)
    phase = 2.0 * math.pi * tau / duration
    road_z = np.where(on, 0.5 * height * (1.0 - np.cos(phase)), 0.0)
    road_vz = np.where(on, 0.5 * height * np.sin(phase) * 2.0 * math.pi / duration, 0.0)
    wn, zeta, amp = math.sqrt(k / mass), 0.15, 0.06
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    after = tau >= 0.0
    decay = np.exp(-zeta * wn * np.where(after, tau, 0.0))
    s, c = np.sin(wd * np.where(after, tau, 0.0)), np.cos(wd * np.where(after, tau, 0.0))
    static = r0 - mass * g / k
    hub_z = static + np.where(after, amp * decay * s, 0.0)
    hub_vz = np.where(after, amp * decay * (wd * c - zeta * wn * s), 0.0)
    return {"hub_z": hub_z, "hub_vz": hub_vz, "road_z": road_z, "road_vz": road_vz}


def _point_contact_closed_form(inputs: dict, starts: dict) -> dict:
    """F = k δ + c δ̇ with δ = r0 − (z_hub − z_road), δ̇ = ż_road − ż_hub; contact δ > 0."""
    k, c, r0 = starts["stiffness"], starts["damping"], starts["unloaded_radius"]
    deflection = r0 - (inputs["hub_z"] - inputs["road_z"])
    rate = inputs["road_vz"] - inputs["hub_vz"]
    return {"force_z": k * deflection + c * rate, "deflection": deflection, "deflection_rate": rate,
            "in_contact": deflection > 0.0}


def _extended_tire_cleat_run(t: np.ndarray, starts: dict) -> dict:
    """Prescribed hub and road motion of a tire rolling over its built-in cleat (SI units).

    Hub: at 7 km/h from x = 0.013 m (so that no sample falls on an edge of the
    footprint's overlap with the cleat); vertically at the static deflection
    n W / k of the progressive spring until the footprint reaches the cleat,
    then a damped oscillation (ζ = 0.15, amplitude 0.12 m, natural frequency
    of the mass W / g on k) about it, which lifts the tire off the road.
    Road (besides the built-in cleat and the lugs): a 4 mm, 1.5 Hz undulation.
    """
    g, speed, x0 = 9.80665, 7.0 / 3.6, 0.013
    k, r0, w_load = starts["stiffness"], starts["unloaded_radius"], starts["static_load"]
    static = r0 - starts["stiffness_exponent"] * w_load / k
    t_reach = (starts["cleat_x"] - 0.5 * starts["footprint_length"] - x0) / speed
    wn, zeta, amp = math.sqrt(k * g / w_load), 0.15, 0.12
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    tau = np.maximum(t - t_reach, 0.0)
    decay, s, c = np.exp(-zeta * wn * tau), np.sin(wd * tau), np.cos(wd * tau)
    a, omega = 0.004, 2.0 * math.pi * 1.5
    hub_vz = np.where(t > t_reach, amp * decay * (wd * c - zeta * wn * s), 0.0)
    return {"hub_z": static + amp * decay * s, "hub_vz": hub_vz,
            "road_z": a * np.sin(omega * t), "road_vz": a * omega * np.cos(omega * t),
            "hub_x": x0 + speed * t, "hub_vx": np.full_like(t, speed)}


def _trapezoid(s, xc: float, height: float, width: float, bevel: float):
    """The bevelled cleat (b > 0) at positions `s`: height H clip(min(t, w − t) / b, 0, 1), t = s − x_c, and
    its slope (the derivative from the right: ±H/b on the bevels, 0 elsewhere)."""
    t = s - xc
    z = height * np.clip(np.minimum(t, width - t) / bevel, 0.0, 1.0)
    rising = ((t >= 0.0) & (t < bevel)).astype(float)
    falling = ((t >= width - bevel) & (t < width)).astype(float)
    return z, height / bevel * (rising - falling)


def _trapezoid_integral(s, xc: float, height: float, width: float, bevel: float):
    """∫ of the bevelled cleat (b > 0) from −∞ to `s`: with t = clip(s − x_c, 0, w), the leading bevel
    covered over r = min(t, b), the top over f = clip(t − b, 0, w − 2b), the trailing bevel over
    e = max(t − (w − b), 0): H (r² / (2b) + f + e − e² / (2b)); H (w − b) past the cleat."""
    t = np.clip(s - xc, 0.0, width)
    rise = np.minimum(t, bevel)
    top = np.clip(t - bevel, 0.0, width - 2.0 * bevel)
    fall = np.maximum(t - (width - bevel), 0.0)
    return height * (rise * rise / (2.0 * bevel) + top + fall - fall * fall / (2.0 * bevel))


#: Gauss–Legendre nodes and weights on [−1, 1], exact for polynomials up to degree 5.
_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(3)


def _bevelled_parabolic(x, length: float, xc: float, height: float, width: float, bevel: float):
    """The bevelled cleat averaged over the footprint under the parabolic pressure density
    q(s) = 3 / (2ℓ) (1 − (2 (s − x) / ℓ)²), and its slope along x, by quadrature.

    On each piece of the footprint between the cleat's kinks the integrands z q and z' q are
    polynomials of degree ≤ 3, so a 3-point Gauss–Legendre rule per piece is exact (to round-off).
    The slope is ∫ z'(s) q(s) ds: d/dx ∫ z(x + ξ) q(ξ) dξ for the continuous trapezoid z.
    """
    lo, hi = x - 0.5 * length, x + 0.5 * length
    cuts = np.sort(np.column_stack([lo, hi, *(np.clip(xc + k, lo, hi) for k in (0.0, bevel, width - bevel,
                                                                               width))]), axis=1)
    centre, radius = 0.5 * (cuts[:, 1:] + cuts[:, :-1]), 0.5 * (cuts[:, 1:] - cuts[:, :-1])
    s = centre[..., None] + radius[..., None] * _GAUSS_NODES
    u = 2.0 * (s - x[:, None, None]) / length
    q = 1.5 / length * (1.0 - u * u)
    z, dz = _trapezoid(s, xc, height, width, bevel)
    weight = radius[..., None] * _GAUSS_WEIGHTS
    return (weight * z * q).sum(axis=(1, 2)), (weight * dz * q).sum(axis=(1, 2))


def _extended_tire_closed_form(inputs: dict, starts: dict) -> dict:
    """The extended tire, vectorised; the enveloped cleat as a difference of an antiderivative.

    Uniform footprint pressure: with G(s) = H clip(s − x_c, 0, w) the cleat
    height integrated up to s, the footprint average is
    (G(x + ℓ/2) − G(x − ℓ/2)) / ℓ and its slope
    H (1[x_c < x + ℓ/2 < x_c + w] − 1[x_c < x − ℓ/2 < x_c + w]) / ℓ.

    Parabolic footprint pressure (``parabolic_pressure``): the pressure density
    at distance ξ ahead of the footprint's centre is q(ξ) = 3 / (2ℓ) (1 − (2ξ/ℓ)²)
    on |ξ| < ℓ/2, with the cumulative pressure Q(ξ) = 1/2 + 3/4 (s − s³/3),
    s = clip(2ξ/ℓ, −1, 1); the cleat occupies ξ in [x_c − x, x_c + w − x], so
    the average is H (Q(x_c + w − x) − Q(x_c − x)) and its slope along x is
    H (q(x_c − x) − q(x_c + w − x)).

    A bevelled cleat (``cleat_bevel`` b > 0, a trapezoid z(s) rising over b
    from x_c and falling over b to x_c + w): under the contact point z(x) and
    its slope from the right; uniform pressure: the same difference of its
    antiderivative (:func:`_trapezoid_integral`), slope (z(x + ℓ/2) − z(x − ℓ/2)) / ℓ;
    parabolic pressure: exact piecewise quadrature (:func:`_bevelled_parabolic`).
    """
    p = starts
    x, length, xc = inputs["hub_x"], p["footprint_length"], p["cleat_x"]
    height, width, bevel = p["cleat_height"], p["cleat_width"], p.get("cleat_bevel", 0.0)
    if bevel > 0.0 and height != 0.0:
        x = np.asarray(x, dtype=float)
        if length > 0.0 and p.get("parabolic_pressure", False):
            cleat, cleat_slope = _bevelled_parabolic(x, length, xc, height, width, bevel)
        elif length > 0.0:
            ends = (x + 0.5 * length, x - 0.5 * length)
            integral = [_trapezoid_integral(e, xc, height, width, bevel) for e in ends]
            at_ends = [_trapezoid(e, xc, height, width, bevel)[0] for e in ends]
            cleat, cleat_slope = (integral[0] - integral[1]) / length, (at_ends[0] - at_ends[1]) / length
        else:
            cleat, cleat_slope = _trapezoid(x, xc, height, width, bevel)
    elif length > 0.0 and p.get("parabolic_pressure", False):
        def cumulative(xi):
            s = np.clip(2.0 * xi / length, -1.0, 1.0)
            return 0.5 + 0.75 * (s - s ** 3 / 3.0)

        def density(xi):
            s = 2.0 * xi / length
            return np.where(np.abs(s) < 1.0, 1.5 / length * (1.0 - s * s), 0.0)

        lead, trail = xc + width - x, xc - x
        cleat = height * (cumulative(lead) - cumulative(trail))
        cleat_slope = height * (density(trail) - density(lead))
    elif length > 0.0:
        ends = (x + 0.5 * length, x - 0.5 * length)
        integral = [height * np.clip(e - xc, 0.0, width) for e in ends]
        inside = [((e > xc) & (e < xc + width)).astype(float) for e in ends]
        cleat, cleat_slope = (integral[0] - integral[1]) / length, height * (inside[0] - inside[1]) / length
    else:
        cleat, cleat_slope = np.where((x >= xc) & (x < xc + width), height, 0.0), np.zeros_like(x)
    arg = 2.0 * math.pi / p["lug_pitch"] * x + p["lug_phase"]
    lug = p["lug_amplitude"] * np.sin(arg)
    lug_slope = p["lug_amplitude"] * 2.0 * math.pi / p["lug_pitch"] * np.cos(arg)
    road = inputs["road_z"] + cleat + lug
    deflection = p["unloaded_radius"] - (inputs["hub_z"] - road)
    rate = inputs["road_vz"] + (cleat_slope + lug_slope) * inputs["hub_vx"] - inputs["hub_vz"]
    n, w_load, k = p["stiffness_exponent"], p["static_load"], p["stiffness"]
    elastic = k * deflection if n == 1.0 else w_load * np.sign(deflection) * np.abs(deflection * k / (n * w_load)) ** n
    force = elastic + p["damping"] * rate + p["friction_force"] * np.tanh(rate / p["friction_velocity"])
    contact = (deflection > 0.0) & (force > 0.0) if p["unilateral"] else deflection > 0.0
    if p["unilateral"]:
        force = np.where(contact, force, 0.0)
    return {"force_z": force, "deflection": deflection, "deflection_rate": rate, "in_contact": contact,
            "road_effective_z": road}


#: Force on each tire minus its static load in the body's default experiment, N (FL, FR, RL, RR).
BODY_FORCE_STEPS_N = (80.0, -30.0, 45.0, -65.0)


def _tractor_body_forces(t: np.ndarray, starts: dict) -> dict:
    """Constant tire forces off the static loads by :data:`BODY_FORCE_STEPS_N` from the start (N)."""
    return {f"force_{tire}": np.full_like(t, starts[f"load_{tire}"] + step)
            for tire, step in zip(("FL", "FR", "RL", "RR"), BODY_FORCE_STEPS_N)}


def _tractor_body_closed_form(inputs: dict, starts: dict) -> dict:
    """Uniformly accelerated body: q = q0 + q'0 τ + a τ²/2 with a = M⁻¹ Jᵀ (F − W) constant (τ = t − t0).

    J and M are those of :meth:`identification.model.tractor.Body.matrices`
    (any body), the initial coordinates the least-squares fit of the initial
    hub values, the seat row that of :func:`identification.fmu.ssp.body_seat_row`; the stepping scheme is exact
    for a constant acceleration, so the FMU must match to round-off.  Hub
    velocities are the rates at the end of each step (q'0 + a τ).
    """
    from identification.model.tractor import Body
    from identification.fmu.ssp import body_seat_row

    tires = ("FL", "FR", "RL", "RR")
    forces = np.array([inputs[f"force_{t}"] for t in tires])
    if not np.all(forces == forces[:, :1]):
        raise ValueError("the body's closed form needs constant forces")
    body = Body(tires=tires, loads_n=tuple(starts[f"load_{t}"] for t in tires), wheelbase_m=starts["wheelbase"],
                pitch=bool(starts["pitch_coupling"]), roll=bool(starts["roll_coupling"]),
                pivot=bool(starts["front_axle_pivot"]), pitch_index=starts["pitch_index"],
                roll_index=starts["roll_index"], pivot_index=starts["pivot_index"])
    J, mass, _ = body.matrices()
    q0 = np.linalg.lstsq(J, np.array([starts[f"initial_hub_dz_{t}"] for t in tires]), rcond=None)[0]
    dq0 = np.linalg.lstsq(J, np.array([starts[f"initial_hub_vz_{t}"] for t in tires]), rcond=None)[0]
    loads = np.array([starts[f"load_{t}"] for t in tires])
    a = (J.T @ (forces[:, 0] - loads)) / mass
    t = inputs["time"]
    tau = t - t[0]
    q = q0[:, None] + dq0[:, None] * tau + 0.5 * a[:, None] * tau ** 2
    dq = dq0[:, None] + a[:, None] * tau
    row = body_seat_row(body, seat_x_m=starts["seat_x"], seat_y=starts["seat_y"])
    out = {}
    for i, tire in enumerate(tires):
        out[f"hub_z_{tire}"] = starts[f"static_hub_z_{tire}"] + J[i] @ q
        out[f"hub_vz_{tire}"] = J[i] @ dq
        out[f"hub_x_{tire}"] = starts["start_x"] + starts["speed"] * t - (starts["wheelbase"] if i >= 2 else 0.0)
        out[f"hub_az_{tire}"] = np.full_like(t, J[i] @ a)
    out["hub_vx"] = np.full_like(t, starts["speed"])
    out["seat_z"] = row @ q
    out["seat_az"] = np.full_like(t, row @ a)
    return out


def _map_tire_run(t: np.ndarray, starts: dict) -> dict:
    """The point-contact cleat run (:func:`_point_contact_cleat_run`, static deflection from the default map's k
    at the start speed) while the speed ramps from 0.5 to 5 m/s: below, through and above the default map's
    nodes and tested range (:func:`build_scripts.map_table.default_map`)."""
    from .map_table import default_map

    speed, k, _, _ = default_map()
    run = _point_contact_cleat_run(t, dict(starts, stiffness=float(np.interp(starts["speed"], speed, k))))
    return {**run, "speed": 0.5 + 9.0 * (t - t[0])}


def _map_tire_closed_form(inputs: dict, starts: dict) -> dict:
    """k, c = numpy.interp of the default map's nodes at the speed (held outside them); the point-contact law;
    extrapolating outside the tested range."""
    from .map_table import default_map

    speed, k, c, (low, high) = default_map()
    stiffness, damping = np.interp(inputs["speed"], speed, k), np.interp(inputs["speed"], speed, c)
    out = _point_contact_closed_form(inputs, dict(starts, stiffness=stiffness, damping=damping))
    return {**out, "stiffness": stiffness, "damping": damping,
            "extrapolating": (inputs["speed"] < low) | (inputs["speed"] > high)}


def _no_inputs(t: np.ndarray, starts: dict) -> dict:
    return {}


def _road_profile_closed_form(inputs: dict, starts: dict) -> dict:
    """The default profile (:func:`build_scripts.road_table.default_road`) under each tire: linear
    interpolation of the heights and of their ``numpy.gradient`` slopes, faded in by a smoothstep."""
    from .road_table import default_road

    x_road, left, right = default_road()
    t = inputs["time"]
    out = {}
    for i, tire in enumerate(("FL", "FR", "RL", "RR")):
        track = left if tire in ("FL", "RL") else right
        x = starts["start_x"] + starts["speed"] * t - (starts["wheelbase"] if i >= 2 else 0.0)
        h = np.interp(x, x_road, track, left=0.0, right=0.0)
        dh = np.interp(x, x_road, np.gradient(track, x_road), left=0.0, right=0.0)
        s = np.clip((x - x_road[0]) / starts["ramp_length"], 0.0, 1.0)
        fade = s * s * (3.0 - 2.0 * s)
        dfade = np.where((s > 0) & (s < 1), 6.0 * s * (1.0 - s) / starts["ramp_length"], 0.0)
        out[f"road_z_{tire}"] = fade * h
        out[f"road_vz_{tire}"] = starts["speed"] * (fade * dh + dfade * h)
    return out


#: kind -> function(t, start values) returning the input signals of its default experiment.
INPUT_SIGNALS = {"point_contact": _point_contact_cleat_run, "extended_tire": _extended_tire_cleat_run,
                 "tractor_body": _tractor_body_forces, "road_profile": _no_inputs, "map_tire": _map_tire_run}
#: kind -> function(inputs, start values) returning its outputs in closed form (``inputs["time"]``: the
#: time of each output row).
CLOSED_FORM = {"point_contact": _point_contact_closed_form, "extended_tire": _extended_tire_closed_form,
               "tractor_body": _tractor_body_closed_form, "road_profile": _road_profile_closed_form,
               "map_tire": _map_tire_closed_form}


def reference_path(kind) -> Path:
    """Path of the kind's reference CSV (a real file: package data of the installed project)."""
    k = load_kind(kind)
    return Path(str(k.folder.joinpath(k.reference_file)))


def read_reference(kind) -> dict:
    """The kind's reference result as ``{column: array}`` (booleans as bool arrays)."""
    k = load_kind(kind)
    text = k.folder.joinpath(k.reference_file).read_text(encoding="utf-8")
    rows = [row for row in csv.reader(line for line in io.StringIO(text) if not line.startswith("#")) if row]
    header, data = rows[0], rows[1:]
    types = {v.name: v.type for v in k.variables}
    out = {}
    for j, name in enumerate(header):
        column = [row[j] for row in data]
        out[name] = (np.array([int(x) != 0 for x in column]) if types.get(name) == "Boolean"
                     else np.array([float(x) for x in column]))
    return out


def write_reference(path, kind, result: dict, comment: str) -> None:
    """Write `result` (``{column: array}``, time first) as a reference CSV."""
    k = load_kind(kind)
    types = {v.name: v.type for v in k.variables}
    names = list(result)
    buf = io.StringIO()
    for line in comment.splitlines():
        buf.write(f"# {line}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(names)
    for i in range(len(result["time"])):
        writer.writerow([str(int(bool(result[n][i]))) if types.get(n) == "Boolean" else repr(float(result[n][i]))
                         for n in names])
    Path(path).write_text(buf.getvalue(), encoding="utf-8")


def reference_signals(kind, start_s: float, stop_s: float, step_s: float, starts: dict) -> dict:
    """Time grid t_k = start + k h and the kind's input signals on it."""
    n = int(round((stop_s - start_s) / step_s))
    t = np.array([start_s + i * step_s for i in range(n + 1)])
    return {"time": t, **INPUT_SIGNALS[kind](t, starts)}


def closed_form_outputs(kind, signals: dict, starts: dict) -> dict:
    """Outputs in closed form with fmpy's alignment: row 0 from inputs of row 0, row k from row k-1."""
    names = [n for n in signals if n != "time"]
    held = {n: np.concatenate([signals[n][:1], signals[n][:-1]]) for n in names}
    held["time"] = np.asarray(signals["time"])
    return CLOSED_FORM[kind](held, starts)


def main(argv=None) -> int:
    """``python -m build_scripts.reference KIND``: rewrite the kind's reference result."""
    parser = argparse.ArgumentParser(prog="python -m build_scripts.reference", description=main.__doc__)
    parser.add_argument("kind")
    args = parser.parse_args(argv)
    from fmpy import read_model_description

    k = load_kind(args.kind)
    starts = resolve_start_values(k, k.reference_start_values)
    with tempfile.TemporaryDirectory(prefix=temp_prefix("ref")) as tmp:
        fmu = build_fmu(args.kind, Path(tmp) / f"{args.kind}.fmu", backend=k.backends[0])
        de = read_model_description(str(fmu)).defaultExperiment
        signals = reference_signals(args.kind, float(de.startTime), float(de.stopTime), float(de.stepSize), starts)
        outputs = k.names("output")
        result = simulate_fmpy(fmu, signals, outputs, start_values=k.reference_start_values)
    expected = closed_form_outputs(args.kind, signals, starts)
    for name in outputs:
        if not np.allclose(result[name], expected[name], rtol=k.reference_rtol, atol=k.reference_atol):
            print(f"{args.kind}: output {name} differs from the closed form; reference not written", file=sys.stderr)
            return 1
    path = reference_path(args.kind)
    columns = {"time": result["time"], **{n: signals[n] for n in signals if n != "time"},
               **{n: result[n] for n in outputs}}
    run_with = (f"run with {json.dumps(k.reference_start_values, sort_keys=True)} (kind.json),\n"
                if k.reference_start_values else "")
    write_reference(path, args.kind, columns,
                    f"Reference result of the default experiment of FMU kind {args.kind} (fmpy.simulate_fmu),\n"
                    f"built with the default start values; {run_with}"
                    f"inputs as fed, outputs as recorded (SI units).\n"
                    f"Regenerate: python -m build_scripts.reference {args.kind}")
    print(f"wrote {path} ({len(result['time'])} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
