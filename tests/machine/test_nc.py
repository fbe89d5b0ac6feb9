"""Corrected NC programs (issue 15 part 2): byte-for-byte copies, the inverse model's points,
subdivision that keeps the predicted path on the programmed line, clear errors."""

import dataclasses
import json
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import EXAMPLE_MACHINE
from gagekit.errors import ConfigError, FileFormatError, InvalidInputError
from gagekit.machine import Truth, compensate, identify, simulate
from gagekit.machine.export import calibration_parameters
from gagekit.machine.nc import compensate_nc, compensate_nc_text

PROGRAM = b"""%
O1000 (TEST PART)
N10 G21 G90 G17
N20 G0 B0 X-1000 Y400 Z1000 W-500 S1200 M3
N30 G1 X-900 F500 ; first cut
N40 Y450
N50 G91 X10 Z5
N60 G90 G1 X1000 (long move)
N70 M5
N80 M30
%
"""

WORD = re.compile(rb"([BXYZW])(-?[0-9.]+)")


@pytest.fixture(scope="module")
def cal(machine):
    truth = Truth.random(machine, seed=7)
    return identify(machine, simulate(machine, truth, machine.sample_commands(290, seed=7), seed=8))


def points(text: bytes, names, start=None):
    """Modal absolute positions after every moving line of a (G90) program."""
    pos = dict(start or {})
    out = []
    for line in text.split(b"\n"):
        body = re.sub(rb"\([^)]*\)", b"", line.split(b";")[0])
        words = WORD.findall(body)
        if words and re.search(rb"\bG0?[01]\b|^[^G]*$", body) and not body.startswith(b"("):
            for k, v in words:
                pos[k.decode()] = float(v)
            out.append([pos[n] for n in names])
    return np.array(out)


def actual(machine, cal, cmds):
    p = calibration_parameters(machine, cal)
    return machine.nominal(cmds) + machine.volumetric_error(cmds, p)


def test_copy_header_and_corrected_points(machine, cal):
    out, rep = compensate_nc_text(machine, cal, PROGRAM, decimals=9, stamp="2026-01-01")
    lines, src = out.split(b"\n"), PROGRAM.split(b"\n")
    assert lines[0] == b"%" and lines[1].startswith(b"(gagekit compensate-nc: machine dissertation-5axis-BXZYW, calibration 2026-01-01")
    kept = [l for l in lines[2:] if not l.startswith(b"G1 ")]
    # every line without a move is copied byte for byte; G91 is written G90
    for a, b in zip(kept, src[1:]):
        if not WORD.search(a):
            assert a == b
    assert b"N50 G90 X" in out and b"G91" not in out
    # F500 moves to the first inserted point of N30 (modal, not written twice)
    assert b"N30 G1 X" in out and out.count(b"F500") == 1 and b"; first cut" in out and b"(long move)" in out
    # the programmed end points, corrected as `compensate` corrects them
    names = machine.joint_names
    prog = np.array([[0, -1000, 1000, 400, -500], [0, -900, 1000, 400, -500], [0, -900, 1000, 450, -500],
                     [0, -890, 1005, 450, -500], [0, 1000, 1005, 450, -500]], dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want, _ = compensate(machine, cal, prog, axes=["X", "Z", "Y"])  # compensate-nc's default: W stays
    numbered = [l for l in lines if re.match(rb"N[2-6]0 ", l)]
    got = []
    for l in numbered:
        d = {k.decode(): float(v) for k, v in WORD.findall(l)}
        got.append([d.get(n, 0.0 if n == "B" else np.nan) for n in names])
    got = np.array(got)
    assert np.abs(got[:, 1:4] - want[:, 1:4]).max() < 2e-9  # X, Z, Y; W words are copied
    assert rep["moves"] == 5 and rep["max_remaining"] < 1e-9


def test_subdivision_keeps_the_predicted_path_on_the_line(machine, cal):
    text = b"G0 B0 X-890 Y450 Z1005 W-500\nN2 G1 X1000 F100\n"
    out, rep = compensate_nc_text(machine, cal, text, decimals=7)
    lines = out.decode().split("\n")
    ins = lines[2:-2]  # between the G0 line and N2: G1 and the feed on the first only
    assert rep["inserted"] == len(ins) > 10 and ins[0].startswith("G1 X") and ins[0].endswith(" F100")
    assert all(l.startswith("X") and "F" not in l for l in ins[1:])
    assert lines[-2].startswith("N2 G1 X") and "F100" not in lines[-2]
    names = machine.joint_names
    cmds, prev = [], {}
    for l in lines[1:-1]:
        prev = {**prev, **{k: float(v) for k, v in re.findall(r"([BXYZW])(-?[0-9.]+)", l)}}
        cmds.append([prev.get("B", 0.0)] + [prev[n] for n in names[1:]])
    cmds = np.array(cmds)
    a = actual(machine, cal, cmds)
    # every written point lands on the programmed line y = 450, z = 1005 - 500 - 450 - 312.035
    assert np.abs(a[:, 1] - a[0, 1]).max() < 1e-6 and np.abs(a[:, 2] - a[0, 2]).max() < 1e-6
    # the correction changes by at most max_step (plus rounding) between consecutive points
    corr = cmds[1:, 1:] - cmds[:-1, 1:]
    dx = np.diff(a[:, 0])
    assert np.all(dx > 0)
    c = cmds[:, 1:4] - np.column_stack([a[:, 0], np.full(len(a), 1005.0), np.full(len(a), 450.0)])
    assert np.abs(np.diff(c, axis=0)).max() < 0.001 + 1e-6
    # between written points (straight in joint space) the predicted path stays within max_step
    mid = 0.5 * (cmds[1:] + cmds[:-1])
    am = actual(machine, cal, mid)
    assert np.abs(am[:, 1:] - a[0, 1:]).max() < 0.001


@given(x0=st.floats(-1200, 1200), x1=st.floats(-1200, 1200), y0=st.floats(400, 2400), y1=st.floats(400, 2400),
       z=st.floats(950, 2100), b=st.floats(0, 90))
@settings(max_examples=25, deadline=None)
def test_any_g1_move_is_followed_within_max_step(machine, cal, x0, x1, y0, y1, z, b):
    x0, x1, y0, y1, z, b = (round(v, 3) for v in (x0, x1, y0, y1, z, b))
    b2 = round(b / 2, 3)
    text = f"G0 B{b:.3f} X{x0:.3f} Y{y0:.3f} Z{z:.3f} W-500\nG1 X{x1:.3f} Y{y1:.3f} B{b2:.3f} F100\n".encode()
    out, _ = compensate_nc_text(machine, cal, text, decimals=8)
    rows = []
    for l in out.decode().split("\n")[1:-1]:
        d = {k: float(v) for k, v in re.findall(r"([BXYZW])(-?[0-9.]+)", l)}
        rows.append(d)
    names = machine.joint_names
    cmds, prev = [], {"B": b}
    for d in rows:
        prev = {**prev, **d}
        cmds.append([prev[n] for n in names])
    cmds = np.array(cmds)
    a = actual(machine, cal, cmds)
    p0 = machine.nominal([[b, x0, z, y0, -500.0]])[0]
    p1 = machine.nominal([[b2, x1, z, y1, -500.0]])[0]
    # each written point's predicted position is the nominal position of its programmed point:
    # on the joint-space line between the two programmed points
    ts = np.linspace(0, 1, 2001)
    line = machine.nominal(np.column_stack([b + (b2 - b) * ts, x0 + (x1 - x0) * ts, np.full_like(ts, z), y0 + (y1 - y0) * ts, np.full_like(ts, -500.0)]))
    dist = np.array([np.linalg.norm(line - q, axis=1).min() for q in a])
    span = np.linalg.norm(p1 - p0) / 2000
    assert dist.max() < 1e-5 + span


def test_errors_name_the_line_and_write_nothing(machine, cal, tmp_path):
    cases = [
        (b"G0 B0 X1 Y400 Z1000 W-500\nG2 X2 Y401 I1 J0\n", "line 2: G2: arcs"),
        (b"G0 B0 X1 Y400 Z1000 W-500\nG81 X1 Y400 Z900 R1\n", "line 2: G81: canned"),
        (b"G0 B0 X1 Y400 Z1000 W-500\n#1=5\n", "line 2: macro"),
        (b"G0 B0 X1 Y400 Z1000 W-500 A30\n", "line 1: word 'A30'"),
        (b"G0 B0 X1 Y400 Z1000 W-500\nG65 P9000\n", "line 2: G65"),
        (b"G1 X1\n", "line 1: B has no position"),
    ]
    for text, want in cases:
        src = tmp_path / "p.nc"
        src.write_bytes(text)
        with pytest.raises(InvalidInputError, match=re.escape(want)):
            compensate_nc(machine, cal, src, tmp_path / "o.nc")
    assert not (tmp_path / "o.nc").exists()
    with pytest.raises(FileFormatError, match="not found"):
        compensate_nc(machine, cal, tmp_path / "missing.nc", tmp_path / "o.nc")
    other = dataclasses.replace(machine, name="other")
    with pytest.raises(ConfigError, match="not 'other'"):
        compensate_nc_text(other, cal, b"G0 X1\n")


def test_linearized_arc_stays_within_tolerance(machine, cal):
    text = b"G0 B0 X0 Y1000 Z1000 W-500\nN5 G3 X-100 Y1100 I-100 J0 F300\n"
    out, rep = compensate_nc_text(machine, cal, text, linearize_arcs=0.005, decimals=8)
    lines = out.decode().split("\n")
    assert lines[-2].startswith("N5 G1 X") and " I" not in lines[-2] and " J" not in lines[-2]
    cmds, d = [], {}
    for l in lines[1:-1]:
        d = {**d, **{k: float(v) for k, v in re.findall(r"([BXYZW])(-?[0-9.]+)", l)}}
        cmds.append([d.get("B", 0.0), d["X"], d["Z"], d["Y"], d["W"]])
    a = actual(machine, cal, np.array(cmds))
    r = np.hypot(a[:, 0] - (-100.0), a[:, 1] - 1000.0)
    assert np.abs(r - 100.0).max() < 1e-6 and len(cmds) > 20


def test_cli_compensate_nc(cal, tmp_path):
    calf = tmp_path / "cal.json"
    cal.save(calf)
    (tmp_path / "p.nc").write_bytes(PROGRAM)
    run = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    p = run("compensate-nc", EXAMPLE_MACHINE, calf, tmp_path / "p.nc", "--out", tmp_path / "o.nc", "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["moves"] == 5 and d["lines"] == 11 and d["inserted"] > 0
    assert (tmp_path / "o.nc").read_bytes().split(b"\n")[1].startswith(b"(gagekit compensate-nc")
    (tmp_path / "q.nc").write_bytes(b"G0 B0 X1 Y400 Z1000 W-500\nG3 X1 Y401 R5\n")
    p = run("compensate-nc", EXAMPLE_MACHINE, calf, tmp_path / "q.nc", "--out", tmp_path / "o2.nc")
    assert p.returncode == 2 and "line 2" in p.stderr and len(p.stderr.splitlines()) == 1
    assert not (tmp_path / "o2.nc").exists()


def test_compensate_kernel_matches_a_numpy_gauss_newton(machine, cal):
    """`compensate` (Rust kernel) against the same iteration written with NumPy here."""
    c0 = machine.sample_commands(200, seed=3)
    p = calibration_parameters(machine, cal)
    idx = [1, 2, 3, 4]
    target = machine.nominal(c0)
    c = c0.copy()
    for _ in range(4):
        miss = (machine.nominal(c) + machine.volumetric_error(c, p) - target).reshape(-1, 3, 1)
        jac = machine.command_jacobian(c).reshape(-1, 3, 5)[:, :, idx]
        c[:, idx] -= (np.linalg.pinv(jac) @ miss)[:, :, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got, left = compensate(machine, cal, c0)
    assert np.abs(got - c).max() < 1e-9 and np.abs(left).max() < 1e-9
