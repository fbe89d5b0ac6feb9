"""Errors predicted from temperatures alone (Sec. 7.2 item 4; issue 15 part 4).

``machine track`` fits a ridge model from the cycle-mean temperatures to the identified groups
(:func:`gagekit.machine.tracking.track`, ``temperature_model``: intercept, coefficients per C,
reference temperatures). :func:`predict_from_temperatures` evaluates it for a new cycle's
temperatures: g = intercept + coefficients . (T - T_ref), and the volumetric error
M_L(c) g (Eq. 3.14) at the commands, table frame, mm.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Union

import numpy as np

from ..errors import ConfigError, FileFormatError, InvalidInputError
from .model import Machine
from .observations import _read_table

__all__ = ["TemperatureModel", "load_temperature_model", "read_temperatures", "predict_from_temperatures"]


@dataclass(frozen=True)
class TemperatureModel:
    """The fitted temperature model of a tracking run."""

    machine: str
    sensors: tuple[str, ...]
    groups: tuple[str, ...]
    intercept: np.ndarray  # (G,)
    coefficients: np.ndarray  # (S, G), group unit per C
    reference: np.ndarray  # (S,) C

    def groups_at(self, temperatures: np.ndarray) -> np.ndarray:
        return self.intercept + (np.asarray(temperatures, dtype=float) - self.reference) @ self.coefficients


def load_temperature_model(path: Union[str, Path]) -> TemperatureModel:
    """Read the ``temperature_model`` of a ``machine track --json`` output (or report track.json)."""
    from .._files import read_text

    p = Path(path)
    try:
        d = json.loads(read_text(p, "tracking result"))
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{p}: not a tracking result JSON ({exc})") from None
    tm = d.get("temperature_model") if isinstance(d, dict) else None
    if not isinstance(tm, dict) or not tm.get("fitted") or "intercept" not in tm:
        raise ConfigError(f"{p}: no fitted temperature model (track cycles with temp_* columns, at least 4 cycles)")
    try:
        sensors = tuple(tm["sensors"])
        groups = tuple(tm["intercept"])
        coef = np.array([[float(tm["coefficients"][g][s]) for g in groups] for s in sensors])
        return TemperatureModel(
            machine=str(d.get("machine", "")),
            sensors=sensors,
            groups=groups,
            intercept=np.array([float(tm["intercept"][g]) for g in groups]),
            coefficients=coef,
            reference=np.array([float(tm["reference_temperatures"][s]) for s in sensors]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{p}: malformed temperature model ({type(exc).__name__}: {exc})") from None


def read_temperatures(path: Union[str, Path], model: TemperatureModel) -> np.ndarray:
    """Cycle-mean temperatures (S,) from a CSV with the model's sensor columns (rows averaged)."""
    header, data = _read_table(path)
    missing = [s for s in model.sensors if s not in header]
    if missing:
        raise FileFormatError(f"{path}: missing temperature column(s) {', '.join(missing)} (the model uses {', '.join(model.sensors)})")
    if len(data) == 0:
        raise FileFormatError(f"{path}: no temperature rows")
    return np.array([data[:, header.index(s)].mean() for s in model.sensors])


def predict_from_temperatures(machine: Machine, model: TemperatureModel, commands: Any, temperatures: np.ndarray) -> np.ndarray:
    """Volumetric error (n, 3), mm, table frame, predicted from the temperatures alone."""
    if model.machine and model.machine != machine.name:
        raise ConfigError(f"the temperature model is of machine '{model.machine}', not '{machine.name}'")
    st = machine.structure()
    if tuple(g.name for g in st.groups) != model.groups:
        raise ConfigError(f"the temperature model's groups do not match machine '{machine.name}': track again with this machine file")
    t = np.asarray(temperatures, dtype=float)
    if t.shape != (len(model.sensors),) or not np.isfinite(t).all():
        raise InvalidInputError(f"temperatures: expected {len(model.sensors)} finite values")
    g = model.groups_at(t)
    return (machine.reduced_design_matrix(commands, st) @ g).reshape(-1, 3)
