"""Resource locations of the native FMUs (RFC 3986 file URIs), through the C decoder itself."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from importlib import resources

import pytest

from build_scripts.native import _fmpy_headers


@pytest.fixture(scope="module")
def uri_to_path(tmp_path_factory):
    """``cleatfmu_uri_to_path`` of fmu_src/native/cleatfmu_resources.c, compiled with gcc."""
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed")
    native = resources.files("fmu_src").joinpath("native")
    lib = tmp_path_factory.mktemp("uri") / "uri.so"
    subprocess.run([gcc, "-std=c99", "-shared", "-fPIC", "-O1", "-I", str(native), "-I",
                    str(native.joinpath("point_contact")), "-I", str(_fmpy_headers()), "-o", str(lib),
                    str(native.joinpath("cleatfmu_resources.c")), str(native.joinpath("cleatfmu_model.c")),
                    str(native.joinpath("cleatfmu_law.c")), "-lm"], check=True)
    # the shared names carry the kind's model identifier (fmu_src/native/cleatfmu_names.h)
    f = getattr(ctypes.CDLL(str(lib)), "CleatfmuPointContact_cleatfmu_uri_to_path")
    f.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_size_t]

    def decode(uri: str):
        path, msg = ctypes.create_string_buffer(4096), ctypes.create_string_buffer(512)
        if f(uri.encode("utf-8"), path, 4096, msg, 512):
            return None, msg.value.decode("utf-8", "replace")
        return path.value.decode("utf-8"), ""
    return decode


@pytest.mark.parametrize("uri, path", [
    ("file:///tmp/a%20%C3%A4%23%25b/resources", "/tmp/a ä#%b/resources"),   # percent-encoded UTF-8
    ("file:///tmp/x/resources/", "/tmp/x/resources"),                         # trailing slash
    ("file:/tmp/x/resources", "/tmp/x/resources"),                            # no authority
    ("file://localhost/tmp/x/resources", "/tmp/x/resources"),                 # local host
    ("FILE://LOCALHOST/tmp/x", "/tmp/x"),                                     # scheme and host are case-insensitive
    ("file:///tmp/50%/r#1", "/tmp/50%/r#1"),                                  # unencoded '%' and '#' are kept
    ("/tmp/x/resources/", "/tmp/x/resources"),                                # a path (FMI 3.0 resourcePath)
])
def test_resource_locations_decode_to_the_local_path(uri_to_path, uri, path):
    assert uri_to_path(uri) == (path, "")


@pytest.mark.parametrize("uri, reason", [
    ("file://otherhost/share/x", "not this machine"),
    ("file:relative/x", "not an absolute file URI"),
    ("file:///tmp/a%00b", "%00"),
    ("", "no resource location"),
])
def test_bad_resource_locations_are_refused_with_a_reason(uri_to_path, uri, reason):
    path, msg = uri_to_path(uri)
    assert path is None and reason in msg
