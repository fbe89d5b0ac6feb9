"""Numbers at the edges (issue 12, items 2, 3, 5, 12): seeds and counts, magnitudes beyond the
documented 1e9 limit (no NaN rows, no Rust panic), the gage verdict independent of how loose
max_shift is, and non-finite results never printed."""

from __future__ import annotations

import json

import numpy as np
import pytest

from .conftest import CASTING_PLY, CASTING_TOML, EXAMPLE_MACHINE, assert_ok, check_outcome, gk_inproc


def _clean(argv, match=None):
    code, out, err = gk_inproc(*argv)
    assert check_outcome(code, out, err, " ".join(map(str, argv))) == "clean", (code, out, err)
    if match:
        assert match in err, err
    return err


@pytest.mark.parametrize("seed,ok", [("-1", False), (str(2**64), False), (str(2**64 - 1), True), ("0", True),
                                     ("x", False)])
def test_seeds(tmp_path, seed, ok):
    argv = ["machine", "simulate", EXAMPLE_MACHINE, "--points", 20, "--out", tmp_path / "o.csv", "--seed", seed, "--json"]
    if ok:
        code, out, err = gk_inproc(*argv)
        assert code == 0, err
    else:
        _clean(argv, "--seed")


@pytest.mark.parametrize("opt,val", [("--starts", -1), ("--starts", 0), ("--points", 0), ("--candidates", -3)])
def test_design_counts(tmp_path, opt, val):
    _clean(["machine", "design", EXAMPLE_MACHINE, opt, val, "--out", tmp_path / "p.csv"], opt)
    assert not (tmp_path / "p.csv").exists()


@pytest.mark.parametrize("opt,val", [("--noise", "nan"), ("--noise", "-1"), ("--scale", "inf"), ("--drift-scale", "nan")])
def test_non_finite_options(tmp_path, opt, val):
    _clean(["machine", "simulate", EXAMPLE_MACHINE, "--points", 20, opt, val, "--out", tmp_path / "o.csv"], opt)


def test_evaluate_plan_needs_test_points(sim):
    _clean(["machine", "evaluate-plan", EXAMPLE_MACHINE, sim / "obs.csv", "--test-points", 0], "--test-points")


@pytest.mark.parametrize("value", ["1e10", "1e160", "1e308", "-1e308"])
def test_commands_beyond_the_limit(sim, tmp_path, value):
    lines = (sim / "obs.csv").read_text().splitlines()
    assert lines[0].split(",")[1] == "X"  # a prismatic joint, mm
    rows = [lines[0]] + [",".join([r.split(",")[0], value, *r.split(",")[2:]]) for r in lines[1:]]
    f = tmp_path / "big.csv"
    f.write_text("\n".join(rows) + "\n")
    err = _clean(["machine", "predict", EXAMPLE_MACHINE, sim / "cal.json", f, "--out", tmp_path / "p.csv"])
    assert "beyond" in err or "outside" in err or "finite" in err, err
    assert not (tmp_path / "p.csv").exists()


@pytest.mark.parametrize("value", ["1e10", "1e160", "1e200", "1e308"])
def test_identify_with_huge_coordinates_is_a_clean_error(sim, tmp_path, value):
    """Was a Rust panic at ident.rs (partial_cmp().unwrap() on NaN singular values)."""
    lines = (sim / "obs.csv").read_text().splitlines()
    rows = [lines[0]] + [",".join([*r.split(",")[:-1], value]) for r in lines[1:]]
    f = tmp_path / "big.csv"
    f.write_text("\n".join(rows) + "\n")
    err = _clean(["machine", "identify", EXAMPLE_MACHINE, f])
    assert "internal error" not in err


def test_gage_verdict_does_not_depend_on_a_loose_max_shift(tmp_path):
    """Issue 12, item 2: max_shift = 1e12 gave 'nonconforming', objective 35.65, instead of
    'conforming', 12.54. Swept over 1e0..1e300 on the bundled casting."""
    text = CASTING_TOML.read_text()
    assert "max_shift = 20.0" in text
    results = {}
    for e in [20.0] + [10.0 ** k for k in range(0, 301, 20)]:
        f = tmp_path / "g.toml"
        f.write_text(text.replace("max_shift = 20.0", f"max_shift = {e!r}"))
        code, out, err = gk_inproc("gage", "check", CASTING_PLY, f, "--no-groups", "--json")
        assert code == 0, err
        d = json.loads(out)
        results[e] = (d["status"], d["objective"])
    ref = results[20.0]
    assert ref[0] == "conforming"
    for e, (status, objective) in results.items():
        if e >= 20.0:
            assert status == ref[0] and objective == pytest.approx(ref[1], rel=1e-6, abs=1e-6), (e, status, objective)


def test_non_finite_results_are_never_printed():
    from gagekit._util import check_finite_result, find_nonfinite
    from gagekit.errors import NumericalError

    assert find_nonfinite({"a": [1.0, {"b": np.array([[0.0, np.nan]])}]}) == "a[1].b[0, 1]"
    assert find_nonfinite({"a": None, "b": "nan", "c": 1}) is None
    with pytest.raises(NumericalError, match="normal\\[2\\]"):
        check_finite_result({"normal": [0.0, 0.0, float("inf")]})


@pytest.mark.parametrize("value", ["1e10", "1e160", "1e308", "-1e308"])
@pytest.mark.parametrize("align", ["none", "best-fit"])
def test_compare_scan_beyond_the_limit(tmp_path, value, align):
    """A scan point beyond 1e9 mm was measured (1e10: a deviation of 1e10 mm in the figures)
    or, from 1e154 on (its square infinite), counted 'beyond --max-distance' with no bound
    given: now one error naming the point and the units."""

    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    obj = tmp_path / "tet.obj"
    obj.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in t))
    pts = np.random.default_rng(0).random((50, 3)) * 0.3
    scan = tmp_path / "scan.xyz"
    scan.write_text("".join(f"{a} {b} {c}\n" for a, b, c in pts) + f"{value} 0.1 0.1\n")
    err = _clean(["compare", scan, obj, "--align", align, "--deviations", tmp_path / "d.npy"], "point 50")
    assert "beyond the supported 1e9" in err and "units" in err, err
    assert not (tmp_path / "d.npy").exists()


@pytest.mark.parametrize("value", ["1e10", "1e160", "1e300"])
def test_compare_cad_vertex_beyond_the_limit(tmp_path, value):
    """A CAD vertex at 1e300 was reported as a degenerate triangle: now the vertex and the units."""
    obj = tmp_path / "big.obj"
    obj.write_text(f"v 0 0 0\nv {value} 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    scan = tmp_path / "scan.xyz"
    scan.write_text("0.1 0.1 0.1\n0.2 0.1 0.1\n")
    _clean(["compare", scan, obj], "vertex 1 has a coordinate of magnitude")
