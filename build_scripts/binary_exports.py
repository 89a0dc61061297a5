"""Exported symbol names of shared libraries for other platforms: PE (Windows DLL) and Mach-O (macOS dylib).

Enough of each format to list what a host can look up with ``GetProcAddress``
or ``dlsym``: the PE export directory's name table, and the external defined
symbols of a 64-bit Mach-O symbol table (without the leading underscore).
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

__all__ = ["pe_exports", "pe_sections", "pe_offset", "macho_exports", "exported_names", "fmi_function_names"]


def pe_offset(sections, rva: int) -> int:
    """File offset of a relative virtual address, given :func:`pe_sections`."""
    for va, size, raw in sections:
        if va <= rva < va + size:
            return raw + rva - va
    raise ValueError(f"RVA {rva:#x} is in no section")


def pe_sections(data: bytes) -> list[tuple[int, int, int]]:
    """``[(virtual address, size, file offset)]`` of the sections of a PE image."""
    pe = struct.unpack_from("<I", data, 0x3C)[0]
    n_sections, opt_size = struct.unpack_from("<H", data, pe + 6)[0], struct.unpack_from("<H", data, pe + 20)[0]
    sections = []
    for i in range(n_sections):
        s = pe + 24 + opt_size + 40 * i
        vsize, va, raw_size, raw = struct.unpack_from("<IIII", data, s + 8)
        sections.append((va, max(vsize, raw_size), raw))
    return sections


def pe_exports(data: bytes) -> set[str]:
    """Names in the export directory of a PE image (DLL).

    Raises
    ------
    ValueError
        If `data` is not a PE image with an export directory.
    """
    if data[:2] != b"MZ":
        raise ValueError("not a PE image (no MZ header)")
    pe = struct.unpack_from("<I", data, 0x3C)[0]
    if data[pe:pe + 4] != b"PE\0\0":
        raise ValueError("not a PE image (no PE signature)")
    opt = pe + 24
    magic = struct.unpack_from("<H", data, opt)[0]
    directories = opt + {0x10B: 96, 0x20B: 112}[magic]
    export_rva, export_size = struct.unpack_from("<II", data, directories)
    if export_size == 0:
        raise ValueError("the PE image has no export directory")
    sections = pe_sections(data)
    d = pe_offset(sections, export_rva)
    n_names, names_rva = struct.unpack_from("<I", data, d + 24)[0], struct.unpack_from("<I", data, d + 32)[0]
    names = set()
    table = pe_offset(sections, names_rva)
    for i in range(n_names):
        at = pe_offset(sections, struct.unpack_from("<I", data, table + 4 * i)[0])
        names.add(data[at:data.index(b"\0", at)].decode("ascii"))
    return names


def macho_exports(data: bytes) -> set[str]:
    """External defined symbols of a 64-bit little-endian Mach-O image, without the leading underscore.

    Raises
    ------
    ValueError
        If `data` is not such an image or has no symbol table.
    """
    if struct.unpack_from("<I", data, 0)[0] != 0xFEEDFACF:
        raise ValueError("not a 64-bit little-endian Mach-O image")
    ncmds = struct.unpack_from("<I", data, 16)[0]
    at = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, at)
        if cmd == 0x2:  # LC_SYMTAB
            symoff, nsyms, stroff, _strsize = struct.unpack_from("<IIII", data, at + 8)
            names = set()
            for i in range(nsyms):
                strx, n_type = struct.unpack_from("<IB", data, symoff + 16 * i)
                if n_type & 0x01 and not n_type & 0x10 and (n_type & 0x0E) == 0x0E:  # N_EXT, not N_PEXT, N_SECT
                    name = data[stroff + strx:data.index(b"\0", stroff + strx)].decode("ascii")
                    names.add(name[1:] if name.startswith("_") else name)
            return names
        at += size
    raise ValueError("the Mach-O image has no symbol table")


def exported_names(path_or_bytes) -> set[str]:
    """Exported names of a DLL or dylib (format from its magic number)."""
    data = path_or_bytes if isinstance(path_or_bytes, bytes) else Path(path_or_bytes).read_bytes()
    return pe_exports(data) if data[:2] == b"MZ" else macho_exports(data)


def fmi_function_names(header: str) -> set[str]:
    """Every function an FMI header (e.g. fmpy's ``fmi2Functions.h``) declares for export."""
    return set(re.findall(r"FMI\d_Export\s+\w+TYPE\s+(\w+)\s*;", header))
