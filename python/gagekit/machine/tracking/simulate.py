"""Thermal mode of the tracker simulator: repeated cycles of one plan on a machine that heats
and cools (Sec. 4.3.3, Figs. 4.4, 4.7, 4.8), with temperatures that drive the drift.

A lumped thermal state h follows the heat input with a first-order lag (time constant tau,
heating in the first two thirds of the cycles, then cooling, Fig. 4.4). Each sensor reads
20 C + gain * h + noise: the sensors on the spindle housing, the W and Y axes respond
strongly, X, Z and the bed weakly (W +4.5 C, Y +3 C at the end of heating, X and Z under 2 C,
Fig. 4.7). The error parameters drift in proportion to the temperature rises of the sensors
that matter (spindle, W, Y: the W- and Y-axis terms, which alone changed markedly in Fig.
4.8), plus a small process noise; the remaining sensors (air, cabinet, coolant, floor) only
wander (random walks) and carry no information about the drift.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InvalidInputError
from ..model import Machine
from ..simulate import TRACKER_SIGMA, Truth, simulate
from .cycles import XYZ as _XYZ

__all__ = ["HEAT_PROFILE", "SENSORS", "simulate_cycles"]

#: Heat input per cycle of the default six-cycle experiment: four heating intervals, then cooling (Fig. 4.4).
HEAT_PROFILE = (0.0, 1.0, 2.0, 3.0, 4.0, 2.6)

#: Sensor -> temperature gain (C per unit thermal state) and noise; the first three drive the drift.
SENSORS = {
    "temp_spindle": 1.4, "temp_W": 1.12, "temp_Y": 0.75,
    "temp_X": 0.35, "temp_Z": 0.4, "temp_bed": 0.2,
    "temp_air": 0.0, "temp_cabinet": 0.0, "temp_coolant": 0.0, "temp_floor": 0.0,
}
_DRIVERS = ("temp_spindle", "temp_W", "temp_Y")
#: Drift per C of the driving sensors' mean rise (rates of Fig. 4.8 divided by the rise per step).
_PER_DEGREE = {"W.delta": 1.8e-5, "W.dbeta": 1.1e-8, "W.dgamma": 9e-9, "Y.delta": 1.1e-5, "Y.dalpha": 7e-9, "Y.dgamma": 5.5e-9}
_WANDER = 0.3  # C per cycle, random walk of the sensors that do not matter
_SENSOR_NOISE = 0.03  # C
_PROCESS_NOISE = 0.03  # fraction of the drift per parameter, per cycle


def thermal_state(cycles: int) -> np.ndarray:
    """Thermal state per cycle: the default profile for up to six cycles, else a first-order
    response to heating during the first two thirds of the cycles (tau = 2 cycles)."""
    if cycles <= len(HEAT_PROFILE):
        return np.array(HEAT_PROFILE[:cycles], dtype=float)
    h, out = 0.0, []
    heat = int(round(2 * cycles / 3))
    a = 1.0 - np.exp(-1.0 / 2.0)
    for j in range(cycles):
        out.append(h)
        h += ((6.0 if j < heat else 0.0) - h) * a
    return np.array(out)


def simulate_cycles(
    machine: Machine,
    truth: Truth,
    commands: Any,
    cycles: int = 6,
    noise: float = TRACKER_SIGMA,
    drift_scale: float = 1.0,
    seed: int = 0,
) -> tuple[list[np.ndarray], dict]:
    """Simulate ``cycles`` measurements of the plan ``commands`` on a heating and cooling
    machine (module docstring). Returns the rows (cycle, joints, x, y, z, time, temp_*) per
    cycle and {"header", "drift" (per C of the driving sensors), "sensors", "drivers"}."""
    if cycles < 1:
        raise InvalidInputError("--cycles must be at least 1")
    names = machine.parameter_names
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7468]))
    per_degree = np.zeros(len(names))
    for k, v in _PER_DEGREE.items():
        if k in names:
            per_degree[names.index(k)] = v * drift_scale * (1 if rng.random() < 0.5 else -1)
    h = thermal_state(cycles)
    sensors = list(SENSORS)
    wander = {s: np.cumsum(rng.normal(scale=_WANDER, size=cycles)) for s in sensors if SENSORS[s] == 0.0}
    temps = np.array([[20.0 + SENSORS[s] * h[j] + wander.get(s, np.zeros(cycles))[j] + rng.normal(scale=_SENSOR_NOISE)
                       for s in sensors] for j in range(cycles)])
    rise = temps[:, [sensors.index(s) for s in _DRIVERS]].mean(axis=1) - temps[0, [sensors.index(s) for s in _DRIVERS]].mean()
    cmds = machine.commands_array(commands)
    out = []
    for j in range(cycles):
        drift = per_degree * rise[j] * (1.0 + _PROCESS_NOISE * rng.normal(size=len(names)))
        t = Truth(truth.machine, truth.parameter_names, truth.parameters + drift, truth.frame)
        obs = simulate(machine, t, cmds, noise=noise, seed=seed + 31 * j)
        block = np.column_stack([np.full(len(cmds), j + 1), cmds, obs.measured, np.full(len(cmds), 60.0 * j),
                                 np.tile(temps[j], (len(cmds), 1))])
        out.append(block)
    header = ["cycle", *machine.joint_names, *_XYZ, "time", *sensors]
    drift_info = {k: float(per_degree[names.index(k)]) for k in _PER_DEGREE if k in names}
    return out, {"header": header, "drift": drift_info, "sensors": sensors, "drivers": list(_DRIVERS)}
