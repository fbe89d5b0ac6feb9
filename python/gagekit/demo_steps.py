"""The steps of ``gagekit demo`` (see :mod:`gagekit.demo`)."""

from __future__ import annotations

from ._util import to_jsonable
from .report.text import table


def machine_step(ctx) -> tuple[dict, str]:
    """Simulated laser-tracker calibration of the example 5-axis machine (Ch. 3):
    290 measured points, identified by the joint and the two-step method, checked
    on a 50-point test set."""
    from . import machine as mc
    from .report.machine import add_calibrations, residual_table

    m = mc.load_machine(mc.example_machine_path())
    n_cal, n_test = (60, 20) if ctx.quick else (290, 50)
    truth = mc.Truth.random(m, seed=1)
    cal = mc.simulate(m, truth, m.sample_commands(n_cal, seed=1), seed=11)
    test = mc.simulate(m, truth, m.sample_commands(n_test, seed=2), seed=12)
    cals = [mc.identify(m, cal, test=test, method=meth) for meth in ("joint", "two-step")]
    ctx.report.text(
        f"Machine {m.name}: {len(m.parameter_names)} error parameters, rank {cals[0].rank}. "
        f"Simulated tracker: {n_cal} calibration points and {n_test} test points, placed at an arbitrary pose, "
        f"noise sigma {1e3 * mc.TRACKER_SIGMA:.1f} um."
    )
    add_calibrations(ctx.report, cals)
    headers, rows = residual_table(cals)
    data = {"machine": m.name, "calibrations": {c.method: c.to_dict() for c in cals}}
    return to_jsonable(data), table(headers, rows)


def cloud_step(ctx) -> tuple[dict, str]:
    """Point-set manipulation (Sec. 5.4.1): read the bundled scan of a casting, cut its
    locator regions (scanner frame) and keep the vertices of each region's convex hull."""
    import time

    from .cloud import cut_and_filter, read_points, regions_from_tables
    from ._util import load_toml
    from .samples import data_path

    t0 = time.perf_counter()
    pts = read_points(data_path("casting_ok.ply"))
    t_read = time.perf_counter() - t0
    spec = load_toml(data_path("casting_ok.toml"))
    boxes = regions_from_tables([r for r in spec["region"] if r.get("frame") == "scanner"], "casting_ok.toml")
    t0 = time.perf_counter()
    cut = cut_and_filter(pts, boxes)
    t_cut = time.perf_counter() - t0
    rows = [[r["name"], r["points"], r["hull_vertices"], f"{r['reduction']:.0f}x"] for r in cut.to_dict()["regions"]]
    headers = ["region", "points", "hull vertices", "reduction"]
    ctx.report.text(f"casting_ok.ply: {len(pts)} points read in {1e3 * t_read:.0f} ms; "
                    f"{len(boxes)} locator regions cut and hull-filtered in {1e3 * t_cut:.0f} ms (cf. Table 5.2).")
    ctx.report.table(headers, rows, "Points per region and the hull vertices kept for the LP (Eq. 5.21)")
    data = {**cut.to_dict(), "read_seconds": t_read, "cut_and_filter_seconds": t_cut}
    return data, f"{len(pts)} points, read in {t_read:.2f} s, cut + hull in {1e3 * t_cut:.0f} ms\n" + table(headers, rows)


def observer_step(ctx) -> tuple[dict, str]:
    """An 80-point plan with the default criterion (I, no zones: it predicted best in the
    simulation study, see README) next to the dissertation's K-optimal plan with the
    dissertation-8 zones (Sec. 4.2), compared with quasi-random plans by the figures of
    Tables 4.2-4.3 and by a simulation study."""
    from . import machine as mc
    from .machine.observer import DEFAULT_CRITERION, DEFAULT_ZONES, design_observer, evaluate_plan

    m = mc.load_machine(mc.example_machine_path())
    n = 40 if ctx.quick else 80
    kw = dict(candidates=1000 if ctx.quick else 3000, starts=1, seed=0)
    study = dict(seeds=3 if ctx.quick else 8, test_points=300 if ctx.quick else 1000, seed=0)
    plan = design_observer(m, n, DEFAULT_CRITERION, zones=DEFAULT_ZONES, **kw)
    k_plan = design_observer(m, n, "K", zones="dissertation-8", **kw)
    ev = evaluate_plan(m, plan.commands, **study)
    k_ev = evaluate_plan(m, k_plan.commands, compare=False, **study)  # same machines and test points
    ctx.plan = plan

    def label(p) -> str:
        return f"{p.criterion}-optimal, " + ("no zones" if p.zones == "none" else f"{p.zones} zones")

    headers = ["plan", "points", "tr((M^T M)^-1)", "log det((M^T M)^-1)", "kappa(M)"]
    rows = [[label(p), n, p.figures["trace"], p.figures["log_det"], p.figures["condition_number"]] for p in (plan, k_plan)]
    q = plan.quasi_random
    for key in ("same_size", "full_290"):
        rows.append(["quasi-random", q[key]["points"], q[key]["trace"], q[key]["log_det"], q[key]["condition_number"]])
    ctx.report.table(headers, rows, "Design figures with columns scaled by L^p (Tables 4.2-4.3)")
    ev_rows = [[label(plan) if key == "plan" else p["label"], p["points"], p["rms_um"], p["rms_um_std"]] for key, p in ev.plans.items()]
    k = k_ev.plans["plan"]
    ev_rows.insert(1, [label(k_plan), k["points"], k["rms_um"], k["rms_um_std"]])
    ctx.report.table(["plan", "points", "RMS prediction error (um)", "std (um)"], ev_rows,
                     f"Simulation study: {ev.seeds} random machines, identification from each plan, "
                     "volumetric error predicted over the workspace. The default plan (first row) is the one "
                     "the next step measures.")
    _plan_figure(ctx, m, plan)
    data = {"plan": plan.to_dict(), "evaluation": ev, "dissertation_plan": k_plan.to_dict(), "dissertation_evaluation": k_ev}
    text = table(headers, [[r[0], r[1], f"{r[2]:.4g}", f"{r[3]:.4g}", f"{r[4]:.4g}"] for r in rows])
    text += "\n\n" + table(["plan", "points", "RMS um", "std um"], [[a, b, f"{c:.2f}", f"{d:.2f}"] for a, b, c, d in ev_rows])
    return to_jsonable(data), text


def _plan_figure(ctx, m, plan) -> None:
    from .report.machine import plan_figure

    ctx.report.figure(plan_figure(m, plan), "observer-plan", "The plan in the workspace (cf. Fig. 4.2)")


def tracking_step(ctx) -> tuple[dict, str]:
    """Eight simulated thermal cycles (heating, then cooling; ten temperature sensors, three of
    which drive the drift) measured with the plan, tracked cycle by cycle against static and
    drift-only models (Tables 4.4-4.6, Fig. 4.8) and a ridge temperature model."""
    import numpy as np

    from . import machine as mc
    from .machine.observations import write_csv
    from .machine.tracking import read_cycles, simulate_cycles, track
    from .report.machine import add_tracking, tracking_table

    m = mc.load_machine(mc.example_machine_path())
    plan = getattr(ctx, "plan", None)
    cmds = plan.commands if plan is not None else m.sample_commands(80, seed=3)
    blocks, info = simulate_cycles(m, mc.Truth.random(m, seed=5), cmds, cycles=8, seed=5)
    path = ctx.out / "cycles.csv"
    write_csv(path, info["header"], np.concatenate(blocks))
    res = track(m, read_cycles(path, m))
    ctx.report.text(f"{len(cmds)} points measured in each of 8 cycles; ten temperature sensors, of which the "
                    f"spindle, W and Y sensors drive the simulated drift of the W and Y axes and four only wander.")
    add_tracking(ctx.report, res)
    headers, rows = tracking_table(res)
    text = table(headers[:5], [[r[0], f"{r[1]:.1f}", f"{r[2]:.1f}", f"{r[3]:.1f}", f"{r[4]:.1f}"] for r in rows])
    return to_jsonable(res.to_dict()), text


def castings_step(ctx) -> tuple[dict, str]:
    """Virtual gages (Ch. 5) on the two bundled castings: 3-2-1 alignment, regions, hull
    filter, the LP of Eq. 5.11 with slacks; pictures of each region before and after T*."""
    from .cloud import read_points
    from .samples import data_path
    from .gage import check_gages
    from .report.gage import add_to_report

    data, lines = {}, []
    for name in ("casting_ok", "casting_short"):
        res = check_gages(read_points(data_path(f"{name}.ply")), data_path(f"{name}.toml"))
        add_to_report(ctx.report, res, name)
        data[name] = res.to_dict()
        worst = min(g.allowance_after for g in res.gages)
        short = [g.name for g in res.gages if g.slack > 0]
        lines.append([name, res.status, f"{res.objective:.4f}", f"{worst:.4f}", ", ".join(short) or "-",
                      "; ".join(" + ".join(g) for g in res.infeasible_groups) or "-"])
    return to_jsonable(data), table(["casting", "status", "objective", "min allowance after (mm)", "short of material", "infeasible groups"], lines)


def cylinders_step(ctx) -> tuple[dict, str]:
    """The dissertation's cylinder data sets 1 and 3 (Sec. 6.4) by every criterion,
    compared with the values it reports (Tables 6.2-6.4)."""
    from ._util import load_toml
    from .cloud import read_points
    from .samples import data_path
    from .form import fit_cylinder
    from .report.form import add_cylinder_fits

    expected = load_toml(data_path("cylinders/expected.toml"))
    headers = ["set", "criterion", "radius / width (mm)", "reported (mm)", "theta", "phi", "seconds"]
    rows, data = [], {}
    import time

    for s in ("set1", "set3"):
        pts = read_points(data_path(f"cylinders/{s}.csv"))
        fits = []
        for crit, key, field in (("least-squares", None, "radius"), ("min-circumscribed", "min_circumscribed", "radius"),
                                 ("max-inscribed", "max_inscribed", "radius"), ("minimum-zone", "minimum_zone", "width")):
            t0 = time.perf_counter()
            fit = fit_cylinder(pts, crit, seed=0)
            dt = time.perf_counter() - t0
            fits.append(fit)
            value = fit.form_error if field == "width" else fit.radius
            reported = repr(expected[s][key][field]) if key else "-"
            rows.append([s, crit, f"{value:.10f}", reported, f"{fit.theta:.6f}", f"{fit.phi:.6f}", f"{dt:.3f}"])
        data[s] = [f.to_dict() for f in fits]
        add_cylinder_fits(ctx.report, s, pts, fits)
    ctx.report.table(headers, rows, "Cylinder fits; reported values are the dissertation's (bounds, not targets)")
    return to_jsonable(data), table(headers, rows)


def inspection_step(ctx) -> tuple[dict, str]:
    """GD&T inspection (ISO 1101 / ISO 5459) of the bundled bracket: 20 callouts with
    known deviations, each measured value next to the one that follows from the
    construction (make_bracket.py)."""
    import importlib.util

    from .cloud import read_points
    from .samples import data_path
    from .inspect import inspect, load_part_spec
    from .report.inspect import add_inspection, callout_rows

    gen_spec = importlib.util.spec_from_file_location("make_bracket", data_path("make_bracket.py"))
    gen = importlib.util.module_from_spec(gen_spec)
    gen_spec.loader.exec_module(gen)
    res = inspect(read_points(data_path("bracket.ply")), load_part_spec(data_path("bracket.toml")))
    add_inspection(ctx.report, res, "Inspection of the bracket")
    rows, worst = [], 0.0
    for r, t in zip(callout_rows(res), res.tolerances):
        key = f"{t.characteristic} of {t.feature}" + (" to " + "|".join(t.datums) if t.feature == "C" else "")
        want = gen.EXPECTED[key]
        worst = max(worst, abs(t.measured - want))
        rows.append([r[0], r[1], r[2], r[3], f"{t.tolerance:.4f}", f"{t.measured:.6f}", f"{want:.6f}", r[8]])
    ctx.report.text(f"Largest difference between a measured value and its analytic value: {worst:.1e} mm.")
    data = {**res.to_dict(), "expected": gen.EXPECTED, "max_abs_difference_from_expected": worst}
    text = table(["#", "feature", "characteristic", "datums", "tolerance", "measured", "expected", "result"], rows)
    return to_jsonable(data), text + f"\n{res.status}; largest |measured - expected| = {worst:.1e} mm"


def cad_step(ctx) -> tuple[dict, str]:
    """The bracket's scan against its STEP model (ISO 1101 profile of a surface): signed
    deviations, per-face statistics and the deviation map. Without gagekit[cad]
    (OpenCASCADE) the model is the bundled tessellation of the same STEP file
    (``bracket.obj``, chord error within 0.5 um, one named group per STEP face), and the
    report says so."""
    from .cad import compare, read_cad
    from .cad.step import MISSING, ocp_available
    from .cloud import read_points
    from .samples import data_path
    from .report.compare import add_compare

    exact = ocp_available()
    model = read_cad(data_path("bracket.step" if exact else "bracket.obj"))
    res = compare(read_points(data_path("bracket.ply")), model)
    if not exact:
        ctx.report.section("Scan against CAD").text(
            f"OpenCASCADE is not installed ({MISSING}): the model is bracket.obj, the bundled tessellation of "
            "bracket.step (chord error within 0.5 um, its 14 named faces); distances are to its triangles.")
    add_compare(ctx.report, res)
    d = res.to_dict()
    rows = [[f["id"], f["name"], f["kind"], f["n"]] + ([f"{f['min']:+.4f}", f"{f['max']:+.4f}", f"{f['rms']:.4f}"] if f["n"] else ["-"] * 3)
            for f in d["faces"]]
    s = d["deviations"]
    text = table(["face", "name", "surface", "n", "min", "max", "rms"], rows)
    return to_jsonable(d), text + f"\nprofile (2 max |d|) {s['profile']:.4f} mm over {d['n_used']} points"


STEPS = [
    ("cloud", "Point cloud: regions and convex-hull filter (Sec. 5.4.1)", cloud_step),
    ("machine", "Machine calibration (Ch. 3)", machine_step),
    ("observer", "Optimal error observer (Ch. 4)", observer_step),
    ("tracking", "Thermal error tracking (Sec. 4.3.3)", tracking_step),
    ("castings", "Virtual gages on two castings (Ch. 5)", castings_step),
    ("cylinders", "Form of cylinders (Ch. 6)", cylinders_step),
    ("inspection", "GD&T inspection of a bracket (ISO 1101, ISO 5459)", inspection_step),
    ("cad", "The bracket's scan against its STEP model (deviation map)", cad_step),
]
