"""One rule, in one place, for using a calibration with a machine (issue 22 section 4):
another machine's calibration is refused by predict, its uncertainty, compensate, export and
compensate-nc alike, in the library and on the command line."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from conftest import EXAMPLE_MACHINE
from gagekit.errors import ConfigError
from gagekit.machine import Truth, compensate, identify, predict, simulate
from gagekit.machine.export import export
from gagekit.machine.nc import compensate_nc_text
from gagekit.machine.predict import predict_uncertainty

WANT = "the calibration is of machine 'another-machine', not 'dissertation-5axis-BXZYW'"


@pytest.fixture(scope="module")
def foreign(machine):
    truth = Truth.random(machine, seed=3)
    cal = identify(machine, simulate(machine, truth, machine.sample_commands(290, seed=3), seed=4))
    return dataclasses.replace(cal, machine="another-machine")


def test_every_use_refuses_another_machines_calibration(machine, foreign, tmp_path):
    cmds = machine.sample_commands(5, seed=1)
    uses = {
        "predict": lambda: predict(machine, foreign, cmds),
        "uncertainty": lambda: predict_uncertainty(machine, foreign, cmds),
        "compensate": lambda: compensate(machine, foreign, cmds),
        "export": lambda: export(machine, foreign, "grid-csv", tmp_path / "g.csv"),
        "compensate-nc": lambda: compensate_nc_text(machine, foreign, b"G0 B0 X0 Y400 Z1000 W-500\n"),
    }
    for name, use in uses.items():
        with pytest.raises(ConfigError) as e:
            use()
        assert str(e.value).startswith(WANT), name
    assert not (tmp_path / "g.csv").exists()


def test_cli_predict_and_compensate_refuse_it(machine, foreign, tmp_path):
    cal = tmp_path / "cal.json"
    foreign.save(cal)
    cmds = tmp_path / "cmds.csv"
    np.savetxt(cmds, machine.sample_commands(4, seed=2), delimiter=",", header=",".join(machine.joint_names), comments="")
    for verb in ("predict", "compensate"):
        r = subprocess.run([sys.executable, "-m", "gagekit", "machine", verb, str(EXAMPLE_MACHINE), str(cal), str(cmds),
                            "--out", str(tmp_path / f"{verb}.csv")], capture_output=True, text=True)
        assert r.returncode == 2, (verb, r.stderr)
        assert r.stderr.startswith("gagekit: error: " + WANT) and len(r.stderr.splitlines()) == 1
        assert not (tmp_path / f"{verb}.csv").exists()
