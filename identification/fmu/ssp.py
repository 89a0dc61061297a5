"""The whole tractor as a system of FMUs: a native body FMU, four tire FMUs and an SSP 1.0 file.

:func:`write_tractor_ssp` packages a model record (:class:`identification.model.TractorModel`,
the rigid or pivoting-front-axle tractor) as ``NAME.ssp``, a zip of

* ``SystemStructure.ssd`` - the system (SSP 1.0): the components, their connectors
  with units, the connections and the default experiment;
* ``resources/body.fmu`` - the body (FMU kind ``tractor_body``, native C): the
  record's body (the rigid tractor: heave, pitch, roll and the front axle's
  roll; or half tractors, or corners) on the four tire forces, hub heights,
  velocities and longitudinal positions out, hub and seat accelerations;
* ``resources/FL.fmu`` ... ``RR.fmu`` - one native extended tire FMU per wheel,
  its built-in cleat placed in the system's road coordinates;
* for a ride (:class:`identification.model.ride.RideModel`) ``resources/road.fmu``
  - the road profile (FMU kind ``road_profile``, native C, its table in its
  resources): the road height and rate under each tire, connected to the
  tires' ``road_z`` and ``road_vz``.

Connections: ``body.hub_z_<T> -> T.hub_z``, ``body.hub_vz_<T> -> T.hub_vz``,
``body.hub_x_<T> -> T.hub_x``, ``body.hub_vx -> T.hub_vx`` and ``T.force_z -> body.force_<T>``.
The body has no direct feedthrough from the forces to the hub motion, so any
exchange order runs the system without an algebraic loop.

Road coordinates: the front axle is at ``start_x`` + v t, a rear hub one
wheelbase behind.  The model record gives each tire x = v (t − arrival) +
cleat_x, so the tire FMU of the system has its cleat at ``start_x`` − offset +
v · arrival + 0 (offset 0 front, the wheelbase rear) and its lug phase shifted
by the same distance: the tire sees exactly the record's road.
"""

from __future__ import annotations

import math
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._files import temp_prefix, xml_text
from ..model import TractorModel
from ..recording import FRONT_TIRES, TIRES

__all__ = ["ROAD", "SystemLayout", "system_layout", "body_seat_row", "write_tractor_ssp", "BODY", "SSD_NAME", "CONNECTIONS"]

BODY = "body"
ROAD = "road"
SSD_NAME = "SystemStructure.ssd"
_NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
       "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
       "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
#: (body connector, tire connector, direction) per tire T; "out" = body -> tire.
CONNECTIONS = (("hub_z_{t}", "hub_z", "out"), ("hub_vz_{t}", "hub_vz", "out"), ("hub_x_{t}", "hub_x", "out"),
               ("hub_vx", "hub_vx", "out"), ("force_{t}", "force_z", "in"))


@dataclass(frozen=True)
class SystemLayout:
    """The start values of the body FMU and of each tire FMU of the system (SI units)."""

    body: dict                 # tractor_body start values
    tires: dict                # tire -> extended_tire start values
    road: dict | None          # road_profile start values (a ride's road profile), or None (a cleat run)
    road_table: bytes | None   # the road_profile FMU's profile table
    static_hub_z: np.ndarray   # m, per tire (the record's closed form at the start)
    start_s: float


def system_layout(record: TractorModel, *, start_s: float, seat_x_m: float, seat_y: float = 0.0,
                  start_x_m: float = 0.0, initial_q=None, initial_dq=None) -> SystemLayout:
    """The body's and the tires' start values that make the FMU system the model record.

    Parameters
    ----------
    record : TractorModel
        Four tires under any body (the rigid tractor with or without a
        pivoting front axle, half tractors per side or axle, four corners),
        each carrying the cleat itself (built-in cleat), or no cleat.
    start_s : float
        Start time of the run, s (the body starts at rest there, or in the
        record's initial state).
    seat_x_m, seat_y : float
        Seat position behind the front axle (m) and from the centre line as a
        fraction of the half-track (+ left).
    start_x_m : float
        Position of the front axle at time 0 in road coordinates, m.
    initial_q, initial_dq : array_like, optional
        The body's coordinates (heave m, pitch rad, roll and front-axle roll
        scaled by the half-track, m) and their rates at the start (default:
        the record's initial state: rest, or the steady state under lugs).
    """
    body = record.body
    if tuple(body.tires) != TIRES:
        raise ValueError(f"the FMU system needs the four tires {', '.join(TIRES)}; got {', '.join(body.tires)}")
    for i, t in enumerate(record.tires):
        if record.cleat.height_m > 0.0 and not record.builtin_cleat(i):
            raise ValueError(f"tire {t} sees the cleat as a road input (point contact); in the FMU system every "
                             f"tire carries its cleat itself (extended tire with cleat_height > 0)")
    v = float(record.cleat.speed_m_s)
    inputs = record.inputs(start_s, 1.0, 1)
    x0 = inputs.hub_x[:, 0]
    static_z = record.static_hub_z(x0)
    q0, dq0 = record.initial_state(start_s, x0, inputs.hub_vx[:, 0])
    J, _, _ = body.matrices()
    u0 = J @ np.asarray(q0 if initial_q is None else initial_q, dtype=float)
    du0 = J @ np.asarray(dq0 if initial_dq is None else initial_dq, dtype=float)
    starts = {f"load_{t}": float(w) for t, w in zip(TIRES, body.loads_n)}
    starts.update({f"static_hub_z_{t}": float(z) for t, z in zip(TIRES, static_z)})
    starts.update({"wheelbase": float(body.wheelbase_m), "pitch_index": float(body.pitch_index),
                   "roll_index": float(body.roll_index), "pitch_coupling": bool(body.pitch),
                   "roll_coupling": bool(body.roll), "front_axle_pivot": bool(body.pivot),
                   "pivot_index": float(body.pivot_index), "speed": v, "start_x": float(start_x_m),
                   "seat_x": float(seat_x_m), "seat_y": float(seat_y)})
    starts.update({f"initial_hub_dz_{t}": float(u) for t, u in zip(TIRES, u0)})
    starts.update({f"initial_hub_vz_{t}": float(u) for t, u in zip(TIRES, du0)})
    tires = {}
    for t, law, arrival in zip(TIRES, record.laws, record.arrivals_s):
        offset = 0.0 if t in FRONT_TIRES else float(body.wheelbase_m)
        # x_system = start_x + v t − offset; x_record = v (t − arrival) + cleat_x
        shift = float(start_x_m) - offset + v * float(arrival) - float(law["cleat_x"])   # x_system − x_record
        p = dict(law)
        p["cleat_x"] = float(law["cleat_x"]) + shift
        if law["lug_amplitude"] != 0.0:
            p["lug_phase"] = float(law["lug_phase"]) - 2.0 * math.pi / float(law["lug_pitch"]) * shift
        p["hub_x"] = float(start_x_m) + v * start_s - offset
        p["hub_vx"] = v
        p["hub_z"] = float(static_z[TIRES.index(t)])
        tires[t] = p
    road = table = None
    if getattr(record, "road_x_m", None) is not None:          # a ride: the road profile is an FMU too
        from build_scripts.road_table import road_table_bytes

        from ..model.ride import RAMP_M

        road = {"speed": v, "start_x": float(record.road_x_m[0]), "wheelbase": float(max(record.offsets_m)),
                "ramp_length": float(RAMP_M)}
        table = road_table_bytes(record.road_x_m, record.road_left_m, record.road_right_m)
    return SystemLayout(body=starts, tires=tires, road=road, road_table=table,
                        static_hub_z=np.asarray(static_z, dtype=float), start_s=float(start_s))


def body_seat_row(body, *, seat_x_m: float, seat_y: float = 0.0) -> np.ndarray:
    """The seat's displacement per generalized coordinate of `body` (as the body FMU computes it).

    The whole tractor (rigid or pivoting front axle): its motion at the seat
    (:func:`identification.model.ride.seat_row`).  A body without both
    couplings has no single motion at the seat: the hubs' displacements are
    interpolated bilinearly there (x from front to rear axle, y across the track).
    """
    from ..model.ride import seat_row

    if body.kind in ("rigid", "pivot"):
        return seat_row(body, seat_x_m=seat_x_m, seat_y=seat_y)
    J, _, _ = body.matrices()
    xi = seat_x_m / body.wheelbase_m
    w = {"FL": (1 - xi) * 0.5 * (1 + seat_y), "FR": (1 - xi) * 0.5 * (1 - seat_y),
         "RL": xi * 0.5 * (1 + seat_y), "RR": xi * 0.5 * (1 - seat_y)}
    return np.array([w[t] for t in body.tires]) @ J


def write_tractor_ssp(path, record: TractorModel, *, start_s: float, stop_s: float, step_s: float,
                      seat_x_m: float, seat_y: float = 0.0, name: str = "tractor",
                      description: str = "", initial_q=None, initial_dq=None) -> Path:
    """Write the model record as an SSP 1.0 archive (see the module docstring); returns `path`.

    Parameters
    ----------
    path : path-like
        The ``.ssp`` file, written atomically (nothing is left at `path` on failure).
    record : TractorModel
        The whole tractor (see :func:`system_layout`).
    start_s, stop_s, step_s : float
        The default experiment and the communication step it was made for, s.
    seat_x_m, seat_y : float
        Seat position (see :func:`system_layout`).
    name, description : str
        The system's name and description in the SSD.
    initial_q, initial_dq : array_like, optional
        The body's initial coordinates and rates (see :func:`system_layout`).
    """
    from build_scripts import build_fmu
    from build_scripts.reproducible import zip_bytes

    from .._files import publish_files

    path = Path(path)
    if path.suffix != ".ssp":
        raise ValueError(f"{path}: an SSP file name must end with .ssp")
    if not (stop_s > start_s and step_s > 0):
        raise ValueError(f"the experiment needs stop > start and step > 0, got {start_s}, {stop_s}, {step_s}")
    layout = system_layout(record, start_s=start_s, seat_x_m=seat_x_m, seat_y=seat_y, initial_q=initial_q,
                           initial_dq=initial_dq)
    files = {}
    with tempfile.TemporaryDirectory(prefix=temp_prefix("ssp")) as tmp:
        body = build_fmu("tractor_body", Path(tmp, "body.fmu"), backend="native", start_values=layout.body,
                         description=f"Body of system '{name}': {_KIND_TEXT[record.body.kind]} (SI units)")
        files[f"resources/{BODY}.fmu"] = body.read_bytes()
        if layout.road is not None:
            from build_scripts.road_table import ROAD_FILE

            road = build_fmu("road_profile", Path(tmp, f"{ROAD}.fmu"), backend="native", start_values=layout.road,
                             resources={ROAD_FILE: layout.road_table},
                             description=f"Road of system '{name}': two-track profile (SI units)")
            files[f"resources/{ROAD}.fmu"] = road.read_bytes()
        for t, starts in layout.tires.items():
            fmu = build_fmu("extended_tire", Path(tmp, f"{t}.fmu"), backend="native", start_values=starts,
                            description=f"Tire {t} of system '{name}': extended tire, cleat in the system's road "
                                        f"coordinates (SI units)")
            files[f"resources/{t}.fmu"] = fmu.read_bytes()
        files[SSD_NAME] = ssd_bytes(name, description, start_s=start_s, stop_s=stop_s, step_s=step_s,
                                    road=layout.road is not None)
        staged = Path(tmp, path.name)
        staged.write_bytes(zip_bytes(files))
        publish_files({path: staged})
    return path


_KIND_TEXT = {"rigid": "rigid tractor", "pivot": "rigid tractor with pivoting front axle",
              "sides": "half tractor per side (heave and pitch)", "axles": "half tractor per axle (heave and roll)",
              "corners": "four independent corners"}


def _connector(parent, name: str, kind: str, unit: str | None) -> None:
    c = ET.SubElement(parent, f"{{{_NS['ssd']}}}Connector", {"name": name, "kind": kind})
    ET.SubElement(c, f"{{{_NS['ssc']}}}Real", {"unit": unit} if unit else {})


#: unit of each connector of the body and of a tire.
_UNITS = {"road_z": "m", "road_vz": "m/s", "hub_z": "m", "hub_vz": "m/s", "hub_x": "m", "hub_vx": "m/s", "force": "N", "force_z": "N",
          "hub_az": "m/s2", "seat_z": "m", "seat_az": "m/s2"}
_BASE = {"m": {"m": "1"}, "m/s": {"m": "1", "s": "-1"}, "N": {"kg": "1", "m": "1", "s": "-2"},
         "m/s2": {"m": "1", "s": "-2"}}


def _unit(connector: str) -> str:
    stem = connector.rsplit("_", 1)[0] if connector.rsplit("_", 1)[-1] in TIRES else connector
    return _UNITS[stem]


def ssd_bytes(name: str, description: str, *, start_s: float, stop_s: float, step_s: float,
              road: bool = False) -> bytes:
    """``SystemStructure.ssd`` of the tractor system (SSP 1.0); with `road` the road FMU after the body."""
    for prefix, uri in _NS.items():
        ET.register_namespace(prefix, uri)
    d, c = _NS["ssd"], _NS["ssc"]
    name, description = xml_text(name), xml_text(description) if description else description
    root = ET.Element(f"{{{d}}}SystemStructureDescription", {"version": "1.0", "name": name})
    system = ET.SubElement(root, f"{{{d}}}System", {"name": name, **({"description": description}
                                                                        if description else {})})
    elements = ET.SubElement(system, f"{{{d}}}Elements")
    body = ET.SubElement(elements, f"{{{d}}}Component", {"name": BODY, "source": f"resources/{BODY}.fmu",
                                                        "type": "application/x-fmu-sharedlibrary"})
    body_connectors = ET.SubElement(body, f"{{{d}}}Connectors")
    body_inputs = [f"force_{t}" for t in TIRES]
    body_outputs = [f"{q}_{t}" for q in ("hub_z", "hub_vz", "hub_x") for t in TIRES] + ["hub_vx"]
    body_outputs += [f"hub_az_{t}" for t in TIRES] + ["seat_z", "seat_az"]
    for n in body_inputs:
        _connector(body_connectors, n, "input", _unit(n))
    for n in body_outputs:
        _connector(body_connectors, n, "output", _unit(n))
    if road:
        comp = ET.SubElement(elements, f"{{{d}}}Component", {"name": ROAD, "source": f"resources/{ROAD}.fmu",
                                                            "type": "application/x-fmu-sharedlibrary"})
        conns = ET.SubElement(comp, f"{{{d}}}Connectors")
        for n in [f"{q}_{t}" for q in ("road_z", "road_vz") for t in TIRES]:
            _connector(conns, n, "output", _unit(n))
    for t in TIRES:
        comp = ET.SubElement(elements, f"{{{d}}}Component", {"name": t, "source": f"resources/{t}.fmu",
                                                            "type": "application/x-fmu-sharedlibrary"})
        conns = ET.SubElement(comp, f"{{{d}}}Connectors")
        for n in ("hub_z", "hub_vz", "hub_x", "hub_vx") + (("road_z", "road_vz") if road else ()):
            _connector(conns, n, "input", _unit(n))
        _connector(conns, "force_z", "output", "N")
    connections = ET.SubElement(system, f"{{{d}}}Connections")
    for t in TIRES:
        for body_name, tire_name, direction in CONNECTIONS:
            b = body_name.format(t=t)
            ends = ((BODY, b), (t, tire_name)) if direction == "out" else ((t, tire_name), (BODY, b))
            ET.SubElement(connections, f"{{{d}}}Connection", {
                "startElement": ends[0][0], "startConnector": ends[0][1],
                "endElement": ends[1][0], "endConnector": ends[1][1]})
        if road:
            for q in ("road_z", "road_vz"):
                ET.SubElement(connections, f"{{{d}}}Connection", {
                    "startElement": ROAD, "startConnector": f"{q}_{t}", "endElement": t, "endConnector": q})
    units = ET.SubElement(root, f"{{{d}}}Units")
    for unit, exponents in _BASE.items():
        u = ET.SubElement(units, f"{{{c}}}Unit", {"name": unit})
        ET.SubElement(u, f"{{{c}}}BaseUnit", exponents)
    experiment = ET.SubElement(root, f"{{{d}}}DefaultExperiment", {"startTime": repr(float(start_s)),
                                                                    "stopTime": repr(float(stop_s))})
    annotations = ET.SubElement(experiment, f"{{{d}}}Annotations")
    note = ET.SubElement(annotations, f"{{{c}}}Annotation", {"type": "org.cleatfmu.experiment"})
    ET.SubElement(note, "Step", {"size": repr(float(step_s)), "exchange": "any"})
    # the step as the Open Simulation Platform's hosts read it (libcosim: without it, an execution created
    # from the SSP alone has no algorithm)
    osp = ET.SubElement(annotations, f"{{{c}}}Annotation", {"type": "com.opensimulationplatform"})
    ET.SubElement(ET.SubElement(osp, f"{{{_NS['osp']}}}Algorithm"), f"{{{_NS['osp']}}}FixedStepAlgorithm",
                  {"baseStepSize": repr(float(step_s))})
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"
