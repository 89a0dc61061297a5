"""Reproducible FMU archives: a GUID from the content, sorted zip entries with fixed dates and mode 0644."""

from __future__ import annotations

import hashlib
import io
import uuid
import zipfile

__all__ = ["GUID_PLACEHOLDER", "content_guid", "zip_bytes"]

#: Stands for the GUID while the content it is derived from is hashed.
GUID_PLACEHOLDER = "{00000000-0000-0000-0000-000000000000}"
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def content_guid(files: dict[str, bytes]) -> str:
    """A GUID ``{8-4-4-4-12}`` derived from the SHA-256 of the archive members (names and bytes)."""
    h = hashlib.sha256()
    for name, data in sorted(files.items()):
        h.update(name.encode() + b"\0" + hashlib.sha256(data).digest())
    return "{" + str(uuid.UUID(bytes=h.digest()[:16], version=5)) + "}"


def zip_bytes(files: dict[str, bytes]) -> bytes:
    """The zip archive of `files`: entries sorted by name, dated 1980-01-01 00:00, mode 0644, deflated."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3
            info.external_attr = 0o100644 << 16
            z.writestr(info, files[name], compresslevel=9)
    return buf.getvalue()
