"""The one-pass ASCII reader reads every number as Python's float() does (both correctly
rounded), bit for bit: plain decimals (its own fast route), exponents, long mantissas,
subnormals, signed zeros; and files cut into many parallel chunks."""

from __future__ import annotations

import struct

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import gagekit

TRICKY = [
    "0", "-0", "+0", "-0.0", "0.1", "0.30000000000000004", "123.4567", "-0.0123", "5.", ".5", "-.5", "+.5",
    "1e-320", "4.9406564584124654e-324", "2.2250738585072011e-308", "2.2250738585072014e-308",
    "1.7976931348623157e308", "9007199254740993", "9007199254740993.0", "999999999999999", "9999999999999999",
    "0.000000000000001", "123456789.012345", "1234567890123456789012345678901234567890",
    "0.1000000000000000055511151231257827021181583404541015625", "1E+05", "7e22", "7e23", "00012.500",
]


def bits(a) -> list:
    return [struct.pack("<d", v) for v in np.asarray(a, dtype=np.float64).ravel()]


def test_tricky_numbers_equal_python_float(tmp_path):
    rows = [TRICKY[i:i + 3] for i in range(0, len(TRICKY) - 2)]
    p = tmp_path / "t.xyz"
    p.write_text("\n".join(" ".join(r) for r in rows) + "\n")
    got = gagekit.read_points(p)
    assert bits(got) == bits([[float(t) for t in r] for r in rows])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e300, 1e300), st.integers(0, 17),
                          st.sampled_from(["repr", "fixed", "exp"])), min_size=3, max_size=300),
       st.sampled_from([" ", ",", "\t", ";", ", "]))
def test_random_numbers_equal_python_float(tmp_path_factory, cells, sep):
    n = len(cells) // 3 * 3
    toks = []
    for v, d, how in cells[:n]:
        toks.append(repr(v) if how == "repr" else f"{v:.{d}f}" if how == "fixed" and abs(v) < 1e30 else f"{v:.{d}e}")
    text = "\n".join(sep.join(toks[i:i + 3]) for i in range(0, n, 3)) + "\n"
    p = tmp_path_factory.mktemp("a") / "r.csv"
    p.write_text(text)
    assert bits(gagekit.read_points(p)) == bits([float(t) for t in toks])


def test_many_chunks_with_comments_and_blank_lines(tmp_path):
    """A file large enough for several parallel chunks, with skipped lines between them:
    the points come back in order and complete."""
    rng = np.random.default_rng(1)
    pts = rng.uniform(-500, 500, (400_000, 3)).round(5)
    lines = [f"{x!r} {y!r} {z!r}" for x, y, z in pts.tolist()]
    for k in range(0, len(lines), 997):
        lines[k] = lines[k] + "\n\n# comment"
    p = tmp_path / "big.xyz"
    p.write_text("x y z\n" + "\n".join(lines) + "\n")
    assert np.array_equal(gagekit.read_points(p), pts)
