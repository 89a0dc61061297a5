"""Quarter-tractor co-simulation: the tire FMU under a corner mass, driven over the cleat with fmpy.

The master owns the body - a corner mass m = W / g under gravity - and the
road; the tire FMU (FMI 2.0 co-simulation) is the force element between them.
Per communication step h the master makes exactly one ``doStep``, one
``setReal`` and one ``getReal`` call.

Coupling scheme (no one-step delay)
-----------------------------------
The tire's force output has direct feedthrough, so the master reads the force
*for the state it has just set*, not the previous step's.  With
a_n = F_n / m − g:

1. position  z_{n+1} = z_n + h v_n + h²/2 a_n;
2. predicted velocity  v* = v_n + h a_n;
3. ``doStep(t_n, h)``; set hub (z_{n+1}, v*) and road (r_{n+1}, ṙ_{n+1});
   read F_{n+1};
4. velocity  v_{n+1} = v_n + h/2 (a_n + a_{n+1}).

Every force is evaluated at the current time with current inputs, so there is
no coupling delay and hence no artificial negative damping k·τ; the only
error is the scheme's truncation error, second order in h: the position is
exact to O(h³) per step, the predicted velocity to O(h²), which enters the
force through c and is corrected by the trapezoidal velocity update.  For the
linear tire the scheme is the trapezoidal rule with an explicit velocity
predictor; it is stable for ω_n h < 2 and its relative decay-rate error is
O((ω_n h)²) (checked against python-control in the tests).

The discrete scheme itself, the cleat on the grid and the impulse
bookkeeping are in :mod:`identification.model.scheme`, shared with the fitting
models of the diagnosis.

Before the first step the master finds the static equilibrium itself (secant
iterations on F(z) = m g at rest), as an importer whose body includes gravity
must.
"""

from __future__ import annotations

import ctypes
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .master import _WARNING, fmi_error, step_body_fmus, step_fn
from ..model.scheme import Trajectory, cleat_grid, corner_body, grid_inputs, half_tractor_body, lug_steady_state, tire_inputs
from .._files import temp_prefix

__all__ = ["TireFmu", "step_fn", "run_quarter_tractor", "run_half_tractor_fmus"]

#: Names of the tire FMU's interface (inputs, parameters, output); the
#: longitudinal inputs exist only in tires that know the cleat themselves.
INPUTS = ("hub_z", "hub_vz", "road_z", "road_vz")
LONGITUDINAL = ("hub_x", "hub_vx")
PARAMETERS = ("stiffness", "damping", "unloaded_radius")
FORCE = "force_z"


class TireFmu:
    """An instantiated tire FMU (fmpy ``FMU2Slave``), usable as a context manager.

    Set-up, parameters and closing go through fmpy; the per-step exchange
    (:meth:`force_fn`, :func:`step_fn`) calls the FMU's ``fmi2SetReal``,
    ``fmi2GetReal`` and ``fmi2DoStep`` directly, on arrays allocated once.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.
    start_values : dict, optional
        Parameter values to set before initialization (name -> value).
    instance_name : str
    """

    def __init__(self, path, *, start_values: dict | None = None, instance_name: str = "tire"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        path = Path(path)
        if not path.is_file():
            raise InputError(path, "no such file" if not path.exists() else "is a directory, not a file"
                             if path.is_dir() else "is not a regular file (a pipe or a device)")
        try:
            self.md = read_model_description(str(path))
        except Exception as exc:  # fmpy raises several types for a bad archive
            raise InputError(path, f"not a readable FMU ({exc.__class__.__name__}: {exc})") from None
        if self.md.fmiVersion != "2.0":
            raise InputError(path, f"an FMI {self.md.fmiVersion} FMU: the co-simulation here runs FMI 2.0 FMUs "
                                   "(export it with --fmi-version 2)")
        if self.md.coSimulation is None:
            raise InputError(path, "the FMU does not support co-simulation")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        missing = [n for n in INPUTS + PARAMETERS + (FORCE,) if n not in self.vr]
        if missing:
            raise InputError(path, f"not a cleatfmu tire FMU: missing variable(s) {', '.join(missing)}")
        self.path = path
        self.longitudinal = all(n in self.vr for n in LONGITUDINAL)
        _check_binary(path, self.md.coSimulation.modelIdentifier)
        self.slave = None
        self._dir = tempfile.mkdtemp(prefix=temp_prefix("fmu"))
        try:
            extract(str(path), self._dir, include=_loaded_member)
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance_name)
            self.slave.instantiate()
        except BaseException as exc:   # nothing extracted stays behind; a library that would not load is named
            if self.slave is not None and getattr(self.slave, "component", None) is None:
                self.slave = None
            shutil.rmtree(self._dir, ignore_errors=True)
            if isinstance(exc, Exception) and not isinstance(exc, InputError):
                why = exc.__class__.__name__
                if isinstance(exc, OSError) and exc.strerror:      # e.g. a full disk while extracting it
                    why += f": {exc.strerror}"
                raise InputError(path, f"cannot instantiate the FMU here ({why})") from None
            raise
        self._initialized = False
        self._start_values = dict(start_values or {})
        self.input_vrs = [self.vr[n] for n in INPUTS + (LONGITUDINAL if self.longitudinal else ())]
        self.force_vr = [self.vr[FORCE]]
        self._raw = _RawFmi2(self.slave, self.input_vrs, self.force_vr[0])

    def initialize(self, t0: float) -> None:
        """Set the start values and initialize at `t0`; an initialized instance is reset first (``fmi2Reset``:
        every variable back to its start value), so it starts afresh as a new instance would."""
        s = self.slave
        if self._initialized:
            self._initialized = False
            s.reset()
        s.setupExperiment(startTime=t0)
        if self._start_values:
            reals = {n: v for n, v in self._start_values.items() if not isinstance(v, bool)}
            bools = {n: v for n, v in self._start_values.items() if isinstance(v, bool)}
            if reals:
                s.setReal([self.vr[n] for n in reals], [float(v) for v in reals.values()])
            if bools:
                s.setBoolean([self.vr[n] for n in bools], list(bools.values()))
        s.enterInitializationMode()
        s.exitInitializationMode()
        self._initialized = True

    def parameters(self) -> dict[str, float | bool]:
        """Current values of the parameters: the Real ones as floats, the Boolean ones
        (``unilateral``, ``parabolic_pressure``, if the FMU has them) as bools."""
        params = [v for v in self.md.modelVariables if v.causality == "parameter"]
        names = [v.name for v in params if v.type == "Real"]
        values = dict(zip(names, self.slave.getReal([self.vr[n] for n in names])))
        flags = [v.name for v in params if v.type == "Boolean"]
        if flags:
            values.update(zip(flags, (bool(b) for b in self.slave.getBoolean([self.vr[n] for n in flags]))))
        return values

    def set_start_values(self, values: dict) -> None:
        """Set parameters (name -> value) for the next :meth:`initialize`; names the FMU lacks are left out."""
        self._start_values.update({n: v for n, v in values.items() if n in self.vr})

    def envelops_test_cleat(self) -> bool:
        """A tire with a footprint and its built-in cleat off (as exported): it rides a cleat only as its
        built-in one (after initialize)."""
        p = self.parameters()
        return self.longitudinal and p.get("footprint_length", 0.0) > 0.0 and p.get("cleat_height", 0.0) == 0.0

    def switch_on_test_cleat(self, t0: float, *, height_m: float, width_m: float, profile=None) -> bool:
        """If :meth:`envelops_test_cleat`, set the test's cleat (`profile`'s bevel) as the built-in one and
        initialize again at `t0` (exported FMUs start with it off, for a ride model's road); whether it did."""
        if not (height_m > 0 and self.envelops_test_cleat()):
            return False
        bevel = 0.0 if profile is None else float(profile.builtin_bevel_m)
        self.set_start_values({"cleat_height": height_m, "cleat_width": width_m, "cleat_bevel": bevel})
        self.initialize(t0)
        return True

    def builtin_cleat(self) -> bool:
        """The tire knows the cleat itself (a built-in cleat): pass a flat road and x (after initialize)."""
        return self.longitudinal and self.parameters().get("cleat_height", 0.0) > 0.0

    def inputs(self, n, start, h, *, arrival_s, speed_m_s, cleat_height_m, cleat_width_m, profile=None):
        """Road and longitudinal inputs for this tire on the grid (after initialize); an external cleat of
        `profile` (:class:`identification.recording.cleat.CleatProfile`) when given and not rectangular."""
        params = self.parameters()
        return tire_inputs(n, start, h, arrival_s=arrival_s, speed_m_s=speed_m_s, cleat_height_m=cleat_height_m,
                           cleat_width_m=cleat_width_m, external_cleat=not self.builtin_cleat(),
                           x_offset_m=params.get("cleat_x", 0.0), profile=profile)

    def force_fn(self):
        """The force callback of :mod:`identification.model.scheme`: ``force(z, vz, x, vx, road_z, road_vz) -> N``,
        one ``fmi2SetReal`` of the inputs and one ``fmi2GetReal`` of the force (a non-longitudinal tire
        ignores x and vx)."""
        set_real, get_real, c, vrs, n_in, values, f_vr, one, out = self.exchange_args()

        def force(z, vz, x, vx, road_z, road_vz):
            values[:] = (z, vz, road_z, road_vz, x, vx)
            status = set_real(c, vrs, n_in, values)
            if status > _WARNING:
                raise fmi_error("fmi2SetReal", status)
            status = get_real(c, f_vr, one, out)
            if status > _WARNING:
                raise fmi_error("fmi2GetReal", status)
            return out[0]
        return force

    def exchange_args(self) -> tuple:
        """What :meth:`force_fn` calls, for a master making the calls inline: (fmi2SetReal, fmi2GetReal,
        component, input value references, their number, input values (6: z, vz, road_z, road_vz, x, vx),
        force value reference, 1, force value), the functions to be called with these ctypes objects only."""
        return self._raw.exchange

    def close(self) -> None:
        """Terminate (if initialized; FMI refuses terminate before that) and free the instance."""
        if self.slave is not None:
            self._raw = None  # the FMU's functions go with its library
            try:
                if self._initialized:
                    self.slave.terminate()
            finally:
                self.slave.freeInstance()
                self.slave = None
                shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


#: The FMU's own functions with the return type only: called with every argument a ctypes object of the
#: C type (fmi2Component, arrays, size_t, fmi2Real, fmi2Boolean), so ctypes converts nothing per call.
_FMI_CALL = ctypes.CFUNCTYPE(ctypes.c_int)


class _RawFmi2:
    """The per-step FMI 2 calls of one instance: its functions, component and preallocated arrays."""

    def __init__(self, slave, input_vrs, force_vr: int):
        def function(name):
            return _FMI_CALL(ctypes.cast(getattr(slave.dll, name), ctypes.c_void_p).value)

        self.component = ctypes.c_void_p(slave.component)
        self.do_step = function("fmi2DoStep")
        n = len(input_vrs)
        values = (ctypes.c_double * 6)()  # x and vx are written even when a tire has no longitudinal inputs
        self.exchange = (function("fmi2SetReal"), function("fmi2GetReal"), self.component,
                         (ctypes.c_uint * n)(*input_vrs), ctypes.c_size_t(n), values,
                         (ctypes.c_uint * 1)(force_vr), ctypes.c_size_t(1), (ctypes.c_double * 1)())


def _check_binary(path: Path, model_identifier: str) -> None:
    """Refuse an FMU without a binary for this machine (before anything is extracted)."""
    import zipfile

    from fmpy import platform, sharedLibraryExtension

    member = f"binaries/{platform}/{model_identifier}{sharedLibraryExtension}"
    try:
        with zipfile.ZipFile(path) as archive:
            present = member in archive.namelist()
    except (OSError, zipfile.BadZipFile) as exc:
        raise InputError(path, f"not a readable FMU ({exc.__class__.__name__}: {exc})") from None
    if not present:
        raise InputError(path, f"has no binary for this machine ({member}); a native FMU is built for every "
                               "platform by default (cleatfmu export --platforms)")


def _loaded_member(name: str) -> bool:
    """The archive members an instance needs: all but the sources, the documentation and other platforms'
    binaries (fmpy loads ``binaries/<platform>/``; FMI 3 names the platform as a tuple)."""
    from fmpy import platform, platform_tuple

    top, _, rest = name.partition("/")
    if top in ("sources", "documentation"):
        return False
    return top != "binaries" or rest.partition("/")[0] in (platform, platform_tuple)


def _check_run(max_step_s, duration_s, speed_m_s):
    if not (max_step_s > 0 and duration_s > max_step_s and speed_m_s > 0):
        raise ValueError("step, duration and speed must be positive (duration > step)")


def run_quarter_tractor(fmu_path, *, mass_kg: float, speed_m_s: float, cleat_height_m: float,
                        cleat_width_m: float, arrival_s: float, t0_s: float, duration_s: float,
                        max_step_s: float, start_values: dict | None = None, step_s: float | None = None,
                        cleat_profile=None):
    """Drive a corner mass on the tire FMU over the cleat.

    Parameters
    ----------
    fmu_path : path-like
        Tire FMU (inputs hub_z, hub_vz, road_z, road_vz [, hub_x, hub_vx]; output force_z).
    mass_kg : float
        Corner mass m = W / g, kg.
    speed_m_s, cleat_height_m, cleat_width_m : float
        Driving speed (m/s) and cleat cross-section (m).
    arrival_s : float
        Time the contact point reaches the cleat, s.
    t0_s, duration_s : float
        The run covers [t0_s, t0_s + duration_s], s.
    max_step_s : float
        Largest communication step, s; the step used is the cleat's duration
        divided by an integer (see :func:`identification.model.scheme.cleat_grid`).
    start_values : dict, optional
        FMU parameters to override (e.g. ``{"stiffness": 5e5}``).
    step_s : float, optional
        Use exactly this step (the cleat's duration must be a multiple of it).
    cleat_profile : CleatProfile, optional
        The cleat's cross-section when not rectangular (a recording's ``cleat_profile``): the road
        under a tire without a built-in cleat.

    Returns
    -------
    CosimResult
        The trajectory (:class:`identification.model.scheme.Trajectory`), the FMU's
        parameters and the wall time of the stepping loop.
    """
    _check_run(max_step_s, duration_s, speed_m_s)
    cleat_time = cleat_width_m / speed_m_s
    vertices = () if cleat_profile is None or cleat_profile.is_rectangular or step_s else \
        [x / cleat_width_m for x in cleat_profile.vertices()]
    start, h, n = cleat_grid(t0_s=t0_s, duration_s=duration_s, arrival_s=arrival_s, cleat_time_s=cleat_time,
                             max_step_s=step_s or max_step_s, vertex_fractions=vertices)
    with TireFmu(fmu_path, start_values=start_values) as tire:
        tire.initialize(start)
        tire.switch_on_test_cleat(start, height_m=cleat_height_m, width_m=cleat_width_m, profile=cleat_profile)
        params = tire.parameters()
        inputs = tire.inputs(n, start, h, arrival_s=arrival_s, speed_m_s=speed_m_s, cleat_height_m=cleat_height_m,
                             cleat_width_m=cleat_width_m, profile=cleat_profile)
        offset = (0.0, 0.0)
        if params.get("lug_amplitude", 0.0):
            offset = lug_steady_state(masses_kg=[mass_kg], stiffness_n_m=[params["stiffness"]],
                                      damping_n_s_m=[params["damping"]], lug_amplitude_m=[params["lug_amplitude"]],
                                      lug_pitch_m=[params["lug_pitch"]], lug_phase_rad=[params["lug_phase"]],
                                      speed_m_s=speed_m_s, arrival_s=[arrival_s - params.get("cleat_x", 0.0)
                                                                       / speed_m_s], t0_s=start)[0]
        wall = time.perf_counter()
        body = corner_body(tire.force_fn(), mass_kg=mass_kg, inputs=inputs, unloaded_radius_m=params["unloaded_radius"],
                           stiffness_guess_n_m=params["stiffness"], initial_offset=offset)
        traj = step_body_fmus([tire], inputs=grid_inputs([inputs], start, h, n), start_s=start, step_s=h, **body)
        wall = time.perf_counter() - wall
    if not np.all(np.isfinite(traj.force_n)):
        raise InputError(fmu_path, "the co-simulation diverged (non-finite tire force)")
    return CosimResult(traj, params, wall)


def run_half_tractor_fmus(fmu_paths, *, loads_n, wheelbase_m: float, dynamic_index: float, speed_m_s: float,
                          cleat_height_m: float, cleat_width_m: float, arrival_s: float, t0_s: float,
                          duration_s: float, max_step_s: float, start_values=(None, None), cleat_profile=None):
    """Two tire FMU instances (front, rear) under the half-tractor, over the cleat.

    The rear tire reaches the cleat wheelbase / speed after the front one; a
    `cleat_profile` as in :func:`run_quarter_tractor`.
    Returns a :class:`CosimResult` whose trajectory has the front tire first.
    """
    _check_run(max_step_s, duration_s, speed_m_s)
    cleat_time = cleat_width_m / speed_m_s
    delay = wheelbase_m / speed_m_s
    start, h, n = cleat_grid(t0_s=t0_s, duration_s=duration_s, arrival_s=arrival_s, cleat_time_s=cleat_time,
                             max_step_s=max_step_s, other_axle_delay_s=delay)
    with TireFmu(fmu_paths[0], start_values=start_values[0], instance_name="front") as front, \
            TireFmu(fmu_paths[1], start_values=start_values[1], instance_name="rear") as rear:
        tires = (front, rear)
        for t in tires:
            t.initialize(start)
            t.switch_on_test_cleat(start, height_m=cleat_height_m, width_m=cleat_width_m, profile=cleat_profile)
        params = [t.parameters() for t in tires]
        inputs = [t.inputs(n, start, h, arrival_s=arrival_s + lag, speed_m_s=speed_m_s,
                           cleat_height_m=cleat_height_m, cleat_width_m=cleat_width_m, profile=cleat_profile)
                  for t, lag in zip(tires, (0.0, delay))]

        offset = ((0.0, 0.0), (0.0, 0.0))
        if params[0].get("lug_amplitude", 0.0) or params[1].get("lug_amplitude", 0.0):
            offset = lug_steady_state(
                masses_kg=None, stiffness_n_m=[p["stiffness"] for p in params],
                damping_n_s_m=[p["damping"] for p in params],
                lug_amplitude_m=[p.get("lug_amplitude", 0.0) for p in params],
                lug_pitch_m=[p.get("lug_pitch", 1.0) for p in params],
                lug_phase_rad=[p.get("lug_phase", 0.0) for p in params], speed_m_s=speed_m_s,
                arrival_s=[arrival_s + lag - p.get("cleat_x", 0.0) / speed_m_s for p, lag in zip(params, (0.0, delay))],
                t0_s=start, wheelbase_m=wheelbase_m, dynamic_index=dynamic_index, loads_n=loads_n)
        wall = time.perf_counter()
        body = half_tractor_body([t.force_fn() for t in tires], loads_n=loads_n, wheelbase_m=wheelbase_m,
                                 dynamic_index=dynamic_index, inputs=inputs,
                                 unloaded_radii_m=[p["unloaded_radius"] for p in params],
                                 stiffness_guesses_n_m=[p["stiffness"] for p in params], initial_offset=offset)
        traj = step_body_fmus(list(tires), inputs=grid_inputs(inputs, start, h, n), start_s=start, step_s=h, **body)
        wall = time.perf_counter() - wall
    if not np.all(np.isfinite(traj.force_n)):
        raise InputError(fmu_paths[0], "the co-simulation diverged (non-finite tire force)")
    return CosimResult(traj, params[0], wall, rear_parameters=params[1])


@dataclass(frozen=True, eq=False)
class CosimResult:
    """A co-simulation run: trajectory, FMU parameters (front first) and loop wall time, s."""

    trajectory: Trajectory
    parameters: dict
    wall_s: float
    rear_parameters: dict | None = None

    # conveniences for the corner (first tire)
    @property
    def time_s(self):
        return self.trajectory.time_s

    @property
    def step_s(self):
        return self.trajectory.step_s

    @property
    def hub_accel_m_s2(self):
        return self.trajectory.hub_accel_m_s2[0]

    @property
    def hub_z_m(self):
        return self.trajectory.hub_z_m[0]

    @property
    def hub_vz_m_s(self):
        return self.trajectory.hub_vz_m_s[0]

    @property
    def force_n(self):
        return self.trajectory.force_n[0]

    @property
    def static_hub_z_m(self):
        return float(self.trajectory.static_hub_z_m[0])

    def mean_acceleration(self, time_s, interval_s: float, tire: int = 0):
        """Mean hub acceleration over each sample interval, m/s² (see :class:`Trajectory`)."""
        return self.trajectory.mean_acceleration(tire, time_s, interval_s)
