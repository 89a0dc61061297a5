"""Build an FMU of one kind from ``fmu_src`` with given start values.

Steps: stage the slave script, the kind's modules (copied from this project
under names unique to the build, :func:`build_prefix`) and the start-value
file in a temporary folder;
let pythonfmu build the FMU there (its import side effects on ``sys.path`` and
``sys.modules`` are undone afterwards); complete the modelDescription.xml
(:mod:`build_scripts.model_description`) with a GUID derived from the content
instead of pythonfmu's time-based one, and without its time stamp; write the
FMU atomically and reproducibly (:mod:`build_scripts.reproducible`).

The native backend (:func:`_build_native`) compiles the C implementation of
``fmu_src/native`` (:mod:`build_scripts.native`) and packages it
(:mod:`build_scripts.native_fmu`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import struct
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from importlib import metadata
from pathlib import Path

from .kinds import FmuKind, load_kind, module_source
from .model_description import complete_model_description
from .reproducible import GUID_PLACEHOLDER, content_guid, zip_bytes
from identification._files import publish_path, temp_beside, temp_prefix, xml_text

__all__ = ["BACKENDS", "build_fmu", "build_prefix", "resolve_start_values", "project_version", "VERIFIED_PYTHONFMU"]

#: pythonfmu versions whose FMI wrapper the FMU-side workarounds
#: (``fmu_src/pythonfmu_wrapper.py``) were written and tested for.
VERIFIED_PYTHONFMU = ("0.7.0",)


def project_version() -> str:
    """Version of the installed cleatfmu distribution (``"unknown"`` if not installed)."""
    try:
        return metadata.version("cleatfmu")
    except metadata.PackageNotFoundError:
        return "unknown"


def resolve_start_values(kind: FmuKind, overrides: dict | None = None) -> dict[str, float | bool]:
    """Start value of every input and parameter: the kind's defaults, then `overrides`.

    A default given as a variable name copies that variable's (resolved) start.
    Real variables take finite numbers (returned as float), Boolean variables
    ``True`` or ``False``.

    Raises
    ------
    ValueError
        For an override that is not an input or parameter, or not a value of its type.
    """
    types = {v.name: v.type for v in kind.variables if v.causality in ("input", "parameter")}
    values = {v.name: v.start for v in kind.variables if v.name in types}
    for name, value in (overrides or {}).items():
        if name not in types:
            raise ValueError(f"{name!r} is not an input or parameter of FMU kind {kind.name} "
                             f"(settable: {', '.join(sorted(types))})")
        values[name] = _typed_start(name, types[name], value)
    for name, value in values.items():
        if isinstance(value, str):
            values[name] = values[value]
    return values


def _typed_start(name: str, typ: str, value):
    if typ == "Boolean":
        if not isinstance(value, bool):
            raise ValueError(f"start value of Boolean {name!r} must be True or False, got {value!r}")
        return value
    if isinstance(value, (bool, str)) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"start value of {name!r} must be a finite number, got {value!r}")
    return float(value)


@contextlib.contextmanager
def _undo_import_side_effects(module_names):
    """Restore sys.path and the kind's entries of sys.modules after pythonfmu's build."""
    saved_path = list(sys.path)
    saved_modules = {name: sys.modules.pop(name) for name in module_names if name in sys.modules}
    try:
        yield
    finally:
        sys.path[:] = saved_path
        for name in module_names:
            sys.modules.pop(name, None)
        sys.modules.update(saved_modules)


def _is_pythonfmu_module(name: str) -> bool:
    return name == "pythonfmu" or name.startswith("pythonfmu.")


@contextlib.contextmanager
def _installed_pythonfmu():
    """The installed pythonfmu package, even after a pythonfmu FMU was loaded in this process.

    A loaded pythonfmu FMU puts its resources folder on ``sys.path``, and that
    folder holds a copy of pythonfmu without its binaries: a later build would
    import that copy and write an FMU without ``binaries/``.  Inside this
    context ``import pythonfmu`` gives the installed package; afterwards the
    modules and ``sys.path`` are restored, so a loaded FMU keeps its copy.
    """
    try:
        root = Path(str(metadata.distribution("pythonfmu").locate_file("pythonfmu"))).resolve()
    except metadata.PackageNotFoundError:
        raise ValueError("the pythonfmu backend needs the pythonfmu package (pip install pythonfmu)") from None
    current = sys.modules.get("pythonfmu")
    if current is None or Path(current.__file__).resolve().parent == root:
        import pythonfmu

        if Path(pythonfmu.__file__).resolve().parent == root:
            yield pythonfmu
            return
    saved_path = list(sys.path)
    saved = {name: sys.modules.pop(name) for name in [n for n in sys.modules if _is_pythonfmu_module(n)]}
    sys.path.insert(0, str(root.parent))
    try:
        import pythonfmu

        yield pythonfmu
    finally:
        for name in [n for n in sys.modules if _is_pythonfmu_module(n)]:
            sys.modules.pop(name)
        sys.modules.update(saved)
        sys.path[:] = saved_path


def _run_pythonfmu(kind: FmuKind, stage: Path, out_dir: Path, starts: dict, provenance: dict | None) -> Path:
    with _installed_pythonfmu() as pythonfmu:
        raw = _run_installed_pythonfmu(pythonfmu, kind, stage, out_dir, starts, provenance)
    with zipfile.ZipFile(raw) as z:
        if not any(n.startswith("binaries/") and not n.endswith("/") for n in z.namelist()):
            raise ValueError(f"FMU kind {kind.name}: pythonfmu wrote an FMU without binaries")
    return raw


def build_prefix(kind: FmuKind, sources: dict[str, bytes]) -> str:
    """Module-name prefix of one pythonfmu build: ``cleatfmu_<kind>_b<10 hex digits of a content hash>``.

    pythonfmu FMUs whose modules share a name run the code of the one loaded
    first in a process; naming a build's modules after a hash of its sources
    and start values makes FMUs that differ load their own modules, and keeps
    the build reproducible.
    """
    h = hashlib.sha256()
    for name, data in sorted(sources.items()):
        h.update(name.encode() + b"\0" + hashlib.sha256(data).digest())
    return f"cleatfmu_{kind.name}_b{h.hexdigest()[:10]}"


def _run_installed_pythonfmu(pythonfmu, kind: FmuKind, stage: Path, out_dir: Path, starts: dict,
                             provenance: dict | None) -> Path:
    from pythonfmu.builder import FmuBuilder

    if pythonfmu.__version__ not in VERIFIED_PYTHONFMU:
        raise ValueError(f"pythonfmu {pythonfmu.__version__} is installed; the FMUs' workarounds for its FMI "
                         f"wrapper are verified for {', '.join(VERIFIED_PYTHONFMU)} only "
                         f"(see fmu_src/pythonfmu_wrapper.py)")

    own = {filename: kind.folder.joinpath(filename).read_bytes() for filename in (kind.script, *kind.files)}
    copied = {f"{name}.py": module_source(dotted) for name, dotted in sorted(kind.modules.items())}
    start_json = json.dumps({"start": starts, "provenance": provenance or {}}, indent=2, sort_keys=True).encode()
    base, prefix = f"cleatfmu_{kind.name}", build_prefix(kind, {**own, **copied, kind.start_file: start_json})

    def renamed(filename: str) -> str:
        return prefix + filename[len(base):] if filename.startswith(base) else filename

    pattern = re.compile(rb"\b" + re.escape(base.encode()))
    script = stage / renamed(kind.script)
    project_files = []
    for filename, data in own.items():
        path = stage / renamed(filename)
        path.write_bytes(pattern.sub(prefix.encode(), data))  # imports and file names of the kind's modules
        if filename != kind.script:
            project_files.append(path)
    for filename, data in copied.items():
        path = stage / renamed(filename)
        path.write_bytes(data)
        project_files.append(path)
    start_file = stage / renamed(kind.start_file)
    start_file.write_bytes(start_json)
    project_files.append(start_file)
    docs = None
    if kind.folder.joinpath("README.md").is_file():
        docs = stage / "documentation"
        docs.mkdir()
        (docs / "README.md").write_bytes(kind.folder.joinpath("README.md").read_bytes())
    with _undo_import_side_effects({renamed(f"{name}.py")[:-3] for name in kind.module_names()}):
        try:
            return Path(FmuBuilder.build_FMU(script, dest=out_dir, project_files=project_files,
                                             documentation_folder=docs))
        except (ValueError, TypeError) as exc:  # raised by the slave class on bad start values
            raise ValueError(f"FMU kind {kind.name}: {exc}") from None


#: Backends of :func:`build_fmu`.
BACKENDS = ("pythonfmu", "native")


def build_fmu(kind: str, dest, *, start_values: dict | None = None, provenance: dict | None = None,
              description: str | None = None, backend: str = "pythonfmu", fmi_version: int = 2,
              platforms=None, resources: dict | None = None) -> Path:
    """Build an FMU of `kind` whose inputs and parameters start at `start_values`.

    Parameters
    ----------
    kind : str
        Folder name in ``fmu_src`` (e.g. ``"point_contact"``).
    dest : path-like
        The ``.fmu`` file to write.  It is written atomically: a temporary file
        beside it, renamed at the end; nothing is left behind on failure.
    start_values : dict of str to float or bool, optional
        Start values of inputs/parameters in SI units, bool for Boolean
        parameters (others: the kind's defaults).
    provenance : dict, optional
        JSON-serialisable record of where the values come from, stored in the
        FMU's start-value file.
    description : str, optional
        Model description (default: the slave class's own).
    backend : {"pythonfmu", "native"}
        ``"pythonfmu"``: the Python slave of ``fmu_src/<kind>`` (needs Python
        on the importing machine); ``"native"``: the C implementation of
        ``fmu_src/native`` (no Python needed; its hub starts at the static
        equilibrium unless ``hub_z`` is given, see
        :func:`build_scripts.native_fmu.equilibrium_starts`).
    fmi_version : int
        FMI version of a native FMU (2).
    platforms : iterable of str, optional
        Platforms of a native FMU (default: all, see :data:`build_scripts.native.PLATFORMS`).
    resources : dict of str to bytes, optional
        Further files of a native FMU's resources folder: the ``road_profile`` kind's table
        (:data:`build_scripts.road_table.ROAD_FILE`; default :func:`build_scripts.road_table.default_road`),
        the ``map_tire`` kind's (:data:`build_scripts.map_table.MAP_FILE`; default
        :func:`build_scripts.map_table.default_map`; its hub starts at the static equilibrium under
        :data:`build_scripts.native_fmu.DEFAULT_STATIC_LOAD_N` with the map's k at the start speed unless
        ``hub_z`` is given).

    Returns
    -------
    Path
        `dest`.

    Raises
    ------
    ValueError
        Unknown kind, bad start values (also those the slave itself rejects), or
        a model description that does not match the kind's variable table.
    """
    dest = Path(dest)
    if dest.suffix != ".fmu":
        raise ValueError(f"{dest}: an FMU file name must end with .fmu")
    if not dest.parent.is_dir():
        raise ValueError(f"{dest.parent}: no such directory")
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r} (known: {', '.join(BACKENDS)})")
    k = load_kind(kind)
    if backend not in k.backends:
        raise ValueError(f"FMU kind {k.name} has no {backend} backend (it has: {', '.join(k.backends)})")
    starts = resolve_start_values(k, start_values)
    if description is not None:         # a recording's name or a tire key may hold what XML forbids
        description = xml_text(description)
    if backend == "native":
        return _build_native(k, dest, starts, start_values or {}, provenance, description, fmi_version, platforms,
                             resources)
    if resources:
        raise ValueError("resources are for native FMUs (the pythonfmu backend takes none)")
    fd, tmp_name = temp_beside(dest, ".part")
    tmp = Path(tmp_name)
    try:
        os.close(fd)
        with tempfile.TemporaryDirectory(prefix=temp_prefix("build")) as work:
            stage, out_dir = Path(work, "stage"), Path(work, "out")
            stage.mkdir()
            out_dir.mkdir()
            raw = _run_pythonfmu(k, stage, out_dir, starts, provenance)
            with zipfile.ZipFile(raw) as zin:
                files = {info.filename: zin.read(info) for info in zin.infolist() if not info.is_dir()}
            xml = files["modelDescription.xml"]
            guid = content_guid({**files, "modelDescription.xml": _finish_xml(xml, k, starts, description,
                                                                              GUID_PLACEHOLDER)})
            files["modelDescription.xml"] = _finish_xml(xml, k, starts, description, guid)
            tmp.write_bytes(zip_bytes(files))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        publish_path(tmp, dest)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return dest


def _build_native(k, dest: Path, starts, given, provenance, description, fmi_version, platforms,
                  resources=None) -> Path:
    from identification.model.tire_law import extended_parameter_problem, parameter_problem

    from .native_fmu import equilibrium_starts, native_fmu_bytes

    law = {n: starts[n] for n in k.names("parameter")}
    resources = dict(resources or {})
    if "ramp_length" in law:              # the road
        from .road_table import ROAD_FILE, default_road, road_table_bytes

        if set(resources) - {ROAD_FILE}:
            raise ValueError(f"FMU kind {k.name}: the only resource is {ROAD_FILE}")
        resources.setdefault(ROAD_FILE, road_table_bytes(*default_road()))
        problem = None
    elif "extrapolating" in k.names("output"):   # the tire map
        starts, problem, resources = _map_starts(k, starts, given, resources)
    elif resources:
        raise ValueError(f"FMU kind {k.name} takes no resources")
    elif "stiffness" not in law:          # the body
        problem = _body_problem(law)
    else:
        problem = (extended_parameter_problem(law) if "static_load" in law
                   else parameter_problem(law["stiffness"], law["damping"], law["unloaded_radius"]))
    if problem is not None:
        raise ValueError(f"FMU kind {k.name}: invalid start values: {problem}")
    if "stiffness" in law:
        starts = equilibrium_starts(k, starts, given)

    if description is None:
        description = k.native.get("description") or f"cleatfmu {k.name} tire (native C), SI units"
    data = native_fmu_bytes(k, starts, description=description, version=project_version(), fmi_version=fmi_version,
                            platforms=platforms, provenance=provenance, resources=resources)
    fd, tmp_name = temp_beside(dest, ".part")
    tmp = Path(tmp_name)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        publish_path(tmp, dest)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return dest


def _map_starts(k, starts: dict, given: dict, resources: dict) -> tuple:
    """The tire map's start values (hub at the static equilibrium at the start speed unless given), the
    problem of its table or None, and its resources (the default map when none is given)."""
    import numpy as np

    from identification.model.tire_law import value_problem

    from .map_table import MAP_FILE, default_map, map_table_bytes, map_table_problem, read_map_table
    from .native_fmu import DEFAULT_STATIC_LOAD_N

    if set(resources) - {MAP_FILE}:
        raise ValueError(f"FMU kind {k.name}: the only resource is {MAP_FILE}")
    resources = {MAP_FILE: resources.get(MAP_FILE) or map_table_bytes(*default_map())}
    try:
        table = read_map_table(resources[MAP_FILE])
    except (ValueError, IndexError, UnicodeDecodeError, struct.error):
        return starts, f"{MAP_FILE} is not a tire map table", resources
    problem = (map_table_problem(table["speed"], table["k"], table["c"], table["tested"])
               or value_problem("unloaded radius", "m", starts["unloaded_radius"], strictly_positive=True))
    if problem is not None:
        return starts, problem, resources
    out = dict(starts)
    if "hub_z" not in given:
        stiffness = float(np.interp(starts["speed"], table["speed"], table["k"]))
        out["hub_z"] = starts["road_z"] + starts["unloaded_radius"] - DEFAULT_STATIC_LOAD_N / stiffness
    return out, None, resources


def _body_problem(params: dict) -> str | None:
    """Why the body's parameters do not make a tractor (the model record's own check), or None."""
    from identification.model.tractor import Body
    from identification.recording import TIRES

    try:
        Body(tires=TIRES, loads_n=tuple(params[f"load_{t}"] for t in TIRES), wheelbase_m=params["wheelbase"],
             pitch=params["pitch_coupling"], roll=params["roll_coupling"], pivot=params["front_axle_pivot"],
             pitch_index=params["pitch_index"],
             roll_index=params["roll_index"], pivot_index=params["pivot_index"])
    except ValueError as exc:
        return str(exc)
    if not params["wheelbase"] > 0:
        return f"wheelbase must be > 0 m, got {params['wheelbase']!r}"
    return None


def _finish_xml(xml: bytes, kind: FmuKind, starts: dict, description: str | None, guid: str) -> bytes:
    """The completed model description with `guid` and without pythonfmu's time stamp (reproducible)."""
    written = ET.fromstring(xml)
    written.set("guid", guid)
    written.attrib.pop("generationDateAndTime", None)
    xml = ET.tostring(written, encoding="UTF-8", xml_declaration=True)
    version = project_version()
    return complete_model_description(
        xml, kind, start_values=starts,
        description=description if description is not None else written.get("description", ""),
        version=version,
        generation_tool=f"cleatfmu {version} build_scripts ({written.get('generationTool', 'pythonfmu')})")
