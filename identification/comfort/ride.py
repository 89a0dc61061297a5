"""The whole tractor on a road profile: the seat's vertical acceleration for a tire parameter set.

The model record is the whole-tractor one (:class:`~identification.model.tractor.TractorModel`: body,
four tire laws, arrivals) with the cleat replaced by a road profile of two
tracks: each tire rolls on its side's track at its own distance behind the
front axle, so the rear tires meet the front tires' road a wheelbase later
(the front/rear delay L / v), and the left and right tracks are as coherent as
the profile makes them.  The same record runs in the compiled stepping and in
the FMU master (:func:`~identification.fmu.tractor_cosim.run_tractor_fmus`), so a
parameter set and its exported FMUs ride the same road.

The seat is a point of the body, ``seat_x_m`` behind the front axle and
``seat_y`` (a fraction of the half-track, + left) from the centre line: its
vertical acceleration is the row of the body's generalized accelerations
q̈ that places it, z̈ + (a − x) θ̈ + (y − ȳ) ẅ (see the model record for the
coordinates; with a pivoting front axle the seat is on the body, not the
axle).  As for the hubs, the track width need not be known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..identify.tire_map import map_set
from ..model.ride import RAMP_M, RideModel, ride_model, seat_row
from ..model.tractor import Body, TractorModel

__all__ = ["RideModel", "ride_model", "seat_row", "seat_acceleration", "ride", "RideRun", "parameter_sets",
           "check_set_names", "ride_comparison", "REPORT_RIDE", "RAMP_M"]

def seat_acceleration(model: TractorModel, trajectory, *, seat_x_m: float, seat_y: float = 0.0) -> np.ndarray:
    """The seat's vertical acceleration on the trajectory's grid, m/s² (from the hubs' accelerations:
    q̈ = J⁺ ü, exact as the hubs move with the body)."""
    J, _, _ = model.body.matrices()
    qdd = np.linalg.lstsq(J, np.asarray(trajectory.hub_accel_m_s2), rcond=None)[0]
    return seat_row(model.body, seat_x_m=seat_x_m, seat_y=seat_y) @ qdd



# ----------------------------------------------------------------------------- rides and parameter sets

#: What the seat's ratings are: the seat is a point of the body.
FLOOR_VALUES = "floor values: the seat is a point of the body, no seat suspension"

#: Default seat position behind the front axle, as a fraction of the wheelbase (a tractor's seat sits
#: ahead of, and close to, the rear axle).
SEAT_X_FRACTION = 0.85
#: Road grid spacing, m.  The road is interpolated linearly between its points, which attenuates short
#: wavelengths: on an ISO 8608 class C road at 7.2 km/h a 5 cm grid lowers the seat's a_w by 3 %, a 1 cm
#: grid by 0.2 % (``tests/test_ride.py``, against the spectral prediction).
ROAD_SPACING_M = 0.01


@dataclass(frozen=True, eq=False)
class RideRun:
    """One parameter set's ride: the tires, the seat's acceleration and its ISO 2631-1 rating."""

    name: str
    k: dict                    # tire -> N/m
    c: dict                    # tire -> N s/m
    time_s: np.ndarray
    seat_m_s2: np.ndarray
    comfort: object            # ComfortResult (Wk)
    contact: dict | None = None  # the law rated ("linear" or "lift-off"), tension and lost contact per tire
    axes: object = None        # ThreeAxisResult: the seat's x, y, z

    def to_json(self) -> dict:
        doc = {"k": self.k, "c": self.c, **self.comfort.to_json()}
        if self.contact is not None:
            doc["contact"] = self.contact
        if self.axes is not None:
            doc["three_axes"] = self.axes.to_json()
        return doc


def ride(body: Body, sets: dict, *, road, speed_m_s: float, duration_s: float, seat_x_m: float | None = None,
         seat_y: float = 0.0, step_s: float = 1e-3, exposure_h: float | None = None, tires: str = "linear",
         seat_height_m: float | None = None) -> dict:
    """Drive the tractor over `road` once per tire parameter set; the seat's Wk rating of each.

    Parameters
    ----------
    body : Body
        Rigid or pivoting-front-axle tractor.
    sets : dict
        ``name -> (k, c)``, each a dict tire -> value (N/m, N s/m).
    road : RoadProfile
        The two tracks (:func:`identification.comfort.road.road_profile`); the front axle starts at its
        first point, the rear one a wheelbase before it (on level ground, faded in over RAMP_M).
    speed_m_s, duration_s : float
    seat_x_m : float, optional
        Seat position behind the front axle, m (default SEAT_X_FRACTION of the wheelbase).
    seat_y : float
        Seat position from the centre line, fraction of the half-track (+ left).
    step_s : float
        Step of the simulation, s (also the rating's sampling interval).
    exposure_h : float, optional
        Daily exposure for A(8) and the daily VDV (:func:`identification.comfort.iso2631.comfort`).
    tires : {"linear", "auto", "lift-off"}
        The tire law rated: the linear (bilateral) law, the law's lift-off option (unilateral), or
        ``auto``: the lift-off law where the linear one pulls (:mod:`identification.comfort.contact`).  The
        linear law's tension is counted in every case.
    seat_height_m : float, optional
        Seat height above the axles, m (default :data:`identification.comfort.seat_axes.DEFAULT_SEAT_HEIGHT_M`),
        for the seat's fore-aft and lateral acceleration (:mod:`identification.comfort.seat_axes`).

    Returns
    -------
    dict of str to RideRun
        The rating covers the ride after both axles are past the fade-in; ``axes`` rates the seat's three
        axes.
    """
    from .contact import TIRE_MODES, episodes
    from .seat_axes import DEFAULT_SEAT_HEIGHT_M, axis_rows, three_axis
    from ..model.kernels import run_model
    from .iso2631 import comfort

    seat_x = SEAT_X_FRACTION * body.wheelbase_m if seat_x_m is None else float(seat_x_m)
    settle_s = (RAMP_M + body.wheelbase_m) / speed_m_s
    if not duration_s > 2 * settle_s:
        raise InputError("--duration-s", f"must exceed twice the fade-in of both axles ({2 * settle_s:.3g} s at "
                                         f"{speed_m_s * 3.6:.3g} km/h), got {duration_s:g}")
    if road.x_m[-1] < speed_m_s * duration_s:
        raise ValueError(f"the road ({road.x_m[-1]:g} m) is shorter than the ride ({speed_m_s * duration_s:g} m)")
    if tires not in TIRE_MODES:
        raise InputError("--tires", f"unknown tire law {tires!r} ({', '.join(TIRE_MODES)})")
    height = DEFAULT_SEAT_HEIGHT_M if seat_height_m is None else float(seat_height_m)
    rows = axis_rows(body, seat_x_m=seat_x, seat_y=seat_y, height_m=height, track_width_m=road.track_width_m)
    J = body.matrices()[0]
    out = {}
    for name, (k, c) in sets.items():
        laws = [_point_contact(k[t], c[t], load) for t, load in zip(body.tires, body.loads_n)]
        model = ride_model(body, laws, speed_m_s=speed_m_s, road_x_m=road.x_m, road_left_m=road.left_m,
                           road_right_m=road.right_m)
        traj = run_model(model, *model.grid(0.0, duration_s, step_s))
        keep = traj.time_s >= settle_s
        force = traj.force_n[:, keep]
        contact = {"law": "linear", "tension": {t: episodes(force[j] < 0.0, step_s, force_n=force[j], load_n=w)
                                                for j, (t, w) in enumerate(zip(body.tires, body.loads_n))}}
        if tires == "lift-off" or (tires == "auto" and np.any(force < 0.0)):
            model = ride_model(body, [dict(law, unilateral=True) for law in laws], speed_m_s=speed_m_s,
                               road_x_m=road.x_m, road_left_m=road.left_m, road_right_m=road.right_m)
            traj = run_model(model, *model.grid(0.0, duration_s, step_s))
            contact["law"] = "lift-off"
            contact["lost_contact"] = {t: episodes(traj.force_n[j, keep] <= 0.0, step_s)
                                       for j, t in enumerate(body.tires)}
        qdd = np.linalg.lstsq(J, np.asarray(traj.hub_accel_m_s2), rcond=None)[0][:, keep]
        seat = rows["z"] @ qdd
        out[name] = RideRun(name, {t: float(k[t]) for t in body.tires}, {t: float(c[t]) for t in body.tires},
                            traj.time_s[keep], seat, comfort(seat, 1.0 / step_s, "Wk", exposure_h=exposure_h),
                            contact, three_axis(rows["x"] @ qdd, rows["y"] @ qdd, seat, 1.0 / step_s,
                                                exposure_h=exposure_h))
    return out


def _point_contact(k: float, c: float, load: float) -> dict:
    from ..model import tire_law

    return dict(tire_law.EXTENDED_DEFAULTS, stiffness=float(k), damping=float(c), static_load=float(load))


def _documented_body(rec, body_doc, source) -> tuple:
    """The body and the final k, c of a whole-tractor document (``diagnose --json``, or a report's
    ``summary.json`` and its entry of `rec`): (Body, (k, c), how)."""
    from ..fmu.simulate_inputs import body_settings, diagnosis_of, read_body_document
    from ..recording import TIRES

    source = str(source or body_doc)
    doc = read_body_document(body_doc) if not isinstance(body_doc, dict) else body_doc
    doc = diagnosis_of(doc, source, rec.source)
    settings = body_settings(doc, source)
    idx = settings["indices"]
    try:
        final = ({t: float(doc["tires"][t]["k"]) for t in TIRES}, {t: float(doc["tires"][t]["c"]) for t in TIRES})
    except (KeyError, TypeError, ValueError):
        raise InputError(source, "not a 'cleatfmu diagnose --json' whole-tractor document: tires.<TIRE>.k and "
                                 ".c of FL, FR, RL, RR needed") from None
    body = Body(TIRES, tuple(rec.wheel_load_N[t] for t in TIRES), rec.wheelbase_m,
                pitch="axle_coupling" in settings["body_effects"], roll="roll_coupling" in settings["body_effects"],
                pivot=settings["front_axle"] == "pivot", pitch_index=idx.get("pitch_index", 1.0),
                roll_index=idx.get("roll_index", 1.0), pivot_index=idx.get("pivot_index", 0.05))
    what = "rigid tractor" if settings["front_axle"] == "rigid" else "tractor with a pivoting front axle"
    from pathlib import PureWindowsPath

    origin = PureWindowsPath(str(settings["recording"])).name if settings["recording"] else "its recording"
    return body, final, f"{what} of {PureWindowsPath(source).name} (diagnosed from {origin})"


def parameter_sets(rec, names, *, diagnosis=None, workers: int = 1, body_doc=None, speed_m_s=None) -> tuple:
    """The tractor's body and tire parameter sets to ride with, from a whole-tractor recording.

    Parameters
    ----------
    rec : Recording
        All four channels.
    names : iterable of str
        ``final`` (the joint diagnosis's named model), ``paper`` (the paper's method per tire),
        ``waveform`` (the waveform fit per tire), ``static=K`` (every tire at K N/m, e.g. a compression
        test's, with the final model's c), ``fmu=DIR`` (the k and c the four tire FMUs in DIR carry),
        ``params=FILE`` (the k and c of an ``identify --json`` document of the four tires), ``map=FILE`` (the
        k and c of a ``cleatfmu map`` tire map at `speed_m_s`).
    diagnosis : TractorDiagnosis, optional
        The recording's joint diagnosis (run when neither it nor `body_doc` is given).
    workers : int
        Processes of the diagnosis.
    body_doc : dict or path-like, optional
        A ``diagnose --json`` document or a report's ``summary.json`` (its entry of `rec`): the body and the
        final k, c are taken from it, and no diagnosis is run.
    speed_m_s : float, optional
        The ride's speed, for ``map=FILE`` (default: the recording's).

    Returns
    -------
    (Body, dict, str)
        The diagnosed body (the rigid tractor with typical indices when the diagnosis named no body
        coupling), ``name -> (k, c)``, and how the body was obtained.
    """
    from ..diagnose.joint_select import diagnose_tractor
    from ..diagnose.joint_timing import BODY_DEFAULTS
    from ..recording import TIRES

    names = check_set_names(names, recording=rec.source)
    missing = [t for t in TIRES if t not in rec.accel_m_s2]
    if missing:
        raise InputError(rec.source, f"a ride needs all four hubs; no channel {', '.join(missing)}")
    if body_doc is not None and diagnosis is None:
        body, final, how = _documented_body(rec, body_doc, None)
    else:
        diag = diagnosis or diagnose_tractor(rec, workers=workers)
        theta = diag.final.params
        body = diag.final.model.body(theta)
        how = "diagnosed " + ("rigid tractor" if body.kind == "rigid" else "tractor with a pivoting front axle")
        final = ({t: theta[f"k_{t}"] for t in TIRES}, {t: theta[f"c_{t}"] for t in TIRES})
    if body.kind not in ("rigid", "pivot"):
        body = Body(TIRES, tuple(rec.wheel_load_N[t] for t in TIRES), rec.wheelbase_m, pitch=True, roll=True,
                    pitch_index=BODY_DEFAULTS["pitch_index"], roll_index=BODY_DEFAULTS["roll_index"])
        how = "rigid tractor with typical indices (assumed: the diagnosis named no body coupling)"
    sets = {}
    for name in names:
        if name == "final":
            sets[name] = final
        elif name.startswith("fmu="):
            sets[name] = _fmu_set(name, recording=rec.source)
        elif name.startswith("params="):
            sets[name] = _params_set(name)
        elif name.startswith("map="):
            sets[name] = map_set(name[4:], rec.speed_m_s if speed_m_s is None else speed_m_s, TIRES)[:2]
        elif name in ("paper", "waveform"):
            if name == "paper":
                from ..identify.paper import identify as method
            else:
                from ..identify.waveform import identify_waveform_recording as method
            results = method(rec, list(TIRES))
            sets[name] = ({t: results[t].k for t in TIRES}, {t: results[t].c for t in TIRES})
        else:
            k = _stiffness(name)
            sets[name] = ({t: k for t in TIRES}, final[1])
    return body, sets, how


def check_set_names(names, *, recording=None) -> list:
    """The parameter-set names of :func:`parameter_sets`, checked (InputError naming ``--compare``);
    `recording` (a path or name) picks its FMUs in a folder of several recordings' (``fmu=DIR``)."""
    names = [str(n).strip() for n in names if str(n).strip()]
    if not names:
        raise InputError("--compare", "no parameter set given")
    if len(set(names)) != len(names):
        raise InputError("--compare", f"a parameter set named twice in {','.join(names)!r}")
    for name in names:
        if name.startswith("static="):
            _stiffness(name)
        elif name.startswith("fmu="):
            _fmu_set(name, recording=recording)
        elif name.startswith("params="):
            _params_set(name)
        elif name.startswith("map="):
            from ..recording import TIRES
            map_set(name[4:], None, TIRES)
        elif name not in ("paper", "waveform", "final"):
            raise InputError("--compare", f"unknown parameter set {name!r} (paper, waveform, final, static=K, "
                                          f"fmu=DIR, params=FILE, map=FILE)")
    return names


def _fmu_set(name: str, *, recording=None) -> tuple:
    """(k, c) per tire of ``fmu=DIR``: the stiffness and damping the four tire FMUs in DIR carry (their
    start values, as exported or written by ``diagnose --fmu-dir``); in a report's ``fmu/``, those of
    `recording` (path or name)."""
    from pathlib import PureWindowsPath

    from fmpy import read_model_description

    from ..recording import TIRES
    from ..fmu.simulate_inputs import tractor_fmu_paths

    folder = name.split("=", 1)[1]
    stem = None if recording is None else PureWindowsPath(str(recording)).name.removesuffix(".csv")
    paths = tractor_fmu_paths(folder, recording=stem)
    k, c = {}, {}
    for t in TIRES:
        try:
            starts = {v.name: v.start for v in read_model_description(str(paths[t])).modelVariables}
            k[t], c[t] = float(starts["stiffness"]), float(starts["damping"])
        except Exception as exc:   # not an FMU, or not a tire FMU
            raise InputError(paths[t], f"not a cleatfmu tire FMU with stiffness and damping ({exc})") from None
        if not (math.isfinite(k[t]) and 1e4 <= k[t] <= 1e8 and math.isfinite(c[t]) and c[t] >= 0):
            raise InputError(paths[t], f"stiffness {k[t]:g} N/m, damping {c[t]:g} N s/m: not a tire's")
    return k, c


def _params_set(name: str) -> tuple:
    """(k, c) per tire of ``params=FILE``: a ``cleatfmu identify --json`` document of all four tires (either
    method), each tire's k and c checked as ``export`` checks them."""
    from ..fmu.export import read_identified
    from ..recording import TIRES

    path = name.split("=", 1)[1]
    k, c = {}, {}
    for t in TIRES:
        _, _, entry = read_identified(path, t)
        k[t], c[t] = float(entry["k"]), float(entry["c"])
    return k, c


def _stiffness(name: str) -> float:
    """K of ``static=K``: a number in N/m, or a compression test's CSV (its eq. 18 static stiffness)."""
    value = name.split("=", 1)[1]
    try:
        k = float(value)
    except ValueError:
        from pathlib import Path
        if not Path(value).is_file():
            raise InputError("--compare", f"{name!r}: static=K needs a stiffness K in N/m (e.g. static=300e3) or "
                                          f"a compression test's CSV file") from None
        from ..identify.static import static_stiffness_file
        k = static_stiffness_file(value).k_N_per_m
    if not (math.isfinite(k) and 1e4 <= k <= 1e8):
        raise InputError("--compare", f"{name!r}: a tire stiffness of 1e4 .. 1e8 N/m is expected")
    return k


#: The report's ride: road class, first seed, duration (s), road realisations, tire law and parameter sets
#: (``report --static`` adds a compression test's static stiffness).
REPORT_RIDE = {"road_class": "B", "seed": 1, "duration_s": 60.0, "realisations": 30, "tires": "auto",
               "names": ("paper", "final")}


def ride_comparison(rec, names, *, road_class: str = "B", seed: int = 1, speed_m_s: float | None = None,
                    duration_s: float = 60.0, seat_x_m: float | None = None, seat_y: float = 0.0,
                    exposure_h: float | None = 8.0, diagnosis=None, workers: int = 1, ssp_dir=None,
                    realisations: int = 1, tires: str = "linear", seat_height_m: float | None = None,
                    body_doc=None) -> tuple:
    """The recording's tractor on ISO 8608 roads with each parameter set: (runs, JSON document).

    Combines :func:`parameter_sets`, :func:`identification.comfort.road.road_profile` (grid ROAD_SPACING_M)
    and :func:`ride`; `speed_m_s` defaults to the recording's; `body_doc` as for :func:`parameter_sets`.  The tractor rides `realisations` roads of the
    class, seeded by :func:`identification.comfort.expected.realisation_seeds` (`seed`'s road first).  The
    document holds the road, the speed, the seat, the body and per set its k, c, the rating of the ride on
    `seed`'s road and (``expected``) every rating's expected value with its intervals and the a_w from the
    road PSD (SI units), as ``cleatfmu ride --json`` prints it.  The returned runs are those on `seed`'s
    road.  With `ssp_dir` every set's ride on that road is also written there as an SSP 1.0 system of FMUs
    (:func:`identification.comfort.ride_ssp.write_ride_ssps`; ``doc["ssp"]``).
    """
    from .contact import contact_summary
    from .expected import expected_set, rating_values, realisation_seeds
    from .road import road_profile
    from .seat_axes import DEFAULT_SEAT_HEIGHT_M, axis_rows

    seeds = realisation_seeds(seed, realisations)
    speed = rec.speed_m_s if speed_m_s is None else float(speed_m_s)
    body, sets, how = parameter_sets(rec, names, diagnosis=diagnosis, workers=workers, body_doc=body_doc,
                                     speed_m_s=speed)
    every = []
    for s in seeds:
        road_s = road_profile(road_class, speed * duration_s + 1.0, ROAD_SPACING_M, s)
        every.append(ride(body, sets, road=road_s, speed_m_s=speed, duration_s=duration_s, seat_x_m=seat_x_m,
                          seat_y=seat_y, exposure_h=exposure_h, tires=tires,
                          seat_height_m=seat_height_m))
        if len(every) == 1:
            road = road_s                       # seed's own road: the runs returned, the SSP archives
    runs = every[0]
    seat_x = SEAT_X_FRACTION * body.wheelbase_m if seat_x_m is None else float(seat_x_m)
    height = DEFAULT_SEAT_HEIGHT_M if seat_height_m is None else float(seat_height_m)
    rows = axis_rows(body, seat_x_m=seat_x, seat_y=seat_y, height_m=height, track_width_m=road.track_width_m)
    doc = {"recording": rec.source,
           "road": {"class": road.road_class, "seed": int(seed), "realisations": len(seeds),
                    "length_m": float(road.x_m[-1]), "track_width_m": road.track_width_m,
                    "coherence_decay": road.coherence_decay},
           "speed_m_s": speed, "duration_s": float(duration_s), "tires": tires,
           "seat": {"x_m": seat_x, "y": float(seat_y), "height_m": height, "values": FLOOR_VALUES},
           "body": {"kind": body.kind, "pitch_index": body.pitch_index, "roll_index": body.roll_index,
                    **({"pivot_index": body.pivot_index} if body.pivot else {}), "source": how},
           "sets": {name: r.to_json() for name, r in runs.items()}}
    for name, (k, c) in sets.items():
        per_ride = [{**rating_values(e[name].comfort), **e[name].axes.values()} for e in every]
        doc["sets"][name]["expected"] = expected_set(per_ride, body=body, k=k, c=c, row=rows["z"], road=road,
                                                     speed_m_s=speed, seeds=seeds, rows=rows)
        doc["sets"][name]["expected"]["contact"] = contact_summary([e[name].contact for e in every], body.tires)
        if name.startswith("map="):      # the map's values at the speed, with their bands and extrapolation
            doc["sets"][name]["map"] = map_set(name[4:], speed, body.tires)[2]
    if ssp_dir is not None:
        from .ride_ssp import write_ride_ssps
        paths = write_ride_ssps(ssp_dir, body, sets, road=road, speed_m_s=speed, duration_s=duration_s,
                                seat_x_m=seat_x, seat_y=seat_y)
        doc["ssp"] = {name: str(p) for name, p in paths.items()}
    return runs, doc
