"""`gagekit machine design | evaluate-plan`: optimal error observers (Ch. 4).

Registered on the ``machine`` sub-application by the import at the end of ``cli/machine.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import InvalidInputError
from ._common import JSON_OPTION, emit, table
from .machine import MACHINE_ARG, _warnings_to_stderr, app


def _sci(v: float) -> str:
    return f"{v:.4g}"


@app.command("design")
def design_cmd(
    machine_file: Path = MACHINE_ARG,
    points: int = typer.Option(80, "--points", help="Measurement points in the plan (Sec. 4.2: 80)."),
    criterion: str = typer.Option("A", "--criterion", help="A, D, K, E or I (default A: it predicted best in simulation)."),
    zones: str = typer.Option("none", "--zones", help="none, dissertation-8 (Fig. 4.3) or a zones TOML file."),
    exclude: Optional[Path] = typer.Option(None, "--exclude", help="Exclusions TOML: [[box]] tables and/or commands to avoid."),
    candidates: int = typer.Option(20000, "--candidates", help="Quasi-random candidate commands."),
    seed: int = typer.Option(0, "--seed", help="Seed of candidates and search (same seed, same plan)."),
    starts: int = typer.Option(4, "--starts", help="Independent starts of the exchange search."),
    out: Path = typer.Option(..., "--out", help="PLAN.csv to write: one column per joint."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Design an optimal observer plan (Eqs. 4.3-4.8) for the machine's identifiable groups."""
    from ..machine import load_machine
    from ..machine.observer import ObserverSpace, design_observer, read_exclusions, read_zones

    m = load_machine(machine_file)
    space = ObserverSpace.of(m)
    zone_arg = zones
    if zones not in ("none", "dissertation-8"):
        zp = Path(zones)
        if not zp.suffix.lower() == ".toml" and not zp.exists():
            raise InvalidInputError(f"--zones: use none, dissertation-8 or a zones TOML file (got {zones!r})")
        zone_arg = read_zones(zp, space)
    excl = read_exclusions(exclude, space) if exclude is not None else None
    with _warnings_to_stderr():
        plan = design_observer(m, points, criterion, zone_arg, exclude=excl, candidates=candidates, seed=seed,
                               starts=starts, structure=space.structure)
    plan.write(out)
    result = {**plan.to_dict(), "out": str(out)}
    if zones not in ("none", "dissertation-8"):
        result["zones"] = str(zones)

    def human(r: dict) -> str:
        f, q = plan.figures, plan.quasi_random
        rows = [[f"{plan.criterion}-optimal ({plan.zones} zones)", len(plan.commands), _sci(f["trace"]), _sci(f["det"]), _sci(f["condition_number"])]]
        for key, label in (("same_size", "quasi-random"), ("full_290", "quasi-random")):
            rows.append([label, q[key]["points"], _sci(q[key]["trace"]), _sci(q[key]["det"]), _sci(q[key]["condition_number"])])
        lines = [
            table(["plan", "points", "tr((M^T M)^-1)", "|(M^T M)^-1|", "kappa(M)"], rows),
            "",
            f"columns: {plan.scaling['groups']} identifiable groups, each divided by L^p (L = {plan.scaling['length_scale_mm']:.1f} mm; "
            "p = 0 mm, 1 rad, 2 rad/mm)",
        ]
        if plan.zone_counts:
            lines.append("zone counts: " + ", ".join(f"{z['zone'] + 1}: {z['count']}" for z in plan.zone_counts))
        lines.append(f"wrote {len(plan.commands)} commands to {out}")
        return "\n".join(lines)

    emit(result, as_json, human)


@app.command("evaluate-plan")
def evaluate_plan_cmd(
    machine_file: Path = MACHINE_ARG,
    plan: Path = typer.Argument(..., help="PLAN.csv (joint columns), e.g. from `machine design`."),
    seeds: int = typer.Option(20, "--seeds", help="Random machines simulated."),
    noise: float = typer.Option(0.0089, "--noise", help="Tracker noise sigma per coordinate, mm."),
    test_points: int = typer.Option(2000, "--test-points", help="Quasi-random commands where predictions are compared."),
    seed: int = typer.Option(0, "--seed", help="Seed of machines, noise and test commands."),
    compare: bool = typer.Option(True, "--compare/--no-compare", help="Also evaluate quasi-random plans of the same size and of 290 points."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Simulate identification from the plan and report the RMS prediction error over the workspace."""
    from ..machine import load_machine, read_commands
    from ..machine.observer import evaluate_plan

    m = load_machine(machine_file)
    with _warnings_to_stderr():
        cmds = read_commands(plan, m, warn_range=True)
        ev = evaluate_plan(m, cmds, seeds=seeds, noise=noise, test_points=test_points, seed=seed, compare=compare)

    def human(_) -> str:
        rows = [[p["label"], p["points"], f"{p['rms_um']:.2f}", f"{p['rms_um_std']:.2f}", f"{p['rms_um_max']:.2f}"] for p in ev.plans.values()]
        head = (f"RMS prediction error of the volumetric error over {ev.test_points} commands, "
                f"{ev.seeds} simulated machines, tracker noise {ev.noise * 1000:.1f} um (rigid motion removed)")
        return head + "\n\n" + table(["plan", "points", "RMS um", "std", "max"], rows)

    emit(ev, as_json, human)
