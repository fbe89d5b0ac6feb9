"""Simulated observations of the example machine by instruments other than the laser tracker,
the samples of ``docs/instruments.md`` (``gagekit machine ballbar``, ``machine identify``,
``machine track``). Every file comes from the kinematic model of the example machine
(``gagekit data path machine``) with the known errors below and a fixed seed. Lengths mm.

``ballbar_xy.csv`` (``# kind = ballbar``): a ballbar run (ISO 230-4), plane XY, radius
150 mm, feed 1000 mm/min, circle centre B=0 X=0 Z=1500 Y=1400 W=-500, 360 readings per
direction (ccw, then cw); truth: T3.alpha 25 urad (XY squareness), X.delta 30 um/m,
Y.delta -10 um/m (scale), backlash X 4 um and Y 6 um, Y lags 1 ms, noise 0.1 um. It is both a
`machine ballbar` run and a `machine identify` observation file (plane, radius, at lines).
``sphere_b.csv`` (``# kind = sphere``): the probe cycle of one sphere at (150, 400, 250) on the
table at 12 B positions 0..330 deg, W=-500; the B axis displaced by EXOB 15 um, EZOB -10 um,
EAOB 20 urad, ECOB -30 urad (ISO 230-7); noise 1 um on the found X, Z, Y.
``rtest_b.csv`` (``# kind = rtest``): the R-test (ISO 10791-6) of the same B axis errors:
the nominal ball on the nest at 12 B positions, three sensors with directions (1 0 0),
(0 0.6 0.8), (0 -0.8 0.6) read the actual ball; the sensors' zero is 12.3 um off; noise
0.5 um.
``sphere_cycles.csv`` (``# kind = sphere``, ``machine track``): four probing cycles an hour
apart of the sphere above; between cycles EXOB drifts +3 um and EAOB +4 urad per hour, the
spindle warms 1 degC per hour (``temp_spindle``); noise 0.5 um.

Run ``python -m gagekit.data.make_instrument_samples`` to rewrite the bundled files.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20260230

SPHERE = np.array([150.0, 400.0, 250.0])  # table frame: 400 mm above the B axis origin
POSITIONS = np.arange(12) * 30.0  # deg
AT = {"W": -500.0}
LOCATION = {"EXOB": 0.015, "EZOB": -0.010, "EAOB": 20e-6, "ECOB": -30e-6}
BALLBAR_AT = [0.0, 0.0, 1500.0, 1400.0, -500.0]  # B X Z Y W
BALLBAR_ERRORS = {"T3.alpha": 25e-6, "X.delta": 30e-6, "Y.delta": -10e-6}
RTEST_DIRECTIONS = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [0.0, -0.8, 0.6]])


def _machine():
    from gagekit.machine import load_machine
    from gagekit.machine.model import example_machine_path

    return load_machine(example_machine_path())


def _write(path: Path, meta: list[str], header: list[str], rows) -> None:
    lines = [f"# {m}" for m in meta] + [",".join(header)]
    lines += [",".join(v if isinstance(v, str) else str(v) if isinstance(v, int) else f"{v:.6f}" for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def ballbar_rows(machine, seed: int) -> list:
    from gagekit.machine.simulate_instruments import simulate_ballbar

    params = np.zeros(len(machine.parameter_names))
    for k, v in BALLBAR_ERRORS.items():
        params[machine.parameter_names.index(k)] = v
    run = simulate_ballbar(machine, params, "XY", 150.0, np.array(BALLBAR_AT), points=360, backlash={"X": 0.004, "Y": 0.006},
                           lag={"Y": 0.001}, feed=1000.0, noise_um=0.1, seed=seed)
    return [[float(a), float(d), "ccw" if s > 0 else "cw"] for a, d, s in zip(run.angles_deg, run.deviations_um, run.directions)]


def sphere_commands(machine, location: dict, noise_um: float, seed: int) -> np.ndarray:
    from gagekit.machine.simulate_instruments import simulate_sphere

    return simulate_sphere(machine, "B", POSITIONS, SPHERE, AT, location, noise_um=noise_um, seed=seed)


def rtest_rows(machine, rng: np.random.Generator) -> list:
    """The controller puts the nominal ball on the nest while B turns; the actual ball follows
    the displaced B axis: p = R_true(B) (p_base - e) + e (geometry, not the error model)."""
    from gagekit._rotation import rotation_from_vector

    c = sphere_commands(machine, {}, 0.0, 0)
    e = np.array([LOCATION["EXOB"], 0.0, LOCATION["EZOB"]])
    axis = rotation_from_vector(np.array([LOCATION["EAOB"], 0.0, LOCATION["ECOB"]])) @ np.array([0.0, 1.0, 0.0])
    rows = []
    for row in c:
        base = row.copy()
        base[0] = 0.0
        p_base = machine.nominal(base[None, :])[0]
        p = rotation_from_vector(axis * np.radians(row[0])) @ (p_base - e) + e
        d = RTEST_DIRECTIONS @ (p - SPHERE) + 0.0123 + rng.normal(0.0, 0.0005, 3)
        rows.append([*row, *d])
    return rows


def main() -> None:
    m = _machine()
    joints = m.joint_names
    rng = np.random.default_rng(SEED)
    at = ",".join(f"{j}={v:g}" for j, v in zip(joints, BALLBAR_AT))
    _write(HERE / "ballbar_xy.csv", ["simulated ballbar run of the example machine (make_instrument_samples.py)", "kind = ballbar",
                                     "plane = XY", "radius = 150", f"at = {at}", "sigma_um = 0.1"],
           ["angle_deg", "deviation_um", "direction"], ballbar_rows(m, SEED))
    _write(HERE / "sphere_b.csv", ["kind = sphere", "sigma_um = 1.0"], [*joints, "sphere"],
           [[*r, 0] for r in sphere_commands(m, LOCATION, 1.0, SEED + 1)])
    dirs = "; ".join(" ".join(f"{v:g}" for v in d) for d in RTEST_DIRECTIONS)
    _write(HERE / "rtest_b.csv", ["kind = rtest", f"directions = {dirs}", "sigma_um = 0.5"], [*joints, "d1", "d2", "d3"],
           rtest_rows(m, rng))
    rows = []
    for k in range(4):
        loc = {**LOCATION, "EXOB": LOCATION["EXOB"] + 0.003 * k, "EAOB": LOCATION["EAOB"] + 4e-6 * k}
        rows += [[k + 1, *r, float(k), 20.0 + k] for r in sphere_commands(m, loc, 0.5, SEED + 10 + k)]
    _write(HERE / "sphere_cycles.csv", ["kind = sphere"], ["cycle", *joints, "time", "temp_spindle"], rows)


if __name__ == "__main__":
    main()
