"""Hypothesis drives the CLI with random bytes as point files (issue 12, item 9): whatever the
bytes and the extension, `cloud info`, `cloud hull` and `form fit` end in a finite result or
one clean error line, exit 2; never a traceback, a panic or a hang. The readers' own fixes
belong to their owner; this is the command-level contract."""

from __future__ import annotations

import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .conftest import check_outcome, gk_inproc

EXTS = [".xyz", ".csv", ".txt", ".pts", ".asc", ".ds", ".ply", ".npy", ".las", ".laz", ".e57", ".bin", ""]

HEADERS = [
    b"",
    b"x,y,z\n",
    b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
    b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (4, 3), }" + b" " * 48 + b"\n",
    b"LASF",
    b"ASTM-E57",
    b"5\n",
]

# printable numeric noise reaches deeper into the text parsers than uniform bytes
NUMERIC = st.text(alphabet="0123456789.,;eE+- \t\n#naifNAI", max_size=3000).map(str.encode)

BODY = st.one_of(st.binary(max_size=3000), NUMERIC)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(header=st.sampled_from(HEADERS), body=BODY, ext=st.sampled_from(EXTS),
       command=st.sampled_from([("cloud", "info"), ("cloud", "hull"), ("form", "fit", "plane")]))
def test_random_bytes_as_point_files(header, body, ext, command):
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / f"cloud{ext}"
        f.write_bytes(header + body)
        code, out, err = gk_inproc(*command, f, "--json")
        check_outcome(code, out, err, f"{' '.join(command)} {f.name} ({len(header + body)} bytes)")
