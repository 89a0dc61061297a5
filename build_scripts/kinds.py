"""FMU kinds: the folders of ``fmu_src`` and what the build needs to know about each.

A kind is a folder ``fmu_src/<kind>/`` with

* ``kind.json`` — the manifest: ``script`` (the pythonfmu slave script, the
  module named in the FMU's ``slavemodule.txt``), ``files`` (further modules
  of the kind's folder copied into the FMU), ``model_identifier`` (the slave
  class, defined in one of these files), ``modules`` (extra modules copied
  into the FMU: ``{name inside the FMU: "package.module" of this project}``),
  ``reference`` (``{"file": CSV, "rtol": ..., "atol": ..., "start_values":
  {...}}``, the regression result of the default experiment, run with the
  kind's default start values updated by the optional ``start_values``) and
  ``fmu_state`` (whether the kind supports getting, setting and serializing
  its state) and the optional ``backends`` (default both; a native-only kind,
  ``["native"]``, has no pythonfmu slave: its script holds only the variable
  table, and its model is the C code of ``fmu_src/native``);
* the slave script and files, one of which declares the variables in one
  literal table ``VARIABLES`` (read here with :mod:`ast`, without importing
  anything) and the name of the start-value file in ``START_FILE``.

``fmu_src`` is located as a package (``importlib.resources``), so kinds are
found the same way in a source checkout, an editable and a regular install.
"""

from __future__ import annotations

import ast
import json
import sys
from dataclasses import dataclass
from importlib import resources
from importlib.resources.abc import Traversable

__all__ = ["FmuKind", "Variable", "fmu_src_root", "kind_names", "load_kind", "module_name_conflicts"]

MANIFEST = "kind.json"
_VARIABLE_COLUMNS = ("name", "type", "causality", "variability", "unit", "start", "depends", "description")
_ALLOWED_THIRD_PARTY = {"pythonfmu"}


@dataclass(frozen=True)
class Variable:
    """One row of a slave script's ``VARIABLES`` table (value reference = row index)."""

    name: str
    type: str
    causality: str
    variability: str
    unit: str
    start: float | str | None
    depends: dict
    description: str
    value_reference: int


@dataclass(frozen=True)
class FmuKind:
    """Everything the build knows about one FMU kind."""

    name: str
    folder: Traversable
    script: str
    files: tuple
    model_identifier: str
    modules: dict
    reference_file: str
    reference_rtol: float
    reference_atol: float
    reference_start_values: dict
    fmu_state: bool
    start_file: str
    variables: tuple
    native: dict = None
    backends: tuple = ("pythonfmu", "native")

    @property
    def module_name(self) -> str:
        """Name of the slave module inside the FMU (the script's stem)."""
        return self.script[:-3]

    def module_names(self) -> set[str]:
        """Top-level module names this kind puts into an FMU (pythonfmu's own excepted)."""
        return {self.module_name, *(f[:-3] for f in self.files), *self.modules}

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(f"FMU kind {self.name!r} has no variable {name!r}")

    def names(self, *causalities: str) -> list[str]:
        """Names of the variables with any of the given causalities, in value-reference order."""
        return [v.name for v in self.variables if v.causality in causalities]


def fmu_src_root() -> Traversable:
    """The ``fmu_src`` folder (package data of the installed project)."""
    return resources.files("fmu_src")


def kind_names() -> list[str]:
    """Names of all FMU kinds in ``fmu_src``, sorted."""
    root = fmu_src_root()
    return sorted(p.name for p in root.iterdir() if p.is_dir() and p.joinpath(MANIFEST).is_file())


def _literal_assignments(source: str, filename: str) -> tuple[dict, list[str], list[str]]:
    """Top-level literal assignments, imported top-level module names and class names of a script."""
    tree = ast.parse(source, filename=filename)
    literals, imports, classes = {}, [], []
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            try:
                literals[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                pass
        elif isinstance(node, ast.Import):
            imports += [alias.name.split(".")[0] for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise ValueError(f"{filename}: relative imports are not allowed in an FMU script")
            imports.append(node.module.split(".")[0])
        elif isinstance(node, ast.ClassDef):
            classes.append(node.name)
    return literals, imports, classes


def _check_imports(imports, own_modules, filename):
    for name in imports:
        if name not in sys.stdlib_module_names and name not in _ALLOWED_THIRD_PARTY and name not in own_modules:
            raise ValueError(f"{filename}: imports {name!r}; an FMU script may import only the standard "
                             f"library, pythonfmu and the kind's own modules ({', '.join(sorted(own_modules))})")


def module_source(dotted: str) -> bytes:
    """Source bytes of a module of this project given as ``package.module``."""
    package, _, module = dotted.rpartition(".")
    if not package:
        raise ValueError(f"module {dotted!r} must be given as package.module")
    return resources.files(package).joinpath(f"{module}.py").read_bytes()


def load_kind(name: str) -> FmuKind:
    """Read and check the manifest and the variable table of FMU kind `name`.

    Raises
    ------
    ValueError
        If the kind does not exist or its files are inconsistent.
    """
    root = fmu_src_root()
    folder = root.joinpath(name)
    if not folder.joinpath(MANIFEST).is_file():
        raise ValueError(f"unknown FMU kind {name!r} (known: {', '.join(kind_names())})")
    where = f"fmu_src/{name}/{MANIFEST}"
    try:
        manifest = json.loads(folder.joinpath(MANIFEST).read_text(encoding="utf-8"))
        script, identifier = manifest["script"], manifest["model_identifier"]
        files = tuple(manifest.get("files", ()))
        modules, reference, fmu_state = dict(manifest["modules"]), manifest["reference"], bool(manifest["fmu_state"])
        ref_file, rtol, atol = reference["file"], float(reference["rtol"]), float(reference["atol"])
        ref_starts = dict(reference.get("start_values", {}))
        backends = tuple(manifest.get("backends", ("pythonfmu", "native")))
        if not backends or not set(backends) <= {"pythonfmu", "native"}:
            raise ValueError(f"backends must be a non-empty subset of pythonfmu, native, got {backends}")
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{where}: malformed manifest ({exc})") from None
    own = {filename[:-3] for filename in (script, *files)} | set(modules)
    literals, classes = {}, []
    for filename in (script, *files):
        if not filename.endswith(".py") or not folder.joinpath(filename).is_file():
            raise ValueError(f"{where}: {filename!r} is not a .py file of the kind's folder")
        found, imports, defined = _literal_assignments(folder.joinpath(filename).read_text(encoding="utf-8"),
                                                       f"fmu_src/{name}/{filename}")
        _check_imports(imports, own, f"fmu_src/{name}/{filename}")
        literals.update({key: value for key, value in found.items() if key in ("VARIABLES", "START_FILE")})
        classes += defined
    for dotted in modules.values():
        _, module_imports, _ = _literal_assignments(module_source(dotted).decode("utf-8"), dotted)
        _check_imports(module_imports, own, dotted)
    if identifier not in classes and "pythonfmu" in backends:
        raise ValueError(f"{where}: no file of the kind defines class {identifier!r}")
    for required in ("VARIABLES", "START_FILE"):
        if required not in literals:
            raise ValueError(f"fmu_src/{name}: no file declares a literal {required} at module level")
    rows = literals["VARIABLES"]
    variables = []
    for vr, row in enumerate(rows):
        if len(row) != len(_VARIABLE_COLUMNS):
            raise ValueError(f"fmu_src/{name}: VARIABLES row {vr} must have columns {_VARIABLE_COLUMNS}")
        variables.append(Variable(*row, value_reference=vr))
    return FmuKind(name=name, folder=folder, script=script, files=files, model_identifier=identifier, modules=modules,
                   reference_file=ref_file, reference_rtol=rtol, reference_atol=atol,
                   reference_start_values=ref_starts, fmu_state=fmu_state,
                   start_file=literals["START_FILE"], variables=tuple(variables),
                   native=dict(manifest.get("native", {})), backends=backends)


def module_name_conflicts(kinds) -> list[str]:
    """Problems with module names and model identifiers shared between kinds.

    Two pythonfmu FMUs whose modules share a name silently run the code of the
    one loaded first, so every module name and model identifier must be unique
    per kind, and every module name must start with ``cleatfmu_<kind>``.
    """
    problems, owner, identifiers = [], {}, {}
    for kind in kinds:
        prefix = f"cleatfmu_{kind.name}"
        for module in sorted(kind.module_names()):
            if module != prefix and not module.startswith(prefix + "_"):
                problems.append(f"kind {kind.name}: module {module!r} does not start with {prefix!r}")
            if module in owner:
                problems.append(f"module {module!r} is used by kinds {owner[module]} and {kind.name}")
            owner.setdefault(module, kind.name)
        if kind.model_identifier in identifiers:
            problems.append(f"model identifier {kind.model_identifier!r} is used by kinds "
                            f"{identifiers[kind.model_identifier]} and {kind.name}")
        identifiers.setdefault(kind.model_identifier, kind.name)
    return problems
