"""Identified tire parameters -> point-contact tire FMU (the API of ``cleatfmu export``).

``--backend native`` (the command's default) builds the C implementation
(binaries for Linux, Windows and macOS, no Python needed in the importer);
``--backend pythonfmu`` the Python slave.  :func:`export_fmu` defaults to
``"pythonfmu"`` for its library callers.

``cleatfmu export PARAMS.json --tire FL -o FL.fmu`` reads the output of
``cleatfmu identify --json`` and builds (with :func:`build_scripts.build_fmu`)
an FMI 2.0 co-simulation FMU of the point-contact tire whose tunable
parameters start at the identified values: ``stiffness`` = k (N/m),
``damping`` = c (N·s/m) and ``unloaded_radius`` = r0 (m).

The unloaded radius is not identified by the cleat test; unless given with
``--unloaded-radius-m`` it is :data:`DEFAULT_UNLOADED_RADIUS_M`, an assumption
(a typical tractor tire).  It only shifts the hub height at which the tire
touches the road (the hub input starts at r0: zero deflection on a road at
0 m); k and c do not depend on it.

The FMU records where its values come from: its model description names the
recording, speed, tire and corner mass, and the start-value file in its
resources holds the complete ``identify`` entry of the tire.
"""

from __future__ import annotations

import math
from pathlib import Path, PureWindowsPath

from .._files import OutputFolders, check_folder, make_folders
from .._inputs import read_json_file
from ..errors import InputError
from ..recording.plausibility import check_value
from ..model.tire_law import value_problem

__all__ = ["DEFAULT_UNLOADED_RADIUS_M", "FMU_KIND", "read_identified", "export_fmu", "check_backend"]

#: Unloaded tire radius assumed when none is given, m.
DEFAULT_UNLOADED_RADIUS_M = 0.75
#: The FMU kind (folder of ``fmu_src``) that ``export`` builds.
FMU_KIND = "point_contact"

_NUMBERS = ("k", "c", "T", "delta", "zeta", "omega_n", "r2", "mass")
#: Standard gravity, m/s² (:data:`identification.recording.STANDARD_GRAVITY`, not imported from there: that
#: module loads numpy, which an export does not need).
_STANDARD_GRAVITY = 9.80665


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _finite_number(value) -> bool:
    """Whether `value` is a JSON number that is a finite float (an integer beyond 1e308 is not)."""
    if not _number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _show(value) -> str:
    """`value` for a message (an integer too large for a float by its number of digits)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e308:
        return f"an integer of {len(str(abs(value)))} digits"
    return repr(value)


#: What ``--accept-out-of-range`` says in the messages of values out of their plausible range.
_ACCEPT_HINT = "; a genuine value: export with --accept-out-of-range"


def read_identified(path, tire: str | None = None, *, accept_out_of_range: bool = False) -> tuple[dict, str, dict]:
    """Read and check a ``cleatfmu identify --json`` document.

    Parameters
    ----------
    path : path-like
        The PARAMS.json file.
    tire : str, optional
        Tire to export (any letter case: ``fl`` names FL); may be omitted when the file holds exactly one.
    accept_out_of_range : bool
        Accept k, c and the corner mass outside their plausible ranges
        (:data:`identification.recording.plausibility.RANGES`); they must still be finite, k > 0 and c >= 0.

    Returns
    -------
    doc : dict
        The whole document.
    tire : str
        The chosen tire, as the file spells it.
    entry : dict
        Its entry (k in N/m, c in N·s/m, ...).

    Raises
    ------
    InputError
        Unreadable or malformed file, missing tire, invalid k or c, or k, c or mass out of their
        plausible ranges (one line, naming the file).
    """
    path = Path(path)
    doc = read_json_file(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("tires"), dict) or not doc["tires"]:
        raise InputError(path, 'not the output of "cleatfmu identify --json" (no "tires" object)')
    tires = doc["tires"]
    if tire is None:
        if len(tires) != 1:
            raise InputError(path, f"holds tires {', '.join(tires)}; choose one with --tire")
        tire = next(iter(tires))
    if tire not in tires:  # a tire named in another letter case ("fl" for FL)
        tire = next((name for name in tires if name.upper() == str(tire).strip().upper()), tire)
    if tire not in tires:
        raise InputError(path, f"no tire {tire!r} (tires in the file: {', '.join(tires)})")
    entry = tires[tire]
    if not isinstance(entry, dict):
        raise InputError(path, f"tire {tire}: entry is not an object")
    for key in ("k", "c"):
        if key not in entry:
            raise InputError(path, f"tire {tire}: missing {key!r}")
    for key in _NUMBERS:
        if key in entry and not _finite_number(entry[key]):
            raise InputError(path, f"tire {tire}: {key} must be a finite number, got {_show(entry[key])}")
    for key in ("k_ci", "c_ci"):  # the 95 % intervals; an unbounded end is null
        ci = entry.get(key)
        if ci is not None and not (isinstance(ci, list) and len(ci) == 2
                                   and all(v is None or _finite_number(v) for v in ci)
                                   and (None in ci or ci[0] <= ci[1])):
            shown = "[" + ", ".join(map(_show, ci)) + "]" if isinstance(ci, list) else _show(ci)
            raise InputError(path, f"tire {tire}: {key} must be [low, high], got {shown}")
    for key, name, unit, strictly in (("k", "stiffness k", "N/m", True), ("c", "damping c", "N*s/m", False)):
        problem = value_problem(name, unit, entry[key], strictly_positive=strictly)
        if problem is not None:
            raise InputError(path, f"tire {tire}: {problem}")
    if not accept_out_of_range:
        for key, quantity, label in (("k", "stiffness_N_m", "stiffness k"), ("c", "damping_Ns_m", "damping c"),
                                     ("mass", "corner_mass_kg", "corner mass")):
            problem = check_value(quantity, entry.get(key), label=label, hint=_ACCEPT_HINT)
            if problem is not None:
                raise InputError(path, f"tire {tire}: {problem}")
    if "speed_kmh" in doc and not _finite_number(doc["speed_kmh"]):
        raise InputError(path, f"speed_kmh must be a finite number, got {_show(doc['speed_kmh'])}")
    return doc, tire, entry


def _method(entry: dict) -> str:
    """Identification method of an ``identify`` entry: the one it names (a report's recommended entry says
    ``"joint diagnosis"``), else the waveform fit, which carries confidence intervals, or the paper's."""
    if isinstance(entry.get("method"), str) and entry["method"].strip():
        return entry["method"].strip()
    return "waveform" if "k_ci" in entry else "paper"


def _recording_name(doc: dict) -> str | None:
    """The recording's file name (never the directory it was read from on the build machine)."""
    recording = doc.get("recording")
    return PureWindowsPath(str(recording)).name if recording else None


def _description(doc: dict, tire: str, starts: dict, entry: dict, radius_given: bool) -> str:
    """Model description: provenance, then every parameter as ``name = value unit (meaning)``.

    ``fmpy info`` prints the model description but lists only inputs and
    outputs, so the parameters are summarised here, with the units and
    descriptions of the FMU kind's variable table.  The provenance names the
    recording by its file name only, the identification method and the
    cleatfmu version.
    """
    from build_scripts import load_kind
    from build_scripts.build import project_version

    kind = load_kind(FMU_KIND)
    parts = [f"Point-contact tire {tire} (spring k parallel to damper c, SI units), identified by the cleat test"]
    if _recording_name(doc):
        parts.append(f" of recording '{_recording_name(doc)}'")
    if _number(doc.get("speed_kmh")):
        parts.append(f" at {doc['speed_kmh']:.4g} km/h")
    if _number(entry.get("mass")):
        parts.append(f" (corner mass {entry['mass']:.6g} kg)")
    rows = []
    for name in kind.names("parameter"):
        var = kind.variable(name)
        note = "" if name != "unloaded_radius" else ("; given" if radius_given else "; default assumption")
        rows.append(f"{name} = {starts[name]:.6g} {var.unit} ({var.description}{note})")
    parts.append(f" by the {_method(entry)} method, cleatfmu {project_version()}")
    return "".join(parts) + ". Parameters: " + "; ".join(rows) + "."


def export_fmu(params_path, output_path, *, tire: str | None = None, unloaded_radius_m: float | None = None,
               backend: str = "pythonfmu", fmi_version: int = 2, platforms=None,
               accept_out_of_range: bool = False) -> Path:
    """Build the point-contact tire FMU for one identified tire.

    Parameters
    ----------
    params_path : path-like
        Output of ``cleatfmu identify --json``.
    output_path : path-like
        The ``.fmu`` to write (atomically: nothing is left behind on failure); missing folders are
        created (and removed again if the build fails).
    tire : str, optional
        Tire to export (required when the file holds several).
    unloaded_radius_m : float, optional
        Unloaded radius r0, m (default :data:`DEFAULT_UNLOADED_RADIUS_M`, an assumption).
    backend : {"pythonfmu", "native"}
        FMU implementation (see :func:`build_scripts.build_fmu`); a native FMU's
        hub starts at the static equilibrium of the corner mass, when the
        entry has one.
    fmi_version : int
        FMI version (native backend: 2 or 3).
    platforms : list of str, optional
        Platforms of a native FMU (default: all).
    accept_out_of_range : bool
        Accept k, c, the corner mass and the unloaded radius outside their plausible ranges
        (:mod:`identification.recording.plausibility`).

    Returns
    -------
    Path
        `output_path`.

    Raises
    ------
    InputError
        For every problem with the inputs.
    """
    from build_scripts import build_fmu

    doc, tire, entry = read_identified(params_path, tire, accept_out_of_range=accept_out_of_range)
    radius_given = unloaded_radius_m is not None
    radius = float(unloaded_radius_m) if radius_given else DEFAULT_UNLOADED_RADIUS_M
    problem = value_problem("unloaded radius", "m", radius, strictly_positive=True)
    if problem is None and not accept_out_of_range:
        problem = check_value("unloaded_radius_m", radius, label="unloaded radius", hint=_ACCEPT_HINT)
    if problem is not None:
        raise InputError("--unloaded-radius-m", problem)
    output_path = Path(output_path)
    if output_path.suffix != ".fmu":
        raise InputError(output_path, "the output file name must end with .fmu")
    if output_path.is_dir():
        raise InputError(output_path, "is a directory")
    check_folder(output_path.parent)
    check_backend(backend, fmi_version, platforms)
    provenance = {"command": "cleatfmu export", "params_file": Path(params_path).name, "tire": tire,
                  "recording": _recording_name(doc), "method": _method(entry), "speed_kmh": doc.get("speed_kmh"),
                  "identified": entry,
                  "unloaded_radius_m": radius,
                  "unloaded_radius_source": "given" if radius_given else "default assumption"}
    starts = {"stiffness": entry["k"], "damping": entry["c"], "unloaded_radius": radius}
    description = _description(doc, tire, starts, entry, radius_given)
    if backend == "native" and _number(entry.get("mass")) and entry["mass"] > 0:
        starts["hub_z"] = radius - entry["mass"] * _STANDARD_GRAVITY / entry["k"]  # static equilibrium, m
        if not math.isfinite(starts["hub_z"]):
            raise InputError(params_path, f"tire {tire}: the static deflection m g / k of mass {entry['mass']!r} kg "
                                          f"on stiffness {entry['k']!r} N/m is not a finite number")
    try:
        with OutputFolders():  # a folder created for the FMU goes again if the build fails
            make_folders(output_path.parent)
            return build_fmu(FMU_KIND, output_path, start_values=starts, provenance=provenance,
                             description=description, backend=backend, fmi_version=fmi_version,
                             platforms=platforms)
    except OSError as exc:
        raise InputError(output_path, f"cannot write: {exc.strerror or exc}") from None


def check_backend(backend: str, fmi_version: int, platforms) -> None:
    from build_scripts.build import BACKENDS
    from build_scripts.native import PLATFORMS

    if backend not in BACKENDS:
        raise InputError("--backend", f"unknown backend {backend!r} (known: {', '.join(BACKENDS)})")
    if backend == "pythonfmu":
        if fmi_version != 2:
            raise InputError("--fmi-version", "the pythonfmu backend builds FMI 2.0 FMUs only")
        if platforms is not None:
            raise InputError("--platforms", "the pythonfmu backend builds for the platforms pythonfmu ships")
        return
    if fmi_version not in PLATFORMS:
        raise InputError("--fmi-version", f"FMI {fmi_version} is not supported "
                                          f"(supported: {', '.join(map(str, PLATFORMS))})")
    if platforms is not None:
        known = PLATFORMS[fmi_version]
        if not platforms:
            raise InputError("--platforms", "no platform given")
        for platform in platforms:
            if platform not in known:
                raise InputError("--platforms", f"unknown platform {platform!r} for FMI {fmi_version} "
                                                f"(known: {', '.join(known)})")
