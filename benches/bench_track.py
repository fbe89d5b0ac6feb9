"""Time of `gagekit machine track` with a temperature model (issue 22: 365 daily cycles of an
80-point plan in under 30 s). gagekit: `track` (each training set of the nested
leave-one-cycle-out ridge decomposed once, thin SVD, reused across the 25 strengths); peer:
the same computation written directly (one dual-form ridge solve per training set and
strength, about C^5 operations: tests/machine/ridge_reference.py, the implementation gagekit
had before), with everything else of `track` identical. The peer is run where it finishes
in reasonable time (up to --peer-max cycles); beyond, its time is extrapolated from the
largest measured case with its C^5 cost and marked "(extrapolated)".

    python benches/bench_track.py [--cycles 50 100 150 365] [--points 80] [--peer-max 50]

Cycles: the thermal simulation of `machine simulate --plan --cycles` (heating and cooling,
temperature sensors) on a quasi-random 80-point plan of the example machine. Prints: case, gagekit
time, peer time, ratio (peer / gagekit), and checks that both give the same strengths and
leave-one-cycle-out residuals.
"""

from __future__ import annotations

import argparse
import importlib
import shutil
import sys
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np

import gagekit
from _timing import timed
from gagekit.machine import Truth
from gagekit.machine.tracking import Cycles, read_cycles, simulate_cycles, track

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "machine"))
import ridge_reference  # noqa: E402

tr = importlib.import_module("gagekit.machine.tracking.track")


def make_cycles(machine, plan, n: int, folder: Path) -> Cycles:
    """``n`` simulated cycles of ``plan``, written and read back as `machine track` reads them."""
    blocks, info = simulate_cycles(machine, Truth.random(machine, seed=3), plan, cycles=n, seed=1)
    f = folder / f"cycles{n}.csv"
    np.savetxt(f, np.vstack(blocks), delimiter=",", header=",".join(info["header"]), comments="", fmt="%.12g")
    return read_cycles(f, machine)


def peer_track(machine, cyc, st):
    """`track` with the direct nested ridge of ridge_reference."""
    with mock.patch.object(tr, "_loo_errors", ridge_reference.loo_errors), mock.patch.object(tr, "_ridge", ridge_reference.ridge):
        return track(machine, cyc, structure=st)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, nargs="+", default=[50, 100, 150, 365])
    ap.add_argument("--points", type=int, default=80)
    ap.add_argument("--peer-max", type=int, default=50, help="largest cycle count the peer is run on")
    a = ap.parse_args()
    machine = gagekit.load_machine(gagekit.machine.example_machine_path())
    st = machine.structure()
    plan = machine.sample_commands(a.points, seed=0)  # quasi-random (Halton) plan over the workspace
    folder = Path(tempfile.mkdtemp(prefix="bench_track."))
    print(f"{'case':<44} {'gagekit s':>12} {'peer s':>12} {'ratio':>8}")
    measured = None  # (cycles, peer seconds) of the largest case the peer ran
    for n in a.cycles:
        cyc = make_cycles(machine, plan, n, folder)
        tg, res = timed(lambda: track(machine, cyc, structure=st))
        if n <= a.peer_max:
            tp, ref = timed(lambda: peer_track(machine, cyc, st))
            mine = res.temperature_model["leave_one_cycle_out"]
            theirs = ref.temperature_model["leave_one_cycle_out"]
            assert [x["lambda"] for x in mine] == [x["lambda"] for x in theirs]
            assert np.allclose([x["mean"] for x in mine], [x["mean"] for x in theirs], rtol=1e-9)
            measured = (n, tp)
            label = f"track {n} cycles x {a.points} points"
        elif measured is None:
            print(f"{f'track {n} cycles x {a.points} points':<44} {tg:12.3f} {'(peer not run)':>12}", flush=True)
            continue
        else:
            n0, t0 = measured
            tp = t0 * (n / n0) ** 5
            label = f"track {n} cycles x {a.points} points (peer extrapolated)"
        print(f"{label:<44} {tg:12.3f} {tp:12.1f} {tp / tg:8.1f}", flush=True)
    shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
