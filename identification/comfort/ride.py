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

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..identify.tire_map import map_set
from ..model.ride import RAMP_M, RideModel, ride_model, seat_row
from ..model.tractor import Body, TractorModel
# the parameter sets moved to .sets; imported here under their former names
from .sets import _fmu_set, _params_set, _stiffness, check_set_names, parameter_sets  # noqa: F401

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
#: What they are with a suspended seat (``ride(..., seat=SeatModel)``).
SEAT_VALUES = ("z on the suspended seat (the occupant), its floor values alongside; x and y are floor values "
               "(the seat's suspension is vertical only)")

#: Default seat position behind the front axle, as a fraction of the wheelbase (a tractor's seat sits
#: ahead of, and close to, the rear axle).
SEAT_X_FRACTION = 0.85
#: Road grid spacing, m.  The road is interpolated linearly between its points, which attenuates short
#: wavelengths: on an ISO 8608 class C road at 7.2 km/h a 5 cm grid lowers the seat's a_w by 3 %, a 1 cm
#: grid by 0.2 % (``tests/test_ride.py``, against the spectral prediction).
ROAD_SPACING_M = 0.01


@dataclass(frozen=True, eq=False)
class RideRun:
    """One parameter set's ride: the tires, the seat's acceleration and its ISO 2631-1 rating.

    With a suspended seat, `seat_m_s2`, `comfort` and the z axis of `axes` are the occupant's, and
    `suspension` (:class:`~identification.comfort.seat.SeatRide`) holds the floor's rating, the SEAT factor
    and the end stops' contacts."""

    name: str
    k: dict                    # tire -> N/m
    c: dict                    # tire -> N s/m
    time_s: np.ndarray
    seat_m_s2: np.ndarray
    comfort: object            # ComfortResult (Wk)
    contact: dict | None = None  # the law rated ("linear" or "lift-off"), tension and lost contact per tire
    axes: object = None        # ThreeAxisResult: the seat's x, y, z
    suspension: object = None  # SeatRide: the suspended seat on the floor (None: the seat is the floor)
    footprints: dict | None = None   # tire -> footprint length, m (the road averaged over it), or point contact
    bands: dict | None = None        # axis -> ThirdOctave of the seat's weighted acceleration (x, y Wd; z Wk)

    def to_json(self) -> dict:
        doc = {"k": self.k, "c": self.c, **self.comfort.to_json()}
        if self.footprints:
            doc["footprint_m"] = self.footprints
        if self.bands:
            doc["third_octave"] = {axis: b.to_json() for axis, b in self.bands.items()}
        if self.contact is not None:
            doc["contact"] = self.contact
        if self.axes is not None:
            doc["three_axes"] = self.axes.to_json()
        if self.suspension is not None:
            doc["suspended_seat"] = self.suspension.to_json()
        return doc


def ride(body: Body, sets: dict, *, road, speed_m_s: float, duration_s: float, seat_x_m: float | None = None,
         seat_y: float = 0.0, step_s: float = 1e-3, exposure_h: float | None = None, tires: str = "linear",
         seat_height_m: float | None = None, seat=None, footprints: dict | None = None) -> dict:
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
    seat : SeatModel, optional
        A suspended seat (:mod:`identification.comfort.seat`) on the floor at the seat's point, stepped
        from the start of the ride: the z axis is rated on it (x and y stay floor values).
    footprints : dict, optional
        Set name -> {tire: footprint length, m}: those tires roll on their track averaged over the footprint
        (the diagnosis's ``enveloping``; :func:`identification.model.ride.enveloped_track`), the others on
        the point under them.

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
    from .seat import seat_ride

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
        fp = (footprints or {}).get(name) or {}
        laws = [_point_contact(k[t], c[t], load, fp.get(t, 0.0)) for t, load in zip(body.tires, body.loads_n)]
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
        qdd = np.linalg.lstsq(J, np.asarray(traj.hub_accel_m_s2), rcond=None)[0]
        suspension = None if seat is None else seat_ride(seat, rows["z"] @ qdd, 1.0 / step_s, keep=keep,
                                                         exposure_h=exposure_h)
        qdd = qdd[:, keep]
        z = rows["z"] @ qdd if seat is None else suspension.response.seat_m_s2
        rating = comfort(z, 1.0 / step_s, "Wk", exposure_h=exposure_h) if seat is None else suspension.seat
        out[name] = RideRun(name, {t: float(k[t]) for t in body.tires}, {t: float(c[t]) for t in body.tires},
                            traj.time_s[keep], z, rating, contact,
                            three_axis(rows["x"] @ qdd, rows["y"] @ qdd, z, 1.0 / step_s, exposure_h=exposure_h),
                            suspension, {t: float(fp[t]) for t in body.tires if fp.get(t)} or None,
                            _seat_bands(rows["x"] @ qdd, rows["y"] @ qdd, z, 1.0 / step_s))
    return out


def _seat_bands(acc_x, acc_y, acc_z, sample_rate_hz: float) -> dict | None:
    """One-third-octave band spectra of the seat's weighted accelerations (x, y Wd; z Wk) over each
    weighting's band, or None where the ride is too short for the lowest band."""
    from .iso2631 import get_weighting, weight
    from .seat_axes import AXIS_WEIGHTINGS
    from .spectra import third_octave

    out = {}
    for axis, acc in (("x", acc_x), ("y", acc_y), ("z", acc_z)):
        w = get_weighting(AXIS_WEIGHTINGS[axis])
        try:
            out[axis] = third_octave(weight(acc, sample_rate_hz, w), sample_rate_hz, low_hz=w.band_hz[0],
                                     high_hz=w.band_hz[1])
        except InputError:
            return None
    return out


def _point_contact(k: float, c: float, load: float, footprint_m: float = 0.0) -> dict:
    """The tire law of a ride: k, c under its static load; with a footprint (m) the road is averaged over it
    with a parabolic pressure (:func:`identification.model.ride.enveloped_track`), as the diagnosis's
    ``enveloping`` averages the cleat."""
    from ..model import tire_law

    law = dict(tire_law.EXTENDED_DEFAULTS, stiffness=float(k), damping=float(c), static_load=float(load))
    if footprint_m > 0:
        law.update(footprint_length=float(footprint_m), parabolic_pressure=True)
    return law


#: The report's ride: road class, first seed, duration (s), road realisations, tire law and parameter sets
#: (``report --static`` adds a compression test's static stiffness).
REPORT_RIDE = {"road_class": "B", "seed": 1, "duration_s": 60.0, "realisations": 30, "tires": "auto",
               "names": ("paper", "final")}


def _seat_class(seat, body) -> dict:
    """The seat's SEAT factor on the ISO 5007 input class of the tractor's mass (from its static wheel loads,
    ballast included; the standard classes by unladen mass)."""
    from ..recording import STANDARD_GRAVITY
    from .seat import class_of_mass, class_seat_factor

    mass = sum(body.loads_n) / STANDARD_GRAVITY
    return {"tractor_mass_kg": mass, **class_seat_factor(seat, class_of_mass(mass))}


def ride_comparison(rec, names, *, road_class: str = "B", seed: int = 1, speed_m_s: float | None = None,
                    duration_s: float = 60.0, seat_x_m: float | None = None, seat_y: float = 0.0,
                    exposure_h: float | None = 8.0, diagnosis=None, workers: int = 1, ssp_dir=None,
                    realisations: int = 1, tires: str = "linear", seat_height_m: float | None = None,
                    body_doc=None, seat=None, road=None, enveloping: bool = True) -> tuple:
    """The recording's tractor on ISO 8608 roads with each parameter set: (runs, JSON document).

    Combines :func:`parameter_sets`, :func:`identification.comfort.road.road_profile` (grid ROAD_SPACING_M)
    and :func:`ride`; `speed_m_s` defaults to the recording's; `body_doc` as for :func:`parameter_sets`.  The tractor rides `realisations` roads of the
    class, seeded by :func:`identification.comfort.expected.realisation_seeds` (`seed`'s road first).  The
    document holds the road, the speed, the seat, the body and per set its k, c, the rating of the ride on
    `seed`'s road and (``expected``) every rating's expected value with its intervals and the a_w from the
    road PSD (SI units), as ``cleatfmu ride --json`` prints it.  The returned runs are those on `seed`'s
    road.  With `ssp_dir` every set's ride on that road is also written there as an SSP 1.0 system of FMUs
    (:func:`identification.comfort.ride_ssp.write_ride_ssps`; ``doc["ssp"]``).  With `seat` (a
    :class:`~identification.comfort.seat.SeatModel`) the occupant rides a suspended seat (:func:`ride`): the
    z ratings are the seat's, each set's ``suspended_seat`` holds the floor's, the SEAT factor and the end
    stops, with their expected values; the SSP systems hold the floor only.  `road`: None, or a dict of
    further :func:`~identification.comfort.road.road_profile` keywords for the generated roads (e.g.
    ``{"coherence": "class"}``), or a RoadProfile to ride on alone (one ride; `road_class`, `realisations` unused).
    With `enveloping` (the default), where the diagnosis named ``enveloping``, every set's tires roll with the
    footprints it fitted (the tires' geometry; the sets differ in k and c; ``sets.<name>.footprint_m``).  The
    SSP systems hold point-contact tires only: `ssp_dir` with such footprints is refused.
    """
    from .contact import contact_summary
    from .expected import expected_set, rating_values, realisation_seeds
    from .road import RoadProfile, road_profile
    from .seat_axes import DEFAULT_SEAT_HEIGHT_M, axis_rows

    given = road if isinstance(road, RoadProfile) else None        # a road read from a file: one ride on it
    options = dict(road or {}) if given is None else {}             # further road_profile keywords
    seeds = realisation_seeds(seed, 1 if given is not None else realisations)
    speed = rec.speed_m_s if speed_m_s is None else float(speed_m_s)
    body, sets, how, footprint = parameter_sets(rec, names, diagnosis=diagnosis, workers=workers,
                                                body_doc=body_doc, speed_m_s=speed)
    footprints = {name: footprint for name in sets} if enveloping and footprint else {}
    if footprints and ssp_dir is not None:
        raise InputError("--ssp", "the tires ride with the footprints the diagnosis fitted (enveloping), which "
                                  "the SSP systems' point-contact tires cannot carry; add --enveloping off to "
                                  "ride and write every set at point contact")
    every = []
    for s in seeds:
        road_s = given if given is not None else road_profile(road_class, speed * duration_s + 1.0, ROAD_SPACING_M,
                                                              s, **options)
        every.append(ride(body, sets, road=road_s, speed_m_s=speed, duration_s=duration_s, seat_x_m=seat_x_m,
                          seat_y=seat_y, exposure_h=exposure_h, tires=tires,
                          seat_height_m=seat_height_m, seat=seat, footprints=footprints))
        if len(every) == 1:
            road = road_s                       # seed's own road: the runs returned, the SSP archives
    runs = every[0]
    seat_x = SEAT_X_FRACTION * body.wheelbase_m if seat_x_m is None else float(seat_x_m)
    height = DEFAULT_SEAT_HEIGHT_M if seat_height_m is None else float(seat_height_m)
    rows = axis_rows(body, seat_x_m=seat_x, seat_y=seat_y, height_m=height, track_width_m=road.track_width_m)
    doc = {"recording": rec.source,
           "road": {"class": road.road_class, "seed": int(seed), "realisations": len(seeds),
                    "length_m": float(road.x_m[-1]), "track_width_m": road.track_width_m,
                    "coherence_decay": road.coherence_decay, "coherence": road.coherence_model},
           "speed_m_s": speed, "duration_s": float(duration_s), "tires": tires,
           "seat": {"x_m": seat_x, "y": float(seat_y), "height_m": height,
                    "values": FLOOR_VALUES if seat is None else SEAT_VALUES,
                    **({} if seat is None else {"suspension": seat.to_json(), "iso5007": _seat_class(seat, body)})},
           "body": {"kind": body.kind, "pitch_index": body.pitch_index, "roll_index": body.roll_index,
                    **({"pivot_index": body.pivot_index} if body.pivot else {}), "source": how},
           "sets": {name: r.to_json() for name, r in runs.items()}}
    for name, (k, c) in sets.items():
        per_ride = [{**rating_values(e[name].comfort), **e[name].axes.values(),
                     **(e[name].suspension.values() if seat is not None else {})} for e in every]
        doc["sets"][name]["expected"] = expected_set(per_ride, body=body, k=k, c=c, row=rows["z"], road=road,
                                                     speed_m_s=speed, seeds=seeds, rows=rows, seat=seat,
                                                     footprints_m=footprints.get(name))
        doc["sets"][name]["expected"]["contact"] = contact_summary([e[name].contact for e in every], body.tires)
        if all(e[name].bands for e in every):        # the seat's expected band spectra over the roads
            from .spectra import expected_bands
            doc["sets"][name]["expected"]["third_octave"] = {
                axis: expected_bands([e[name].bands[axis] for e in every]).to_json() for axis in ("x", "y", "z")}
        if name.startswith("map="):      # the map's values at the speed, with their bands and extrapolation
            doc["sets"][name]["map"] = map_set(name[4:], speed, body.tires)[2]
    if "final" in sets and len(every) > 1:    # paired on the same roads: the road-to-road scatter cancels
        from .expected import summarise
        for name in sets:
            if name != "final":
                doc["sets"][name]["expected"]["a_w_ratio_to_final"] = summarise(
                    [e[name].comfort.a_w / e["final"].comfort.a_w for e in every])
    if ssp_dir is not None:
        from .ride_ssp import write_ride_ssps
        paths = write_ride_ssps(ssp_dir, body, sets, road=road, speed_m_s=speed, duration_s=duration_s,
                                seat_x_m=seat_x, seat_y=seat_y)
        doc["ssp"] = {name: str(p) for name, p in paths.items()}
    return runs, doc
