"""Cross-compilation of the native (C) tire FMUs with zig, cached per platform and law version.

The C sources live in ``fmu_src/native``: the tire law (``cleatfmu_law.c``),
the tractor body (``cleatfmu_body.c``), the road profile (``cleatfmu_road.c``), the tire map (``cleatfmu_map.c``),
the model (``cleatfmu_model.c``), the resource reader (``cleatfmu_resources.c``)
the instance (``cleatfmu_instance.c``) and the FMI layers
(``fmi2_functions.c``, ``fmi3_functions.c``), one ``config.h`` per kind
(``fmu_src/native/<kind>/config.h``); the FMI headers are the ones fmpy ships
(``fmpy/c-code``).  :func:`compile_binary` builds one shared library with
``python -m ziglang cc -target ...`` and keeps it in the cache
(:func:`cache_dir`) under the SHA-256 of the sources, the target and the
flags, so an export after the first one compiles nothing.  The binaries are
reproducible: the same sources give the same bytes (no time stamp in a PE
image, no build path in a Mach-O install name).
"""

from __future__ import annotations

import hashlib
import os
import re
import struct
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from importlib import resources
from pathlib import Path

from .kinds import FmuKind
from identification._compile import cache_root
from identification._files import temp_prefix

__all__ = ["PLATFORMS", "FMI_VERSIONS", "cache_dir", "source_files", "law_version", "compile_binary",
           "compile_binaries", "config_problems"]

#: FMI version -> {platform folder in binaries/: (zig target, file extension)}.  The macOS targets name their
#: oldest release (the cross-compiler's default is its newest SDK's, 15.0, which older Macs refuse to load):
#: 10.13 for Intel, 11.0 (the first) for Apple silicon; Linux binaries link against glibc 2.17.
PLATFORMS = {
    2: {"linux64": ("x86_64-linux-gnu.2.17", ".so"),
        "win64": ("x86_64-windows-gnu", ".dll"),
        "darwin64": ("x86_64-macos.10.13", ".dylib")},
    3: {"x86_64-linux": ("x86_64-linux-gnu.2.17", ".so"),
        "aarch64-linux": ("aarch64-linux-gnu.2.17", ".so"),
        "x86_64-windows": ("x86_64-windows-gnu", ".dll"),
        "x86_64-darwin": ("x86_64-macos.10.13", ".dylib"),
        "aarch64-darwin": ("aarch64-macos.11.0", ".dylib")},
}
FMI_VERSIONS = tuple(PLATFORMS)

_COMMON = ("cleatfmu_names.h", "cleatfmu_law.h", "cleatfmu_law.c", "cleatfmu_body.h", "cleatfmu_body.c", "cleatfmu_road.h",
           "cleatfmu_road.c", "cleatfmu_map.h", "cleatfmu_map.c", "cleatfmu_model.h", "cleatfmu_model.c", "cleatfmu_resources.h",
           "cleatfmu_resources.c", "cleatfmu_instance.h", "cleatfmu_instance.c")
_FMI_LAYER = {2: ("fmi2_functions.c",), 3: ("fmi3_functions.c", "fmi3_unsupported.c")}
_FMI_HEADERS = {2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
                3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}
_FLAGS = ("-shared", "-std=c99", "-O2", "-g0", "-fvisibility=hidden", "-ffp-contract=off", "-fno-fast-math")
#: Version of the compile-and-link recipe beyond the flags (install name, PE post-processing); part of the cache key.
_RECIPE = "2"
def cache_dir() -> Path:
    """Folder of the compiled binaries: $CLEATFMU_CACHE_DIR, else $XDG_CACHE_HOME/cleatfmu, else ~/.cache/cleatfmu
    (:func:`identification._compile.cache_root`)."""
    return cache_root()


def _fmpy_headers() -> Path:
    """fmpy's folder of FMI headers, located without importing fmpy (and numpy with it)."""
    from importlib.util import find_spec

    spec = find_spec("fmpy")
    if spec is None or spec.origin is None:
        raise ValueError("the native backend needs fmpy's FMI headers (pip install fmpy)")
    return Path(spec.origin).parent / "c-code"


def source_files(kind: FmuKind, fmi_version: int) -> dict[str, bytes]:
    """``{file name: bytes}`` of every source needed to compile `kind` for `fmi_version` (the FMU's sources/)."""
    native = resources.files("fmu_src").joinpath("native")
    files = {name: native.joinpath(name).read_bytes() for name in (*_COMMON, *_FMI_LAYER[fmi_version])}
    files["config.h"] = native.joinpath(kind.name, "config.h").read_bytes()
    headers = _fmpy_headers()
    files.update({name: (headers / name).read_bytes() for name in _FMI_HEADERS[fmi_version]})
    return dict(sorted(files.items()))


def c_sources(fmi_version: int) -> list[str]:
    """Names of the C files to compile (in the FMU's sources/)."""
    return [n for n in (*_COMMON, *_FMI_LAYER[fmi_version]) if n.endswith(".c")]


def config_problems(kind: FmuKind) -> list[str]:
    """Differences between the kind's variable table and its config.h (names, types, causalities, order)."""
    text = resources.files("fmu_src").joinpath("native", kind.name, "config.h").read_text(encoding="utf-8")
    rows = re.findall(r'\{"(\w+)", VT_(\w+), VC_(\w+), RULE_\w+, "([^"]*)"\}', text)
    want = [(v.name, v.type.upper(), v.causality.upper(), v.unit) for v in kind.variables]
    got = [(n, t, c, u) for n, t, c, u in rows]
    problems = [] if got == want else [f"fmu_src/native/{kind.name}/config.h: variable table {got} differs from "
                                       f"VARIABLES {want}"]
    m = re.search(r"#define N_VARIABLES (\d+)", text)
    if not m or int(m.group(1)) != len(kind.variables):
        problems.append(f"fmu_src/native/{kind.name}/config.h: N_VARIABLES is not {len(kind.variables)}")
    m = re.search(r"#define MODEL_IDENTIFIER (\w+)", text)
    if not m or m.group(1) != kind.model_identifier:
        problems.append(f"fmu_src/native/{kind.name}/config.h: MODEL_IDENTIFIER is not {kind.model_identifier}")
    return problems


def law_version(kind: FmuKind, fmi_version: int) -> str:
    """SHA-256 (hex) of the sources of `kind` for `fmi_version`: changes whenever the C code does."""
    h = hashlib.sha256()
    for name, data in source_files(kind, fmi_version).items():
        h.update(name.encode() + b"\0" + hashlib.sha256(data).digest())
    return h.hexdigest()


def _zig_version() -> str:
    from importlib import metadata

    try:
        return metadata.version("ziglang")
    except metadata.PackageNotFoundError:
        raise ValueError("the native backend needs the ziglang package (pip install ziglang)") from None


def _pe_without_time_stamps(data: bytes) -> bytes:
    """A PE image with its COFF, export-directory and debug-directory time stamps and PDB signature zeroed.

    lld writes the link time and a random PDB signature there, so two
    compilations of the same sources would differ; the loader uses neither.
    """
    from .binary_exports import pe_sections, pe_offset

    out = bytearray(data)
    pe = struct.unpack_from("<I", out, 0x3C)[0]
    struct.pack_into("<I", out, pe + 8, 0)
    opt = pe + 24
    directories = opt + {0x10B: 96, 0x20B: 112}[struct.unpack_from("<H", out, opt)[0]]
    sections = pe_sections(bytes(out))
    export_rva, export_size = struct.unpack_from("<II", out, directories)
    if export_size:
        struct.pack_into("<I", out, pe_offset(sections, export_rva) + 4, 0)
    debug_rva, debug_size = struct.unpack_from("<II", out, directories + 6 * 8)
    if debug_size:
        at = pe_offset(sections, debug_rva)
        for i in range(debug_size // 28):
            entry = at + 28 * i
            struct.pack_into("<I", out, entry + 4, 0)
            kind, size = struct.unpack_from("<II", out, entry + 12)
            raw = struct.unpack_from("<I", out, entry + 24)[0]  # PointerToRawData
            if kind == 2 and size >= 20 and out[raw:raw + 4] == b"RSDS":  # CodeView: a random PDB signature
                out[raw + 4:raw + 20] = bytes(16)
    return bytes(out)


def compile_binary(kind: FmuKind, fmi_version: int, platform: str) -> bytes:
    """The shared library of `kind` for one platform, from the cache or compiled with zig (then cached).

    Raises
    ------
    ValueError
        Unknown platform, a config.h that does not match the kind, or a failing compilation.
    """
    if platform not in PLATFORMS.get(fmi_version, {}):
        raise ValueError(f"FMI {fmi_version}: unknown platform {platform!r} "
                         f"(known: {', '.join(PLATFORMS.get(fmi_version, {}))})")
    problems = config_problems(kind)
    if problems:
        raise ValueError(problems[0])
    target, ext = PLATFORMS[fmi_version][platform]
    key = hashlib.sha256(f"{law_version(kind, fmi_version)} {target} {' '.join(_FLAGS)} zig {_zig_version()} "
                         f"recipe {_RECIPE}".encode()).hexdigest()[:32]
    cached = cache_dir() / "native" / key / f"{kind.model_identifier}{ext}"
    if cached.is_file():
        return cached.read_bytes()
    with tempfile.TemporaryDirectory(prefix=temp_prefix("cc")) as tmp:
        src = Path(tmp, "src")
        src.mkdir()
        for name, data in source_files(kind, fmi_version).items():
            (src / name).write_bytes(data)
        out = Path(tmp, "out")
        out.mkdir()
        lib = out / f"{kind.model_identifier}{ext}"
        command = [sys.executable, "-m", "ziglang", "cc", "-target", target, *_FLAGS, "-I", ".", "-o", str(lib),
                   *c_sources(fmi_version)]
        if "linux" in target:
            command.append("-lm")
        if "macos" in target:  # else the install name is the absolute path of the temporary output
            command.append(f"-Wl,-install_name,@rpath/{lib.name}")
        done = subprocess.run(command, cwd=src, capture_output=True, text=True)
        if done.returncode != 0 or not lib.is_file():
            raise ValueError(f"compiling {kind.name} for {platform} ({target}) failed: {done.stderr.strip()[-2000:]}")
        data = lib.read_bytes()
        if ext == ".dll":
            data = _pe_without_time_stamps(data)
    cached.parent.mkdir(parents=True, exist_ok=True)
    fd, part = tempfile.mkstemp(prefix=".part", dir=cached.parent)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.replace(part, cached)
    return data


def compile_binaries(kind: FmuKind, fmi_version: int, platforms) -> dict[str, bytes]:
    """``{platform: shared library bytes}``, compiled in parallel where not cached."""
    platforms = list(platforms)
    with ThreadPoolExecutor(max_workers=max(1, len(platforms))) as pool:
        libs = list(pool.map(lambda p: compile_binary(kind, fmi_version, p), platforms))
    return dict(zip(platforms, libs))
