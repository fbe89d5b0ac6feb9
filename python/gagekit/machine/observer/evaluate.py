"""The simulated worth of an observer plan (issue 7): RMS prediction error of the volumetric
error over the workspace after identification from the plan."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from ...errors import InvalidInputError
from ..frame import frame_columns
from ..identify import identify
from ..predict import predict
from ..model import Machine, ModelStructure
from ..simulate import TRACKER_SIGMA, Truth, simulate
from .design import FULL_SET

__all__ = ["PlanEvaluation", "prediction_rms", "evaluate_plan"]


# ---------------------------------------------------------------------------------- evaluation

@dataclass(frozen=True, eq=False)
class PlanEvaluation:
    """RMS prediction error of the volumetric error over the workspace (um), per plan."""

    plans: dict
    seeds: int
    noise: float
    test_points: int

    def to_dict(self) -> dict:
        return {"plans": self.plans, "seeds": self.seeds, "noise_mm": self.noise, "test_points": self.test_points}


def prediction_rms(machine: Machine, commands: np.ndarray, truths: Sequence[Truth], noise: float, test: np.ndarray,
                   seed: int = 0, structure: Optional[ModelStructure] = None) -> np.ndarray:
    """For each truth: identify from noisy simulated readings at ``commands`` and return the
    RMS (um) over ``test`` of predicted minus true volumetric error, after removing the best
    rigid motion of the table frame (which part set-up takes up and the tracker cannot see)."""
    st = structure if structure is not None else machine.structure()
    p_nom = machine.nominal(test)
    frame = frame_columns(p_nom)
    out = []
    for k, truth in enumerate(truths):
        obs = simulate(machine, truth, commands, noise=noise, seed=seed + 7919 * (k + 1))
        cal = identify(machine, obs, structure=st)
        diff = (predict(machine, cal, test, structure=st) - (machine.positions(test, truth.parameters) - p_nom)).reshape(-1)
        coef, *_ = np.linalg.lstsq(frame, diff, rcond=None)
        res = (diff - frame @ coef).reshape(-1, 3)
        out.append(1000.0 * math.sqrt(float((res**2).sum(axis=1).mean())))
    return np.array(out)


def evaluate_plan(
    machine: Machine,
    plan: Any,
    seeds: int = 20,
    noise: float = TRACKER_SIGMA,
    test_points: int = 2000,
    seed: int = 0,
    compare: bool = True,
) -> PlanEvaluation:
    """Simulation study (issue 7): random machines (Table 3.3 magnitudes), noisy tracker
    readings at the plan's commands, identification, and the RMS prediction error of the
    volumetric error over ``test_points`` quasi-random commands; with ``compare``, the same
    for quasi-random plans of the same size and of 290 points."""
    cmds = machine.commands_array(plan, "plan")
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise InvalidInputError(f"--seeds must be a positive integer, got {seeds!r}")
    st = machine.structure()
    if len(cmds) < st.rank:
        raise InvalidInputError(
            f"the plan has {len(cmds)} points; identification of the {st.rank} groups needs at least {st.rank} points"
        )
    test = machine.sample_commands(int(test_points), seed=seed + 101)
    truths = [Truth.random(machine, seed=seed + 1000 + s) for s in range(seeds)]

    def summary(c: np.ndarray, label: str) -> dict:
        rms = prediction_rms(machine, c, truths, noise, test, seed=seed, structure=st)
        return {"label": label, "points": int(len(c)), "rms_um": float(np.mean(rms)), "rms_um_std": float(np.std(rms)),
                "rms_um_max": float(np.max(rms))}

    plans = {"plan": summary(cmds, "plan")}
    if compare:
        plans["quasi_random_same_size"] = summary(machine.sample_commands(len(cmds), seed=seed + 3), "quasi-random, same size")
        plans[f"quasi_random_{FULL_SET}"] = summary(machine.sample_commands(FULL_SET, seed=seed + 3), f"quasi-random, {FULL_SET} points")
    return PlanEvaluation(plans=plans, seeds=seeds, noise=noise, test_points=int(test_points))
