"""The steps of ``gagekit demo`` (see :mod:`gagekit.demo`)."""

from __future__ import annotations

from ._util import to_jsonable
from .cli._common import table


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


STEPS = [
    ("machine", "Machine calibration (Ch. 3)", machine_step),
]
