"""`gagekit machine`: Machine-tool volumetric error models, identification and observers (Ch. 3-4)."""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Optional

import numpy as np
import typer

from ..errors import InvalidInputError
from ..machine.simulate import TRACKER_SIGMA
from ._common import JSON_OPTION, count_option, emit, float_option, seed_option, table, warn

app = typer.Typer(help="Machine-tool volumetric error models, identification and observers (Ch. 3-4).", no_args_is_help=True)

MACHINE_ARG = typer.Argument(..., help="Machine file (TOML).", exists=False, dir_okay=False)
NOISE_OPTION = float_option(TRACKER_SIGMA, "--noise", help="Tracker noise sigma per coordinate, mm (Sec. 3.2.1).")


@contextmanager
def _warnings_to_stderr() -> Iterator[None]:
    """Print warnings (commands outside the joint ranges) as one line each on stderr."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for w in caught:
        warn(w.message)


def _outputs(*paths: Optional[Path]) -> None:
    """Check every output path before the work starts (folder exists and is writable, not a
    folder, not read-only): a bad path fails in a second, not after the computation."""
    from .._files import output_file

    for p in paths:
        if p is not None:
            output_file(p)


def _sci(v: Optional[float]) -> str:
    return "-" if v is None else f"{v:.4e}"


@app.command("check")
def check(
    machine_file: Path = MACHINE_ARG,
    commands: int = count_option(2000, "--commands", help="Quasi-random commands used for the rank analysis."),
    observations: Optional[str] = typer.Option(
        None, "--observations", help="tracker, sphere, rtest, ballbar or a comma list: which groups and rotary-axis location errors each instrument sees, and together."
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Validate a machine file; show its chain, parameters, rank and identifiable groups (Eq. 3.14)."""
    from ..machine import load_machine

    m = load_machine(machine_file)
    if observations is not None:
        from .machine_instruments import check_observations

        return check_observations(m, observations, as_json)
    s = m.structure(n=commands)
    result = {**m.to_dict(), "n_parameters": m.n_parameters, **s.to_dict()}

    def human(_):
        lines = [
            f"machine {m.name}: chain {' '.join(m.chain)} (table -> spindle), tool {list(m.tool)} mm",
            f"{m.n_parameters} parameters, rank {s.rank} (gap s_r/s_r+1 = {s.rank_gap:.1e} over {s.n_commands} commands)",
            f"no effect: {', '.join(s.no_effect) or 'none'}",
            "",
            table(["#", "group"], [[i + 1, g.name] for i, g in enumerate(s.groups)]),
        ]
        return "\n".join(lines)

    emit(result, as_json, human)


@app.command("simulate")
def simulate_cmd(
    machine_file: Path = MACHINE_ARG,
    points: Optional[int] = typer.Option(
        None, "--points", min=1, max=10**9, help="Number of quasi-random commands over the joint ranges (or give --plan)."
    ),
    out: Path = typer.Option(..., "--out", help="Observations CSV to write (joint columns, x, y, z; with --cycles also cycle, time, temp_*)."),
    noise: float = NOISE_OPTION,
    seed: int = seed_option(help="Seed for commands, noise and (without --params) the truth."),
    truth: Optional[Path] = typer.Option(None, "--truth", help="Write the true parameters, groups and frame (JSON)."),
    params: Optional[Path] = typer.Option(
        None,
        "--params",
        help='Truth JSON to use instead of random errors (e.g. written by --truth): {"parameters": {name: value}, '
        '"frame": {"rotation": 3x3, "translation": 3}}; parameters left out are zero.',
    ),
    scale: float = float_option(1.0, "--scale", help="Scale of the random errors (1 = Table 3.3's magnitudes)."),
    plan: Optional[Path] = typer.Option(None, "--plan", help="PLAN.csv (joint columns): measure these commands instead of --points quasi-random ones."),
    cycles: int = typer.Option(
        0, "--cycles", min=0, max=10**6, help="Thermal mode (Sec. 4.3.2): measure the commands in this many heating/cooling cycles (0: static)."
    ),
    drift_scale: float = float_option(1.0, "--drift-scale", help="Thermal mode: scale of the W- and Y-axis drift (Fig. 4.8)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Simulate laser-tracker observations from the exact perturbed chain (seeded).

    With --cycles N the machine heats and cools over N cycles (thermal mode): the W- and Y-axis
    terms drift as in Fig. 4.8 and the CSV gains cycle, time and temp_* columns, ready for
    `gagekit machine track`.
    """
    from ..machine import Truth, load_machine, read_commands

    _outputs(out, truth)

    m = load_machine(machine_file)
    if (points is None) == (plan is None):
        raise InvalidInputError("give either --points N (quasi-random commands) or --plan PLAN.csv")
    if points is not None and points < 1:
        raise InvalidInputError(f"--points must be at least 1, got {points}")
    if cycles < 0:
        raise InvalidInputError(f"--cycles must be 0 (static) or more, got {cycles}")
    t = Truth.load(params, m) if params is not None else Truth.random(m, seed=seed, scale=scale)
    cmds = read_commands(plan, m) if plan is not None else m.sample_commands(points, seed=seed)
    result = _write_simulation(m, t, cmds, out, cycles=cycles, noise=noise, drift_scale=drift_scale, seed=seed)
    if truth is not None:
        t.save(truth, m)
    result.update(noise=noise, seed=seed, truth=str(truth) if truth else None)

    def human(r):
        what = f"{r['cycles']} cycles of {r['points']} points" if r["cycles"] else f"{r['points']} observations"
        return f"wrote {what} to {r['out']}" + (f", truth to {r['truth']}" if r["truth"] else "")

    emit(result, as_json, human)


def _write_simulation(m, t, cmds, out: Path, *, cycles: int, noise: float, drift_scale: float, seed: int) -> dict:
    """Write simulated observations: static (cycles = 0) or over thermal cycles."""
    from ..machine import simulate

    if cycles == 0:
        obs = simulate(m, t, cmds, noise=noise, seed=seed)
        obs.write(out)
        return {"points": len(obs), "cycles": 0, "out": str(out)}
    from ..machine.observations import write_csv
    from ..machine.tracking import simulate_cycles

    blocks, info = simulate_cycles(m, t, cmds, cycles=cycles, noise=noise, drift_scale=drift_scale, seed=seed)
    write_csv(out, info["header"], np.concatenate(blocks))
    return {"points": int(len(blocks[0])), "cycles": cycles, "out": str(out), "drift_per_cycle": info["drift"]}


def _identify_text(cal) -> str:
    rows = [[g.name, _sci(g.value), _sci(g.std), g.unit + (" (frame)" if g.frame_confounded else "")] for g in cal.groups]
    lines = [
        f"method {cal.method}: rank {cal.rank}, condition number {cal.condition_number:.1f}, "
        f"sigma {cal.sigma * 1000:.2f} um (noise floor {cal.noise_floor * 1000:.2f} um), {cal.iterations} iteration(s)",
        "",
        table(["group", "value", "std", "unit"], rows),
        "",
        f"no effect: {', '.join(cal.unidentifiable) or 'none'}",
    ]
    if cal.frame_confounded:
        how = "taken by the tracker frame" if cal.method == "joint" else "estimated relative to the step-1 frame"
        lines.append(
            f"(frame): a rigid motion of the table frame, not separable from the tracker placement; {how}: "
            f"{'; '.join(cal.frame_confounded)}"
        )
    lines.append("")
    for label, st in (("identification", cal.residuals), ("test", cal.test)):
        if st is None:
            continue
        lines.append(f"{label} set ({st.n_points} points)  mean residual  % decrease  max residual  % decrease")
        lines.append(f"  nominal               {st.nominal_mean:10.4f} mm         N/A  {st.nominal_max:9.4f} mm         N/A")
        lines.append(
            f"  model                 {st.model_mean:10.4f} mm  {st.decrease_mean_pct:9.2f}%  {st.model_max:9.4f} mm  {st.decrease_max_pct:9.2f}%"
        )
    return "\n".join(lines)


@app.command("identify")
def identify_cmd(
    machine_file: Path = MACHINE_ARG,
    observations: list[Path] = typer.Argument(
        ..., help="Observations CSV(s): tracker (joint columns and x, y, z, mm) or, with a '# kind = sphere|rtest' line, "
        "probed-sphere or R-test readings; several files of any kinds are identified together."
    ),
    test: Optional[Path] = typer.Option(None, "--test", help="Test observations CSV (Table 3.5)."),
    method: str = typer.Option("joint", "--method", help="joint (frame correction estimated with the groups) or two-step (dissertation)."),
    test_frame: str = typer.Option("same", "--test-frame", help="same (test set measured in the same tracker set-up) or refit."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the calibration JSON (input of predict and compensate)."),
    residuals: Optional[Path] = typer.Option(
        None, "--residuals", help="Write per-point residuals (CSV: set, joints, nominal and model residual vectors and lengths, mm)."
    ),
    unknowns: Optional[str] = typer.Option(
        None, "--unknowns", help="Mixed observations: groups (default with a tracker file) or location (rotary-axis location errors; default otherwise)."
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Identify the error model's groups from tracker observations (Sec. 3.1.5, Tables 3.2-3.5), or from any mix
    of tracker, probed-sphere and R-test files."""
    from ..machine import identify, load_machine, read_observations

    _outputs(out, residuals)
    if method not in ("joint", "two-step"):
        raise InvalidInputError(f"--method must be joint or two-step, got {method!r}")
    m = load_machine(machine_file)
    from ..machine.instruments import read_instrument

    kinds = [read_instrument(p, m) for p in observations]
    if len(kinds) > 1 or kinds[0].kind != "tracker" or unknowns is not None:
        from .machine_instruments import identify_mixed_cmd

        return identify_mixed_cmd(m, kinds, unknowns, out, test, residuals, as_json)
    observations = observations[0]
    with _warnings_to_stderr():
        obs = read_observations(observations, m)
        tobs = read_observations(test, m) if test is not None else None
        cal = identify(m, obs, test=tobs, method=method, test_frame=test_frame)
    if out is not None:
        cal.save(out)
    if residuals is not None:
        _write_residuals(residuals, m, cal, obs, tobs)
    emit(cal, as_json, _identify_text)


def _write_residuals(path: Path, m, cal, obs, tobs) -> None:
    from ..machine.observations import write_csv

    pr = cal.point_residuals
    blocks = [(0.0, obs.commands, pr["nominal"], pr["model"])]
    if tobs is not None:
        blocks.append((1.0, tobs.commands, pr["test_nominal"], pr["test_model"]))
    rows = [
        np.hstack([np.full((len(c), 1), k), c, a, np.linalg.norm(a, axis=1)[:, None], b, np.linalg.norm(b, axis=1)[:, None]])
        for k, c, a, b in blocks
    ]
    header = ["test"] + m.joint_names + ["nx", "ny", "nz", "nominal", "mx", "my", "mz", "model"]
    write_csv(path, header, np.vstack(rows))


@app.command("predict")
def predict_cmd(
    machine_file: Path = MACHINE_ARG,
    calibration: Path = typer.Argument(..., help="Calibration JSON from identify --out (with --temperatures: a track --json result)."),
    commands: Path = typer.Argument(..., help="Commands CSV (joint columns)."),
    out: Path = typer.Option(
        ..., "--out", help="Errors CSV to write: joint columns, ex, ey, ez and their standard uncertainties ux, uy, uz (mm, table frame)."
    ),
    temperatures: Optional[Path] = typer.Option(
        None, "--temperatures", help="Temperatures CSV (the model's temp_* columns; rows averaged): predict from the tracking run's temperature model."
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Predict the volumetric error at given commands (Eq. 3.9), or from a cycle's temperatures alone."""
    from ..machine import load_calibration, load_machine, predict, predict_uncertainty, read_commands
    from ..machine.observations import write_csv

    _outputs(out)
    m = load_machine(machine_file)
    cmds = read_commands(commands, m)
    if temperatures is not None:
        from ..machine.thermal import load_temperature_model, predict_from_temperatures, read_temperatures

        model = load_temperature_model(calibration)
        temps = read_temperatures(temperatures, model)
        err = predict_from_temperatures(m, model, cmds, temps)
        write_csv(out, m.joint_names + ["ex", "ey", "ez"], np.hstack([cmds, err]))
    else:
        cal = load_calibration(calibration)
        with _warnings_to_stderr():
            err = predict(m, cal, cmds)
        u = predict_uncertainty(m, cal, cmds)
        write_csv(out, m.joint_names + ["ex", "ey", "ez", "ux", "uy", "uz"], np.hstack([cmds, err, u]))
    length = np.linalg.norm(err, axis=1) if len(err) else np.zeros(1)
    result = {"points": int(len(err)), "out": str(out), "mean": float(length.mean()), "max": float(length.max())}
    if temperatures is None and len(err):
        # standard uncertainty (k = 1) of each component, GUM 5.1.2 through Eq. 3.14: the CSV's ux, uy, uz
        result["u"] = {"k": 1, "max": dict(zip("xyz", map(float, u.max(axis=0)))),
                       "rms": dict(zip("xyz", map(float, np.sqrt((u**2).mean(axis=0)))))}
    if temperatures is not None:
        result["temperatures"] = dict(zip(model.sensors, map(float, temps)))
    emit(result, as_json, lambda r: f"wrote {r['points']} predicted errors to {r['out']} (mean {r['mean']:.4f} mm, max {r['max']:.4f} mm)")


@app.command("compensate")
def compensate_cmd(
    machine_file: Path = MACHINE_ARG,
    calibration: Path = typer.Argument(..., help="Calibration JSON from identify --out."),
    commands: Path = typer.Argument(..., help="Commands CSV (joint columns)."),
    out: Path = typer.Option(..., "--out", help="Corrected commands CSV to write."),
    axes: Optional[str] = typer.Option(None, "--axes", help="Comma-separated joints that compensate (default: all prismatic)."),
    as_json: bool = JSON_OPTION,
) -> None:
    """Correct commands so that the predicted actual target position is the nominal one."""
    from ..machine import compensate, load_calibration, load_machine, read_commands
    from ..machine.observations import write_csv

    _outputs(out)
    m = load_machine(machine_file)
    cal = load_calibration(calibration)
    cmds = read_commands(commands, m)
    ax = [a.strip() for a in axes.split(",") if a.strip()] if axes else None
    with _warnings_to_stderr():
        corrected, remaining = compensate(m, cal, cmds, axes=ax)
    write_csv(out, m.joint_names, corrected)
    rem = np.linalg.norm(remaining, axis=1) if len(remaining) else np.zeros(1)
    result = {"points": int(len(corrected)), "out": str(out), "remaining_max": float(rem.max())}
    emit(result, as_json, lambda r: f"wrote {r['points']} corrected commands to {r['out']} (remaining predicted error <= {r['remaining_max']:.2e} mm)")
