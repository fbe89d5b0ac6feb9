"""compensate-nc as a programmer reads its output (issue 22 sections 3, 4 and 6): the
program's own word order and modal words, no repeated F, the redundant W axis left alone
unless named, the true line count, the corrected axes named, moves outside the joint
ranges warned about naming the line, and a max step too small for a move refused in one line
instead of allocating without bound."""

import json
import re
import subprocess
import sys
import time
import warnings

import pytest

from conftest import EXAMPLE_MACHINE
from gagekit.errors import InvalidInputError
from gagekit.machine import Truth, identify, simulate
from gagekit.machine.nc import compensate_nc, compensate_nc_text

# a program written X Y Z (not the machine's B X Z Y W order), in G1 mode from line 3 on
PROGRAM = b"""%
N10 G0 X-1000 Y400 Z1000 B0 W-500 S1200 M3
N20 G1 X-800 F500
N30 Y450
N40 X200 Z1010 F800 (long cut)
N50 M30
%
"""


@pytest.fixture(scope="module")
def cal(machine):
    truth = Truth.random(machine, seed=7)
    return identify(machine, simulate(machine, truth, machine.sample_commands(290, seed=7), seed=8))


def _quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return fn(*a, **k)


def axis_letters(line: str) -> str:
    body = re.sub(r"\([^)]*\)", "", line)
    return "".join(re.findall(r"([XYZBW])-?[0-9.]", body))


def test_inserted_and_appended_words_keep_the_programs_order(machine, cal):
    out, rep = _quiet(compensate_nc_text, machine, cal, PROGRAM)
    lines = out.decode().split("\n")
    assert rep["inserted"] > 10
    inserted = [line for line in lines[2:] if line and not line.startswith(("N", "%"))]
    assert len(inserted) == rep["inserted"]
    for line in inserted:
        letters = axis_letters(line)
        # every inserted block lists its axes in the program's order X, Y, Z, B, W
        assert letters == "".join(c for c in "XYZBW" if c in letters), line
    # N30 wrote Y only: the corrected X and Z are appended after it, X before Z
    n30 = next(l for l in lines if l.startswith("N30"))
    assert re.fullmatch(r"N30 Y450\.\d{4} X-800\.\d{4} Z1000\.\d{4}", n30), n30


def test_no_repeated_feed_or_motion_words(machine, cal):
    out, _ = _quiet(compensate_nc_text, machine, cal, PROGRAM)
    text = out.decode()
    assert len(re.findall(r"F\d", text)) == len(re.findall(rb"F\d", PROGRAM)) == 2
    lines = text.split("\n")
    n20 = lines.index(next(l for l in lines if l.startswith("N20")))
    first = next(k for k, l in enumerate(lines) if k > 1 and not l.startswith(("N10", "%", "(")))
    # the inserted points of N20 come first: G1 and F500 on the first (the mode was G0), then
    # coordinates only; N20 keeps its number and G1, and F500 is not written again
    assert lines[first].startswith("G1 X") and lines[first].endswith(" F500")
    assert all(re.fullmatch(r"X\S+ Y\S+ Z\S+", l) for l in lines[first + 1:n20]), lines[first + 1:n20]
    assert re.fullmatch(r"N20 G1 X-800\.\d{4} Y400\.\d{4} Z1000\.\d{4}", lines[n20]), lines[n20]
    # N40 in G1 mode: its first inserted point needs no G1, only the new feed
    n40 = lines.index(next(l for l in lines if l.startswith("N40")))
    n30 = lines.index(next(l for l in lines if l.startswith("N30")))
    assert re.fullmatch(r"X\S+ Y\S+ Z\S+ F800", lines[n30 + 1]), lines[n30 + 1]
    assert "F" not in lines[n40] and "(long cut)" in lines[n40]


def test_the_redundant_w_axis_is_left_alone_unless_named(machine, cal):
    out, rep = _quiet(compensate_nc_text, machine, cal, PROGRAM)
    assert rep["axes"] == ["X", "Y", "Z"]
    assert re.findall(rb"W-?[0-9.]+", out) == [b"W-500"]  # copied as written, never appended
    out, rep = _quiet(compensate_nc_text, machine, cal, PROGRAM, axes=["W", "X", "Y", "Z"])
    assert rep["axes"] == ["X", "Y", "Z", "W"]  # said in the program's order
    assert len(re.findall(rb"W-?[0-9.]+", out)) > 10 and b"W-500 " not in out


def test_cli_counts_written_lines_and_names_the_corrected_axes(cal, tmp_path):
    calf = tmp_path / "cal.json"
    cal.save(calf)
    (tmp_path / "p.nc").write_bytes(PROGRAM)
    run = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    p = run("compensate-nc", EXAMPLE_MACHINE, calf, tmp_path / "p.nc", "--out", tmp_path / "o.nc")
    assert p.returncode == 0 and p.stderr == "", p.stderr
    written = (tmp_path / "o.nc").read_text().count("\n")
    assert written > 20
    assert p.stdout.startswith(f"wrote {tmp_path / 'o.nc'}: {written} lines (7 read), axes X, Y, Z corrected in 4 moves"), p.stdout
    p = run("compensate-nc", EXAMPLE_MACHINE, calf, tmp_path / "p.nc", "--out", tmp_path / "o.nc", "--json")
    d = json.loads(p.stdout)
    assert d["lines"] == 7 and d["lines_written"] == written and d["axes"] == ["X", "Y", "Z"]


def test_moves_outside_the_joint_ranges_are_warned_naming_the_line(machine, cal, tmp_path):
    text = b"G0 X0 Y400 Z1000 B0 W-500\nG1 X5000 F100\nG0 X0\n"
    with pytest.warns(UserWarning, match=re.escape("NC program: commands outside the machine's joint ranges (X: 1 at line 2)")):
        compensate_nc_text(machine, cal, text)
    # a G91 run-away: 600 mm steps leave the +-1250 mm of X from the third on (line 4)
    runaway = b"G0 X0 Y400 Z1000 B0 W-500\nG91 G1 X600 F100\nX600\nX600\nX600\nG90\n"
    with pytest.warns(UserWarning, match=re.escape("commands outside the machine's joint ranges (X: 2, first at line 4)")):
        compensate_nc_text(machine, cal, runaway)
    calf = tmp_path / "cal.json"
    cal.save(calf)
    (tmp_path / "r.nc").write_bytes(runaway)
    p = subprocess.run([sys.executable, "-m", "gagekit", "machine", "compensate-nc", str(EXAMPLE_MACHINE), str(calf),
                        str(tmp_path / "r.nc"), "--out", str(tmp_path / "o.nc")], capture_output=True, text=True)
    assert p.returncode == 0
    assert p.stderr == (f"gagekit: warning: {tmp_path / 'r.nc'}: commands outside the machine's joint ranges "
                        "(X: 2, first at line 4)\n"), p.stderr
    # inside the ranges: no warning
    _quiet(compensate_nc_text, machine, cal, PROGRAM)


@pytest.mark.parametrize("max_step", [1e-9, 1e-300])
def test_a_max_step_too_small_for_a_move_is_refused(machine, cal, tmp_path, max_step):
    text = b"G0 X-500 Y400 Z1000 B0 W-500\nG1 X500 F100\n"  # a 1 m move
    t0 = time.perf_counter()
    with pytest.raises(InvalidInputError, match=r"^line 2: the correction changes by .* more than 100000: raise the max step"):
        compensate_nc_text(machine, cal, text, max_step=max_step)
    assert time.perf_counter() - t0 < 30
    calf = tmp_path / "cal.json"
    cal.save(calf)
    (tmp_path / "p.nc").write_bytes(text)
    p = subprocess.run([sys.executable, "-m", "gagekit", "machine", "compensate-nc", str(EXAMPLE_MACHINE), str(calf),
                        str(tmp_path / "p.nc"), "--out", str(tmp_path / "o.nc"), "--max-step", str(max_step)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == "" and len(p.stderr.splitlines()) == 1
    assert p.stderr.startswith(f"gagekit: error: {tmp_path / 'p.nc'}, line 2: the correction changes by")
    assert not (tmp_path / "o.nc").exists()


def test_compensate_nc_file_reports_written_lines(machine, cal, tmp_path):
    (tmp_path / "p.nc").write_bytes(PROGRAM)
    res = _quiet(compensate_nc, machine, cal, tmp_path / "p.nc", tmp_path / "o.nc")
    assert res.lines == 7 and res.lines_written == (tmp_path / "o.nc").read_bytes().count(b"\n")
