"""Machine observers (Sec. 4.2, 4.3.1): plans, zones, exclusions, simulated evaluation, CLI."""

import json
import subprocess
import sys

import numpy as np
import pytest

import gagekit
from gagekit.errors import ConfigError, DegenerateGeometryError, GagekitError, InvalidInputError
from gagekit.machine import load_machine, read_commands
from gagekit.machine.observer import (
    ObserverSpace,
    design_observer,
    dissertation_zones,
    evaluate_plan,
    read_exclusions,
    read_zones,
)

EXAMPLE = gagekit.machine.example_machine_path()
FAST = dict(candidates=1500, starts=1)


@pytest.fixture(scope="module")
def machine():
    return load_machine(EXAMPLE)


@pytest.fixture(scope="module")
def space(machine):
    return ObserverSpace.of(machine)


def test_space_uses_the_redundant_sum(space, machine):
    assert space.names == ("B", "X", "Z+W", "Y", "W")
    c = machine.sample_commands(5, seed=2)
    assert np.allclose(space.to_commands(space.to_u(c)), c)
    assert np.allclose(space.bounds[2], [100.0, 2000.0])
    # scaled columns are of order one over the workspace
    rows = space.rows(space.to_u(machine.sample_commands(500, seed=3)))
    assert rows.shape == (500, 3, 32)
    assert 0.05 < np.abs(rows).max(axis=(0, 1)).min() and np.abs(rows).max() < 5


def test_dissertation_zones_are_eight_equal_volumes(space):
    zones = dissertation_zones(space, 80)
    assert [z[2] for z in zones] == [10] * 8
    u = space.bounds[:, 0] + np.random.default_rng(0).random((40000, 5)) * np.ptp(space.bounds, axis=1)
    from gagekit.design.optimal import _in_zone

    frac = [float(_in_zone(u, (*z[:2], z[2], z[3])).mean()) for z in zones]
    assert frac == pytest.approx([1 / 8] * 8, abs=0.01)


def test_plan_honours_zones_and_beats_quasi_random(machine, tmp_path):
    plan = design_observer(machine, 32, "A", "dissertation-8", **FAST)
    assert [z["count"] for z in plan.zone_counts] == [4] * 8
    r = machine.ranges
    assert ((plan.commands >= r[:, 0] - 1e-9) & (plan.commands <= r[:, 1] + 1e-9)).all()
    assert plan.figures["trace"] < plan.quasi_random["same_size"]["trace"]
    plan.write(tmp_path / "plan.csv")
    assert np.allclose(read_commands(tmp_path / "plan.csv", machine), plan.commands)
    again = design_observer(machine, 32, "A", "dissertation-8", **FAST)
    assert np.array_equal(again.commands, plan.commands)


def test_exclusions_are_avoided(machine, space, tmp_path):
    f = tmp_path / "excl.toml"
    f.write_text('commands = [[0, -1250, 900, 350, -800]]\n\n[[box]]\nX = [0, 1250]\n"Z+W" = [1000, 2000]\n')
    ex = read_exclusions(f, space)
    plan = design_observer(machine, 32, "D", exclude=ex, **FAST)
    c = plan.commands
    inside = (c[:, 1] >= 0) & (c[:, 2] + c[:, 4] >= 1000)
    assert not inside.any()
    near = (np.abs(c - [0, -1250, 900, 350, -800]) <= 0.01 * np.ptp(machine.ranges, axis=1)).all(axis=1)
    assert not near.any()
    assert ex.mask(space, space.to_u(c)).all()


def test_user_zones(machine, space, tmp_path):
    f = tmp_path / "zones.toml"
    f.write_text("[[zone]]\ncount = 5\nY = [350, 800]\n\n[[zone]]\ncount = 6\nX = [-1250, -1000]\n")
    plan = design_observer(machine, 32, "A", read_zones(f, space), **FAST)
    assert [z["count"] for z in plan.zone_counts] == [5, 6]
    bad = tmp_path / "bad.toml"
    bad.write_text("[[zone]]\ncount = 2\nQ = [0, 1]\n")
    with pytest.raises(ConfigError, match="unknown variable 'Q'"):
        read_zones(bad, space)


@pytest.mark.parametrize(
    "kwargs,exc,msg",
    [
        (dict(points=10), InvalidInputError, "at least 32 points"),
        (dict(criterion="Z"), InvalidInputError, "unknown design criterion"),
        (dict(zones="dissertation-9"), InvalidInputError, "unknown zones"),
        (dict(candidates=5), InvalidInputError, "--candidates"),
    ],
)
def test_bad_plans(machine, kwargs, exc, msg):
    args = dict(points=32, criterion="A", zones="none", **FAST)
    args.update(kwargs)
    with pytest.raises(exc, match=msg):
        design_observer(machine, **args)


def test_exclusions_leaving_nothing(machine, space, tmp_path):
    f = tmp_path / "all.toml"
    f.write_text("[[box]]\nX = [-2000, 2000]\n")
    with pytest.raises(DegenerateGeometryError, match="exclusions leave"):
        design_observer(machine, 32, exclude=read_exclusions(f, space), **FAST)


def test_evaluation_ranks_plans(machine):
    plan = design_observer(machine, 40, "A", **FAST)
    ev = evaluate_plan(machine, plan.commands, seeds=3)
    p = ev.plans
    assert set(p) == {"plan", "quasi_random_same_size", "quasi_random_290"}
    # 290 points beat 40; the optimal 40 beat quasi-random 40 (simulated, 3 machines)
    assert p["quasi_random_290"]["rms_um"] < p["plan"]["rms_um"] < p["quasi_random_same_size"]["rms_um"]
    with pytest.raises(InvalidInputError, match="at least 32 points"):
        evaluate_plan(machine, plan.commands[:20], seeds=1)


def gk(*args, ok=True):
    proc = subprocess.run([sys.executable, "-m", "gagekit", "machine", *map(str, args)], capture_output=True, text=True, timeout=300)
    if ok:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_cli_design_and_evaluate(tmp_path):
    out = gk("design", EXAMPLE, "--points", 32, "--zones", "dissertation-8", "--candidates", 1500, "--starts", 1,
             "--out", tmp_path / "plan.csv", "--json").stdout
    d = json.loads(out)
    for key in ("criterion", "points", "trace", "log_det", "condition_number", "zone_counts", "quasi_random", "column_scaling"):
        assert key in d
    assert len(d["points"]) == 32 and d["quasi_random"]["full_290"]["points"] == 290
    ev = json.loads(gk("evaluate-plan", EXAMPLE, tmp_path / "plan.csv", "--seeds", 2, "--no-compare", "--json").stdout)
    assert list(ev["plans"]) == ["plan"] and ev["plans"]["plan"]["rms_um"] > 0
    bad = gk("design", EXAMPLE, "--points", 5, "--out", tmp_path / "x.csv", ok=False)
    assert bad.returncode == 2 and "at least 32 points" in bad.stderr and bad.stdout == ""
