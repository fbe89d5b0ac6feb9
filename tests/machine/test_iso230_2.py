"""ISO 230-2:2014 positioning figures (issue 15 part 3): hand-computed values, a published test
report (with the two mistakes we found in it), inconsistent runs, the CLI and its report."""

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gagekit.samples import sample_path
from gagekit.errors import FileFormatError, InvalidInputError
from gagekit.machine.iso230_2 import iso230_2, read_runs

ECMC = sample_path("iso230-2")


def write_runs(path: Path, rows) -> Path:
    path.write_text("target,direction,cycle,measured\n" + "".join(f"{t},{d},{c},{m!r}\n" for t, d, c, m in rows))
    return path


def small(tmp_path):
    dev = {(0.0, "+"): [1, 2, 3], (0.0, "-"): [0, 0, 3], (100.0, "+"): [4, 5, 6], (100.0, "-"): [6, 6, 6]}  # um
    rows = [(t, d, c + 1, t + v * 1e-3) for (t, d), vs in dev.items() for c, v in enumerate(vs)]
    return write_runs(tmp_path / "runs.csv", rows)


def test_hand_computed_small_set(tmp_path):
    r = iso230_2(*read_runs(small(tmp_path)))
    s3 = math.sqrt(3.0)  # s_down at target 0: deviations 0, 0, 3 about their mean 1
    want = {  # um, from the formulas of ISO 230-2:2014 clause 3, worked by hand
        "B": 1.0, "B_mean": 0.0,
        "R_up": 4.0, "R_down": 4 * s3, "R": max(2 + 2 * s3 + 1, 4.0, 4 * s3),
        "E_up": 3.0, "E_down": 5.0, "E": 5.0, "M": 4.0,
        "A_up": 7.0, "A_down": 6.0 - (1 - 2 * s3), "A": 7.0 - (1 - 2 * s3),
    }
    for k, v in want.items():
        assert getattr(r, k) * 1e3 == pytest.approx(v, abs=1e-9), k
    t0, t1 = r.targets
    assert (t0.mean_up, t0.mean_down, t0.B) == pytest.approx((2e-3, 1e-3, 1e-3))
    assert (t0.s_up, t0.s_down) == pytest.approx((1e-3, s3 * 1e-3))
    assert (t1.mean, t1.B, t1.R) == pytest.approx((5.5e-3, -1e-3, 4e-3))
    assert r.cycles == 3


def test_published_report_and_its_two_mistakes():
    """The ecmc ISO 230-2 report (tests/data/README.md): every figure it prints agrees within
    its rounding (5 decimals) except two, whose definitions it gets wrong:
    - R: printed 0.0075 mm as max(R_fwd, R_bwd); ISO 230-2 defines R as max R_i, and the
      report's own table has R(3) = 0.00835 mm;
    - E: printed 0.01485 mm (= E_bwd); ISO 230-2's bidirectional systematic deviation is
      max(x_up, x_down) - min(x_up, x_down) = 0.006968 - (-0.00902) = 0.01599 mm."""
    r = iso230_2(*read_runs(ECMC))
    printed = {"A_up": 0.01806, "A_down": 0.01655, "A": 0.01858, "E_up": 0.01505, "E_down": 0.01485, "M": 0.01495,
               "R_up": 0.0075, "R_down": 0.00388, "B": 0.00456, "B_mean": 0.00069}
    for k, v in printed.items():
        assert getattr(r, k) == pytest.approx(v, abs=1.5e-5), k
    per_target = {"B": [-0.00196, 0.00456, 0.00293, -0.00114, -0.00094], "s_up": [0.00067, 0.00046, 0.00188, 0.00098, 0.00052],
                  "s_down": [0.00097, 0.00039, 0.00083, 0.00054, 0.00031], "R": [0.00524, 0.00628, 0.00835, 0.00419, 0.00259],
                  "mean": [0.00323, -0.00189, 0.00062, -0.00845, 0.0065]}
    for k, vs in per_target.items():
        assert [getattr(t, k) for t in r.targets] == pytest.approx(vs, abs=1.5e-5), k
    assert r.R == pytest.approx(0.008354, abs=1e-6) and abs(r.R - 0.0075) > 5e-4
    assert r.E == pytest.approx(0.015988, abs=1e-6) and abs(r.E - 0.01485) > 1e-3


@pytest.mark.parametrize(
    "rows, message",
    [
        ([(0, "+", 1, 0.0), (0, "+", 2, 0.0), (0, "-", 1, 0.0), (0, "-", 2, 0.0), (10, "+", 1, 10.0), (10, "+", 2, 10.0)], "measured up (+) only"),
        ([(0, "+", 1, 0.0), (0, "-", 1, 0.0), (10, "+", 1, 10.0), (10, "-", 1, 10.0)], "at least 2 are needed"),
        ([(0, "+", 1, 0.0), (0, "+", 2, 0.0), (0, "-", 1, 0.0), (10, "+", 1, 10.0), (10, "+", 2, 10.0), (10, "-", 1, 10.0), (10, "-", 2, 10.0)], "unequal numbers of cycles"),
        ([(0, "+", 1, 0.0), (0, "+", 1, 0.001)], "read twice"),
        ([(0, "+", 1, 0.0), (0, "-", 1, 0.0), (0, "+", 2, 0.0), (0, "-", 2, 0.0)], "1 target position"),
    ],
)
def test_inconsistent_runs(tmp_path, rows, message):
    with pytest.raises(InvalidInputError, match=re.escape(message)):
        read_runs(write_runs(tmp_path / "r.csv", rows))


def test_malformed_files(tmp_path):
    (tmp_path / "a.csv").write_text("target,dir,cycle,measured\n0,+,1,0\n")
    with pytest.raises(FileFormatError, match="missing column"):
        read_runs(tmp_path / "a.csv")
    (tmp_path / "b.csv").write_text("target,direction,cycle,measured\n0,left,1,0\n")
    with pytest.raises(FileFormatError, match="direction must be"):
        read_runs(tmp_path / "b.csv")
    with pytest.raises(InvalidInputError):
        iso230_2([0.0, 1.0], np.zeros((2, 3)), np.zeros((2, 2)))


def test_cli_json_and_report(tmp_path):
    run = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, a)], capture_output=True, text=True)  # noqa: E731
    p = run("iso230-2", ECMC, "--json", "--report", tmp_path / "rep")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert set(d) >= {"A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean", "targets"}
    assert d["cycles"] == 5 and len(d["targets"]) == 5 and set(d["targets"][0]) >= {"target", "mean_up", "mean_down", "s_up", "s_down", "B", "R"}
    html = (tmp_path / "rep" / "report.html").read_text()
    assert "ISO 230-2" in html and (tmp_path / "rep" / "iso230-2.png").stat().st_size > 1000
    bad = write_runs(tmp_path / "bad.csv", [(0, "+", 1, 0.0), (0, "+", 2, 0.0)])
    p = run("iso230-2", bad)
    assert p.returncode == 2 and p.stderr.startswith("gagekit: error: ") and len(p.stderr.splitlines()) == 1


def test_text_table_prints_um_to_three_decimals():
    """Every um value of the text output is the JSON value to 0.001 um, printed with three
    decimals (issue 22 section 6: it was rounded to 0.001 um and printed with four)."""
    import re
    import subprocess
    import sys

    run = lambda *a: subprocess.run([sys.executable, "-m", "gagekit", "machine", "iso230-2", str(ECMC), *a],  # noqa: E731
                                    capture_output=True, text=True, timeout=120)
    text, d = run().stdout, json.loads(run("--json").stdout)
    lines = text.splitlines()  # title, the summary values, blank, header, dashes, one row per target
    fixed = lambda v: (lambda s: s[1:] if s.startswith("-") and float(s) == 0 else s)(f"{1e3 * v:.3f}")  # noqa: E731
    for key, value in re.findall(r"(\w+) (-?\d+\.\d+)", lines[1]):
        assert value == fixed(d[key]), key
    rows = [ln.split() for ln in lines[5:] if ln.strip()]
    assert len(rows) == len(d["targets"]) == 5
    for row, t in zip(rows, d["targets"]):
        assert row[1:] == [fixed(t[k]) for k in ("mean_up", "mean_down", "s_up", "s_down", "R", "B")], row
