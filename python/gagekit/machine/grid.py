"""The grid of a compensation table and the model values at its nodes (Sec. 7.1.1 (3)): a
regular grid over named joints, the minimum-norm parameters of a calibration (Eq. 3.14),
the predicted volumetric error (Eq. 3.9) with its standard uncertainty, the first-order
command corrections c = -pinv(J) e and their uncertainty (GUM 5.1.2), and the multilinear
interpolation a grid controller applies between the nodes. The controller formats
(:mod:`.controllers`) and :func:`gagekit.machine.export.export` are built on it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from ..errors import InvalidInputError
from .calibration import Calibration
from .model import Machine
from .predict import check_calibration, predict, predict_covariance, predict_uncertainty

__all__ = ["Grid", "DEFAULT_STEP", "make_grid", "calibration_parameters", "corrections", "correction_uncertainty",
           "grid_predictions", "interpolate_grid", "multilinear", "number_text"]

DEFAULT_STEP = {"prismatic": 50.0, "rotary": 5.0}


@dataclass(frozen=True)
class Grid:
    """A regular grid over ``axes`` (node values per axis, file units); other joints ``fixed``."""

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    fixed: dict

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.values)

    def commands(self, machine: Machine) -> np.ndarray:
        """(N, J) commands at the nodes, C order of ``axes``."""
        mesh = np.meshgrid(*self.values, indexing="ij")
        n = mesh[0].size if mesh else 1
        c = np.empty((n, len(machine.joint_names)))
        for j, name in enumerate(machine.joint_names):
            if name in self.axes:
                c[:, j] = mesh[self.axes.index(name)].reshape(-1)
            else:
                c[:, j] = self.fixed[name]
        return c

    def random_commands(self, machine: Machine, n: int, seed: int) -> np.ndarray:
        """``n`` uniform random commands inside the grid (other joints fixed)."""
        rng = np.random.default_rng(seed)
        c = np.empty((n, len(machine.joint_names)))
        for j, name in enumerate(machine.joint_names):
            if name in self.axes:
                v = self.values[self.axes.index(name)]
                c[:, j] = rng.uniform(v[0], v[-1], n)
            else:
                c[:, j] = self.fixed[name]
        return c

    def to_dict(self) -> dict:
        return {
            "axes": list(self.axes),
            "points": list(self.shape),
            "start": [float(v[0]) for v in self.values],
            "end": [float(v[-1]) for v in self.values],
            "step": [float(v[1] - v[0]) if len(v) > 1 else 0.0 for v in self.values],
            "fixed": dict(self.fixed),
        }


def _per_axis(value: Any, axes: Sequence[str], what: str) -> dict:
    """A number for every axis, or {axis: number}; returns {axis: value or None}."""
    if value is None:
        return {a: None for a in axes}
    if isinstance(value, Mapping):
        unknown = [k for k in value if k not in axes]
        if unknown:
            raise InvalidInputError(f"{what}: '{unknown[0]}' is not one of the grid axes {', '.join(axes)}")
        return {a: value.get(a) for a in axes}
    return {a: value for a in axes}


def make_grid(
    machine: Machine,
    axes: Sequence[str],
    step: Any = None,
    points: Any = None,
    at: Optional[Mapping[str, float]] = None,
    limits: Optional[Mapping[str, tuple[float, float]]] = None,
) -> Grid:
    """A regular grid over ``axes`` inside the joint ranges; see the module docstring."""
    names = machine.joint_names
    spec = {j.name: j for j in machine.joints}
    axes = list(axes)
    if not axes:
        raise InvalidInputError("grid: no axes")
    machine.check_joint_names(axes, "grid axes")
    if len(set(axes)) != len(axes):
        raise InvalidInputError(f"grid axes repeat a joint: {', '.join(axes)}")
    if step is not None and points is not None:
        raise InvalidInputError("give --step or --points, not both")
    steps = _per_axis(step, axes, "--step")
    counts = _per_axis(points, axes, "--points")
    limits = dict(limits or {})
    for k in limits:
        if k not in axes:
            raise InvalidInputError(f"--limits: '{k}' is not one of the grid axes {', '.join(axes)}")
    values = []
    for a in axes:
        j = spec[a]
        lo, hi = j.range
        if a in limits:
            l0, l1 = (float(v) for v in limits[a])
            if not (math.isfinite(l0) and math.isfinite(l1) and l0 < l1):
                raise InvalidInputError(f"--limits {a}: need finite lo < hi, got {l0}:{l1}")
            if l0 < lo - 1e-9 or l1 > hi + 1e-9:
                raise InvalidInputError(f"--limits {a}={l0:g}:{l1:g} is outside the joint range [{lo:g}, {hi:g}]")
            lo, hi = l0, l1
        n = counts[a]
        if n is not None:
            if int(n) != n or n < 2:
                raise InvalidInputError(f"--points for {a} must be an integer >= 2, got {n}")
            n = int(n)
        else:
            s = steps[a] if steps[a] is not None else DEFAULT_STEP[j.kind]
            if not (isinstance(s, (int, float)) and math.isfinite(s) and s > 0):
                raise InvalidInputError(f"--step for {a} must be a positive number, got {s}")
            n = int(math.ceil((hi - lo) / s - 1e-9)) + 1
        if n > 100_000:
            raise InvalidInputError(f"grid axis {a}: {n} nodes is too many (raise --step)")
        values.append(np.linspace(lo, hi, n))
    fixed = {}
    at = dict(at or {})
    machine.check_joint_names(at, "--at")
    for k in at:
        if k in axes:
            raise InvalidInputError(f"--at: '{k}' is a grid axis; fix only the other joints")
    for name in names:
        if name in axes:
            continue
        lo, hi = spec[name].range
        v = at.get(name, 0.0 if lo <= 0.0 <= hi else 0.5 * (lo + hi))
        v = float(v)
        if not (math.isfinite(v) and lo <= v <= hi):
            raise InvalidInputError(f"--at {name}={v:g} is outside the joint range [{lo:g}, {hi:g}]")
        fixed[name] = v
    size = int(np.prod([len(v) for v in values]))
    if size > 5_000_000:
        raise InvalidInputError(f"the grid has {size} nodes; raise --step or lower --points")
    return Grid(tuple(axes), tuple(values), fixed)


def calibration_parameters(machine: Machine, calibration: Calibration) -> np.ndarray:
    """The minimum-norm parameter vector (P,) with the calibration's group values (Eq. 3.14);
    raises ConfigError when the calibration is not this machine's (:func:`check_calibration`)."""
    c = check_calibration(machine, calibration)
    return np.linalg.pinv(c) @ np.array([g.value for g in calibration.groups])


def corrections(machine: Machine, commands: np.ndarray, errors: np.ndarray, joints: Sequence[str]) -> np.ndarray:
    """(n, k) first-order command corrections: c = -pinv(J[:, joints]) e (command Jacobian)."""
    idx = [machine.joint_names.index(j) for j in joints]
    n = commands.shape[0]
    out = np.empty((n, len(idx)))
    for s in range(0, n, 50_000):
        jac = machine.command_jacobian(commands[s : s + 50_000]).reshape(-1, 3, len(machine.joint_names))[:, :, idx]
        out[s : s + 50_000] = -np.einsum("nij,nj->ni", np.linalg.pinv(jac), errors[s : s + 50_000])
    return out


def correction_uncertainty(machine: Machine, calibration: Calibration, commands: np.ndarray, joints: Sequence[str]) -> np.ndarray:
    """(n, k) standard uncertainty (mm) of the corrections c = -pinv(J[:, joints]) e: with
    P = -pinv(J) and the prediction covariance C_e (:func:`predict_covariance`),
    u(c)^2 = diag(P C_e P^T) (GUM 5.1.2, exact: c is linear in the group values)."""
    st = machine.structure()
    idx = [machine.joint_names.index(j) for j in joints]
    n = commands.shape[0]
    out = np.empty((n, len(idx)))
    for s in range(0, n, 20_000):
        c = commands[s : s + 20_000]
        ce = predict_covariance(machine, calibration, c, structure=st)
        jac = machine.command_jacobian(c).reshape(-1, 3, len(machine.joint_names))[:, :, idx]
        pm = np.linalg.pinv(jac)
        var = np.einsum("nki,nij,nkj->nk", pm, ce, pm)
        out[s : s + 20_000] = np.sqrt(np.clip(var, 0.0, None))
    return out


def grid_predictions(machine: Machine, calibration: Calibration, commands: np.ndarray, with_uncertainty: bool = True):
    """Predicted error (n, 3) and its standard uncertainty (n, 3) (or None), mm, in chunks."""
    st = machine.structure()
    e = np.empty((commands.shape[0], 3))
    u = np.empty((commands.shape[0], 3)) if with_uncertainty else None
    for s in range(0, commands.shape[0], 20_000):
        c = commands[s : s + 20_000]
        e[s : s + 20_000] = predict(machine, calibration, c, structure=st)
        if with_uncertainty:
            u[s : s + 20_000] = predict_uncertainty(machine, calibration, c, structure=st)
    return e, u


def number_text(v: float) -> str:
    """A number as the tables write it: shortest round-trip repr, 0.0 for zeros."""
    return repr(float(v)) if v != 0.0 else "0.0"


def interpolate_grid(grid: Grid, table: np.ndarray, commands: np.ndarray, machine: Machine) -> np.ndarray:
    """Multilinear interpolation of a (shape..., k) table at commands (n, J): what a grid
    compensation (FANUC 3-D, trilinear) does between the nodes."""
    idx = [machine.joint_names.index(a) for a in grid.axes]
    return multilinear(grid.values, table, commands[:, idx])


def multilinear(values: tuple[np.ndarray, ...], table: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Multilinear interpolation on a regular (rectilinear) grid: ``values`` the ascending
    node coordinates per axis, ``table`` (len(values[0]), ..., len(values[-1]), k...), ``points``
    (n, d) inside the grid. Each point blends the 2^d vertices of its cell with the interior
    division ratios (the trilinear rule of FANUC's A-79351E for d = 3); an axis with one node
    holds that node's value. Points outside the grid are refused."""
    pts = np.asarray(points, dtype=float).reshape(len(points), len(values))
    table = np.asarray(table, dtype=float)
    lo_idx, frac = [], []
    for d, v in enumerate(values):
        v = np.asarray(v, dtype=float)
        x = pts[:, d]
        if np.any((x < v[0]) | (x > v[-1])) or not np.all(np.isfinite(x)):
            raise InvalidInputError(f"interpolation: a point lies outside the grid on axis {d} [{v[0]:g}, {v[-1]:g}]")
        if len(v) == 1:
            lo_idx.append(np.zeros(len(x), dtype=np.intp))
            frac.append(np.zeros(len(x)))
            continue
        i = np.clip(np.searchsorted(v, x, side="right") - 1, 0, len(v) - 2)
        lo_idx.append(i)
        frac.append((x - v[i]) / (v[i + 1] - v[i]))
    out = np.zeros((len(pts),) + table.shape[len(values):])
    for corner in range(1 << len(values)):
        weight = np.ones(len(pts))
        index = []
        for d, v in enumerate(values):
            up = (corner >> d) & 1
            index.append(np.minimum(lo_idx[d] + up, len(v) - 1))
            weight = weight * (frac[d] if up else 1.0 - frac[d])
        out += weight.reshape((-1,) + (1,) * (out.ndim - 1)) * table[tuple(index)]
    return out
