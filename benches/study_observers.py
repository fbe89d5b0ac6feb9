"""Which observer criterion and zones predict best? The study behind the README's table and
the default of `gagekit machine design` (issue 7).

For each criterion (I, A, D, E, K) and zones (none, dissertation-8) and design seed, design an
80-point plan for the example machine, then run `evaluate_plan`: random machines (Table 3.3
magnitudes), noisy tracker readings (8.9 um) at the plan's commands, identification, and the RMS
error of the predicted volumetric error over quasi-random workspace commands (rigid motion of the
table frame removed). The same machines and test commands serve every plan, and quasi-random
plans of 80 and 290 points are the reference.

    python benches/study_observers.py [--points 80] [--machines 12] [--design-seeds 0 1]
                                      [--candidates 20000] [--starts 4]

Prints one markdown table (RMS um per design seed) and the design time of each plan.
"""

from __future__ import annotations

import argparse
import time

from gagekit.machine import example_machine_path, load_machine
from gagekit.machine.observer import design_observer, evaluate_plan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=80)
    ap.add_argument("--machines", type=int, default=12, help="random machines per plan")
    ap.add_argument("--design-seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--candidates", type=int, default=20000)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--test-points", type=int, default=2000)
    args = ap.parse_args()

    m = load_machine(example_machine_path())
    study = dict(seeds=args.machines, test_points=args.test_points, seed=0)
    rms: dict[tuple[str, str], list[float]] = {}
    reference = None
    for crit in ("I", "A", "D", "E", "K"):
        for zones in ("none", "dissertation-8"):
            for s in args.design_seeds:
                t0 = time.perf_counter()
                plan = design_observer(m, args.points, crit, zones=zones, candidates=args.candidates,
                                       starts=args.starts, seed=s)
                t_design = time.perf_counter() - t0
                ev = evaluate_plan(m, plan.commands, compare=reference is None, **study)
                if reference is None:
                    reference = ev.plans
                value = ev.plans["plan"]["rms_um"]
                rms.setdefault((crit, zones), []).append(value)
                print(f"# {crit} {zones:15s} seed {s}: design {t_design:5.2f} s, RMS {value:.2f} um", flush=True)

    print(f"\nRMS prediction error over the workspace, um ({args.points} points, {args.machines} machines, "
          f"design seeds {', '.join(map(str, args.design_seeds))}):\n")
    print("| criterion | no zones | dissertation-8 zones |")
    print("| :-- | --: | --: |")
    for crit in ("I", "A", "D", "E", "K"):
        cells = [", ".join(f"{v:.2f}" for v in rms[(crit, z)]) for z in ("none", "dissertation-8")]
        print(f"| {crit} | {cells[0]} | {cells[1]} |")
    for key, p in reference.items():
        if key != "plan":
            print(f"| {p['label']} | {p['rms_um']:.2f} | |")


if __name__ == "__main__":
    main()
