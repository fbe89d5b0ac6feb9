"""Thermal mode of the tracker simulator: repeated cycles of one plan with drifting axes
(Sec. 4.3.3, Figs. 4.4, 4.7, 4.8)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InvalidInputError
from ..model import Machine
from ..simulate import TRACKER_SIGMA, Truth, simulate
from .cycles import XYZ as _XYZ

__all__ = ["HEAT_PROFILE", "simulate_cycles"]

#: Thermal state of the simulated cycles: heating for four cycles, then cooling (Fig. 4.4).
HEAT_PROFILE = (0.0, 1.0, 2.0, 3.0, 4.0, 2.6)


def simulate_cycles(
    machine: Machine,
    truth: Truth,
    commands: Any,
    cycles: int = 6,
    noise: float = TRACKER_SIGMA,
    drift_scale: float = 1.0,
    seed: int = 0,
) -> tuple[list[np.ndarray], dict]:
    """Thermal mode of the simulator: the W- and Y-axis terms drift with a heating and
    cooling profile (Fig. 4.8: only they changed markedly), temperatures follow (W +4.5 C,
    Y +3 C at the end of heating, X and Z under 2 C, Fig. 4.7).

    Returns the rows (cycle, joints, x, y, z, time, temp_X..temp_W) per cycle and the header.
    """
    if cycles < 1:
        raise InvalidInputError("--cycles must be at least 1")
    names = machine.parameter_names
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7468]))
    drift = np.zeros(len(names))
    per_step = {"W.delta": 2e-5, "W.dbeta": 1.2e-8, "W.dgamma": 1e-8, "Y.delta": 1.2e-5, "Y.dalpha": 8e-9, "Y.dgamma": 6e-9}
    for k, v in per_step.items():
        if k in names:
            drift[names.index(k)] = v * drift_scale * (1 if rng.random() < 0.5 else -1)
    profile = [HEAT_PROFILE[min(j, len(HEAT_PROFILE) - 1)] if j < len(HEAT_PROFILE) else HEAT_PROFILE[-1] * 0.8 ** (j - 5)
               for j in range(cycles)]
    rise = {"X": 0.35, "Z": 0.4, "Y": 0.75, "W": 1.12}
    joints = machine.joint_names
    sensors = [f"temp_{j}" for j in joints if j in rise]
    out = []
    cmds = machine.commands_array(commands)
    for j in range(cycles):
        t = Truth(truth.machine, truth.parameter_names, truth.parameters + profile[j] * drift, truth.frame)
        obs = simulate(machine, t, cmds, noise=noise, seed=seed + 31 * j)
        temps = [20.0 + rise[s[5:]] * profile[j] + rng.normal(scale=0.05) for s in sensors]
        block = np.column_stack([np.full(len(cmds), j + 1), cmds, obs.measured, np.full(len(cmds), 60.0 * j),
                                 np.tile(temps, (len(cmds), 1))])
        out.append(block)
    header = ["cycle", *joints, *_XYZ, "time", *sensors]
    return out, {"header": header, "drift": {k: float(drift[names.index(k)]) for k in per_step if k in names}}
