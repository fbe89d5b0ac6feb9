"""Simulated laser-tracker measurements from the exact perturbed chain (Eq. 3.7).

The truth is a parameter vector for the machine and a tracker frame anywhere in the shop;
a reading is q = T0 R(commands) r_t + noise, with R the exact (not first-order) chain and
independent N(0, noise) on each coordinate. Seeded: same seed, same data.

    truth = Truth.random(machine, seed=1)                       # Table 3.3 magnitudes
    cal = simulate(machine, truth, machine.sample_commands(290, seed=1), seed=11)
    test = simulate(machine, truth, machine.sample_commands(50, seed=2), seed=12)
    result = identify(machine, cal, test=test)
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .._util import dumps
from ..errors import FileFormatError, InvalidInputError
from .identify import Frame, rotation_from_vector
from .model import Machine
from .observations import Observations

__all__ = ["Truth", "simulate", "TRACKER_SIGMA", "typical_magnitudes"]

#: Tracker standard deviation per coordinate of Sec. 3.2.1 (mm).
TRACKER_SIGMA = 0.0089


def typical_magnitudes(machine: Machine) -> np.ndarray:
    """Standard deviation of each parameter for random machines, after Table 3.3:
    shape rotations 5e-5 rad and offsets 0.05 mm, prismatic rates 3e-8 rad/mm and scale
    1e-4, rotary-joint rotations 5e-6 rad and translations 0.015 mm."""
    out = []
    for name, power in zip(machine.parameter_names, machine.parameter_length_powers):
        el = machine.elements[[e.name for e in machine.elements].index(name.split(".")[0])]
        kind = getattr(el, "kind", "shape")
        if kind == "prismatic":
            out.append(1e-4 if name.endswith(".delta") else 3e-8)
        elif kind == "rotary":
            out.append(5e-6 if power == 1 else 0.015)
        else:
            out.append(5e-5 if power == 1 else 0.05)
    return np.array(out)


@dataclass(frozen=True)
class Truth:
    """True error parameters (``parameters``, machine order, mm/rad) and tracker frame."""

    machine: str
    parameter_names: tuple[str, ...]
    parameters: np.ndarray
    frame: Frame

    @classmethod
    def random(cls, machine: Machine, seed: int = 0, scale: float = 1.0, tracker_distance: float = 3000.0) -> "Truth":
        """Random parameters of Table 3.3's magnitudes (times ``scale``) and a tracker turned
        by a uniformly random rotation and moved up to ``tracker_distance`` mm."""
        rng = np.random.default_rng(np.random.SeedSequence([seed, 0x6D61]))
        p = rng.normal(size=machine.n_parameters) * typical_magnitudes(machine) * scale
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        angle = 2.0 * math.acos(min(1.0, abs(q[0])))
        axis = q[1:] / max(np.linalg.norm(q[1:]), 1e-300)
        rot = rotation_from_vector(axis * angle)
        t = rng.uniform(-1.0, 1.0, 3) * tracker_distance
        return cls(machine.name, tuple(machine.parameter_names), p, Frame(rot, t))

    @classmethod
    def from_parameters(cls, machine: Machine, values: dict, frame: Optional[Frame] = None) -> "Truth":
        """Truth from {parameter name: value} (others zero) and a frame (default identity)."""
        names = machine.parameter_names
        unknown = [k for k in values if k not in names]
        if unknown:
            raise InvalidInputError(f"unknown parameter(s) {', '.join(unknown)} for machine '{machine.name}'")
        p = np.array([float(values.get(n, 0.0)) for n in names])
        return cls(machine.name, tuple(names), p, frame or Frame.identity())

    def group_values(self, machine: Machine, structure=None) -> dict:
        """The true value of every identifiable group."""
        st = structure if structure is not None else machine.structure()
        vals = st.group_values(self.parameters)
        return {g.name: float(v) for g, v in zip(st.groups, vals)}

    def to_dict(self, machine: Optional[Machine] = None) -> dict:
        d = {
            "machine": self.machine,
            "parameters": {n: float(v) for n, v in zip(self.parameter_names, self.parameters)},
            "frame": self.frame.to_dict(),
        }
        if machine is not None:
            d["groups"] = self.group_values(machine)
        return d

    def save(self, path: Union[str, Path], machine: Optional[Machine] = None) -> None:
        from .._files import write_text

        write_text(path, dumps(self.to_dict(machine)) + "\n")

    @classmethod
    def load(cls, path: Union[str, Path], machine: Machine) -> "Truth":
        from .._files import read_text

        p = Path(path)
        text = read_text(p, "truth JSON")
        try:
            d = json.loads(text)
            params, frame = d["parameters"], Frame.from_dict(d["frame"])
        except (ValueError, KeyError, TypeError) as exc:
            raise FileFormatError(f"{p}: not a truth JSON with parameters and frame ({exc})") from None
        if not isinstance(params, dict):
            raise FileFormatError(f"{p}: parameters must be an object {{name: value}}")
        return cls.from_parameters(machine, params, frame)


def simulate(
    machine: Machine,
    truth: Truth,
    commands: Any,
    noise: float = TRACKER_SIGMA,
    seed: int = 0,
) -> Observations:
    """Tracker readings at ``commands`` (file units): exact perturbed chain, tracker frame of
    ``truth``, independent N(0, noise) mm on each coordinate (seeded)."""
    if not (math.isfinite(noise) and noise >= 0):
        raise InvalidInputError(f"noise must be a non-negative number of mm, got {noise}")
    if tuple(truth.parameter_names) != tuple(machine.parameter_names):
        raise InvalidInputError(f"truth was made for machine '{truth.machine}', not for '{machine.name}'")
    cmds = machine.commands_array(commands)
    actual = machine.positions(cmds, truth.parameters)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7472]))
    q = truth.frame.to_tracker(actual) + rng.normal(scale=noise, size=actual.shape) if noise > 0 else truth.frame.to_tracker(actual)
    return Observations(cmds, q, tuple(machine.joint_names))
