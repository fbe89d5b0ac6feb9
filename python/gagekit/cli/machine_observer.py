"""`gagekit machine design | evaluate-plan`: optimal error observers (Ch. 4).

Registered on the ``machine`` sub-application by :func:`register`, called in ``cli/__init__.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import ConfigError, InvalidInputError
from ._common import JSON_OPTION, count_option, emit, float_option, seed_option, table
from .machine import MACHINE_ARG, NOISE_OPTION, _outputs, _warnings_to_stderr, _write_simulation


def _sci(v: float) -> str:
    return f"{v:.4g}"


def design_cmd(
    machine_file: Path = MACHINE_ARG,
    points: int = count_option(80, "--points", help="Measurement points in the plan (Sec. 4.2: 80)."),
    criterion: str = typer.Option("I", "--criterion", help="A, D, K, E or I (default I: it predicted best in simulation; see README)."),
    zones: str = typer.Option("none", "--zones", help="none, dissertation-8 (Fig. 4.3) or a zones TOML file."),
    exclude: Optional[Path] = typer.Option(None, "--exclude", help="Exclusions TOML: [[box]] tables and/or commands to avoid."),
    candidates: int = count_option(20000, "--candidates", help="Quasi-random candidate commands."),
    seed: int = seed_option(help="Seed of candidates and search (same seed, same plan)."),
    starts: int = count_option(4, "--starts", help="Independent starts of the exchange search."),
    out: Path = typer.Option(..., "--out", help="PLAN.csv to write: one column per joint."),
    instrument: Optional[str] = typer.Option(
        None, "--instrument", help="sphere, rtest (rotary positions to probe) or ballbar (circles: plane and centre) instead of tracker points."
    ),
    sphere: Optional[str] = typer.Option(None, "--sphere", help="--instrument sphere/rtest: the sphere's place on the table, x,y,z mm (table frame)."),
    at: Optional[str] = typer.Option(None, "--at", help="--instrument: joints held fixed, e.g. W=-500."),
    radius: float = typer.Option(150.0, "--radius", help="--instrument ballbar: ballbar length, mm."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Design an optimal observer plan (Eqs. 4.3-4.8) for the machine's identifiable groups."""
    from ..machine import load_machine
    from ..machine.observer import ObserverSpace, design_observer, read_exclusions, read_zones

    _outputs(out)
    m = load_machine(machine_file)
    if instrument is not None:
        from .machine_instruments import design_instrument_cmd

        return design_instrument_cmd(m, instrument, points, criterion, sphere, at, radius, seed, out, as_json)
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
        label = f"{plan.criterion}-optimal" + ("" if plan.zones == "none" else f" ({zones} zones)")
        rows = [[label, len(plan.commands), _sci(f["trace"]), _sci(f["det"]), _sci(f["condition_number"])]]
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


def evaluate_plan_cmd(
    machine_file: Path = MACHINE_ARG,
    plan: Path = typer.Argument(..., help="PLAN.csv (joint columns), e.g. from `machine design`."),
    seeds: int = count_option(20, "--seeds", help="Random machines simulated."),
    noise: float = NOISE_OPTION,
    test_points: int = count_option(2000, "--test-points", help="Quasi-random commands where predictions are compared."),
    seed: int = seed_option(help="Seed of machines, noise and test commands."),
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


def _track_text(r) -> str:
    rows = []
    for c in r.cycles:
        rows.append([c["cycle"], f"{c['observed']['mean'] * 1000:.1f}", f"{c['observed']['max'] * 1000:.1f}"]
                    + [f"{c[k]['mean'] * 1000:.1f} / {c[k]['max'] * 1000:.1f}" for k in ("full", "static", "drift_only")])
    text = "residuals at the plan's points, um (mean / max)\n\n" + table(
        ["cycle", "observed mean", "observed max", "full (Table 4.4)", "static (Table 4.5)", "drift only (Table 4.6)"], rows)
    tm = r.temperature_model
    if tm and tm.get("fitted"):
        text += (f"\n\ntemperature model over {', '.join(tm['sensors'])}: leave-one-cycle-out mean residual "
                 f"{tm['leave_one_cycle_out_mean'] * 1000:.1f} um")
    return text


def track_cmd(
    machine_file: Path = MACHINE_ARG,
    cycles_csv: Path = typer.Argument(..., help="Observations of repeated cycles: cycle, joints, x, y, z [, time, temp_*]."),
    history: Optional[Path] = typer.Option(None, "--history", help="SQLite history of this machine to append the run to."),
    report: Optional[Path] = typer.Option(None, "--report", help="Directory for track.json and the drift plot (Fig. 4.8)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Track the error model cycle by cycle against static and drift-only calibrations (Tables 4.4-4.6)."""
    from .._util import dumps
    from ..machine import load_machine
    from ..machine.tracking import History, read_cycles, track
    from ..report.machine import plot_drift

    from .._files import output_dir

    if report is not None:
        output_dir(report)
    m = load_machine(machine_file)
    from ..machine.instruments import cycles_kind

    if cycles_kind(cycles_csv) == "sphere":  # sphere-probing cycles: rotary-axis location errors per cycle
        from .machine_instruments import track_sphere_cmd

        return track_sphere_cmd(m, cycles_csv, history, report, as_json)
    # the history is opened (and a foreign, damaged, read-only or other machine's file refused)
    # before the computation, so that no computed run is lost to a bad --history path
    h = History(history, m) if history is not None else None
    try:
        with _warnings_to_stderr():
            cyc = read_cycles(cycles_csv, m)
            res = track(m, cyc)
        out = res.to_dict()
        if h is not None:
            out["history_run"] = h.append(cyc, res)
    finally:
        if h is not None:
            h.close()
    if report is not None:
        from .._files import atomic_dir, write_text
        from ..report import Report
        from ..report.machine import add_tracking

        with atomic_dir(report) as tmp:
            write_text(tmp / "track.json", dumps(out))
            plot_drift(res, tmp / "drift.png")
            rep = Report(f"Thermal tracking of {m.name}", f"{cycles_csv}: {len(res.cycles)} cycles")
            rep.section("Residuals and drift per cycle (Sec. 4.3.3)")
            add_tracking(rep, res)
            page = rep.write(tmp).name
        out["report"] = str(report / page)
    emit(out, as_json, lambda _: _track_text(res))


def history_cmd(
    history_file: Path = typer.Argument(..., help="SQLite history written by `machine track --history`."),
    as_json: bool = JSON_OPTION,
) -> None:
    """List the tracking runs stored in a history file."""
    from ..machine.tracking import read_history

    s = read_history(history_file)

    def human(_) -> str:
        lines = [f"history of machine {s['machine']} (created {s['created']}), {len(s['runs'])} run(s)"]
        for run in s["runs"]:
            lines.append(f"\nrun {run['run']} ({run['created']}, {run['points']} points, {run['source']})")
            lines.append(table(["cycle", "observed um", "full um", "static um", "drift only um"],
                               [[c["cycle"], f"{c['observed_mean'] * 1000:.1f}", f"{c['full_mean'] * 1000:.1f}",
                                 f"{c['static_mean'] * 1000:.1f}", f"{c['drift_only_mean'] * 1000:.1f}"] for c in run["cycles"]]))
        return "\n".join(lines)

    emit(s, as_json, human)


def simulate_cycles_cmd(
    machine_file: Path = MACHINE_ARG,
    plan: Optional[Path] = typer.Argument(None, help="PLAN.csv (joint columns) measured in every cycle (or --plan)."),
    out: Path = typer.Option(..., "--out", help="Cycles CSV to write (cycle, joints, x, y, z, time, temp_*)."),
    plan_option: Optional[Path] = typer.Option(None, "--plan", help="PLAN.csv, as `machine simulate --plan` takes it."),
    cycles: int = count_option(6, "--cycles", help="Measurement cycles (Fig. 4.4: 4 heating, 1 cooling after the first)."),
    noise: float = NOISE_OPTION,
    drift_scale: float = float_option(1.0, "--drift-scale", help="Scale of the W- and Y-axis thermal drift."),
    seed: int = seed_option(help="Seed of the truth, drift signs and noise."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Short for `machine simulate MACHINE.toml --plan PLAN.csv --cycles N` (thermal mode)."""
    from ..machine import Truth, load_machine, read_commands

    if (plan is None) == (plan_option is None):
        raise ConfigError("give the plan once: simulate-cycles MACHINE.toml PLAN.csv, or --plan PLAN.csv")
    plan = plan if plan is not None else plan_option
    _outputs(out)
    if cycles < 1:
        raise InvalidInputError(f"--cycles must be at least 1, got {cycles}")
    m = load_machine(machine_file)
    result = _write_simulation(m, Truth.random(m, seed=seed), read_commands(plan, m), out, cycles=cycles,
                               noise=noise, drift_scale=drift_scale, seed=seed)
    emit(result, as_json, lambda r: f"wrote {r['cycles']} cycles of {r['points']} points to {r['out']}")


#: (command name, function) of this module, in help order.
COMMANDS = (
    ("design", design_cmd),
    ("evaluate-plan", evaluate_plan_cmd),
    ("track", track_cmd),
    ("history", history_cmd),
    ("simulate-cycles", simulate_cycles_cmd),
)


def register(app: typer.Typer) -> None:
    """Add this module's commands to the ``machine`` sub-application ``app``."""
    for name, fn in COMMANDS:
        app.command(name)(fn)
