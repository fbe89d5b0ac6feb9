"""Prediction and compensation of volumetric errors from a calibration (Eqs. 3.9, 3.13, 3.14)."""

from __future__ import annotations

import math
import warnings
from typing import Any, Optional, Sequence

import numpy as np

from .. import _core
from ..errors import ConfigError, InvalidInputError
from .calibration import Calibration
from .model import Machine, ModelStructure

__all__ = ["predict", "predict_uncertainty", "predict_covariance", "compensate", "check_calibration"]


def check_calibration(machine: Machine, cal: Calibration, st: Optional[ModelStructure] = None) -> np.ndarray:
    """The one rule for using a calibration with a machine (predict, compensate, export,
    compensate-nc, uncertainty): it must name this machine (when it names one) and its groups
    must be this machine's (same count, leaders and coefficients, Eq. 3.14). Returns the
    coefficient matrix (groups x parameters); raises ConfigError otherwise."""
    if cal.machine and cal.machine != machine.name:
        raise ConfigError(
            f"the calibration is of machine '{cal.machine}', not '{machine.name}': identify again with this machine file"
        )
    return _coefficients(machine, cal, st if st is not None else machine.structure())


def _coefficients(machine: Machine, cal: Calibration, st: ModelStructure) -> np.ndarray:
    names = machine.parameter_names
    index = {n: j for j, n in enumerate(names)}
    model_terms = {g.leader: g.terms for g in st.groups}
    c = np.zeros((len(cal.groups), len(names)))
    for i, g in enumerate(cal.groups):
        for name, coef in g.terms.items():
            if name not in index:
                raise ConfigError(
                    f"calibration group '{g.name}' uses parameter '{name}', which machine '{machine.name}' does not have"
                )
            c[i, index[name]] = coef
        want = model_terms.get(g.leader)
        if want is None or set(want) != set(g.terms) or any(
            not math.isclose(want[t], g.terms[t], rel_tol=1e-6, abs_tol=1e-9) for t in want
        ):
            raise ConfigError(
                f"calibration group '{g.name}' does not match machine '{machine.name}' "
                "(different chain, offsets or tool): identify again with this machine file"
            )
    if len(cal.groups) != st.rank:
        raise ConfigError(f"calibration has {len(cal.groups)} groups, machine '{machine.name}' has {st.rank}")
    return c


def predict(machine: Machine, calibration: Calibration, commands: Any, structure: Optional[ModelStructure] = None) -> np.ndarray:
    """Volumetric error (n, 3), mm, in the table frame at ``commands`` (file units): M p
    (Eq. 3.9, 3.13) with p any parameter vector having the identified group values."""
    st = structure if structure is not None else machine.structure()
    c = check_calibration(machine, calibration, st)
    machine.warn_out_of_range(commands)
    values = np.array([g.value for g in calibration.groups])
    p = np.linalg.pinv(c) @ values
    return machine.volumetric_error(commands, p)


def _group_covariance(calibration: Calibration, st: ModelStructure) -> np.ndarray:
    if calibration.covariance is None:
        raise ConfigError("calibration has no covariance (written by an older gagekit?): identify again")
    cov = np.asarray(calibration.covariance, dtype=np.float64)
    if cov.shape != (st.rank, st.rank):
        raise ConfigError(f"calibration covariance is {cov.shape}, expected ({st.rank}, {st.rank})")
    return cov


def predict_covariance(
    machine: Machine, calibration: Calibration, commands: Any, structure: Optional[ModelStructure] = None
) -> np.ndarray:
    """Covariance (n, 3, 3), mm^2, of each predicted error vector from the group covariance
    Sigma of the identification: M_L,i Sigma M_L,i^T, with M_L,i the three rows of the reduced
    design matrix (Eq. 3.14) at command i. The prediction is linear in the group values, so
    this is the law of propagation of uncertainty exactly (GUM, JCGM 100:2008, 5.1.2, with
    the covariance terms of 5.2.2 Eq. 13); no linearisation error. The groups the frame takes
    (a rigid motion) have zero rows in Sigma and are not included."""
    st = structure if structure is not None else machine.structure()
    check_calibration(machine, calibration, st)
    cov = _group_covariance(calibration, st)
    ml = machine.reduced_design_matrix(commands, st).reshape(-1, 3, st.rank)
    return np.einsum("nik,kl,njl->nij", ml, cov, ml)


def predict_uncertainty(
    machine: Machine, calibration: Calibration, commands: Any, structure: Optional[ModelStructure] = None
) -> np.ndarray:
    """Standard uncertainty (n, 3), mm, of each predicted error component from the group
    covariance: sqrt(diag(M_L Sigma M_L^T)), with M_L the reduced design matrix (Eq. 3.14);
    see :func:`predict_covariance` (GUM 5.1.2).
    The uncertainty of the groups the frame takes is a rigid motion and is not included."""
    st = structure if structure is not None else machine.structure()
    check_calibration(machine, calibration, st)
    cov = _group_covariance(calibration, st)
    ml = machine.reduced_design_matrix(commands, st)
    var = np.einsum("ij,jk,ik->i", ml, cov, ml)
    return np.sqrt(np.clip(var, 0.0, None)).reshape(-1, 3)


def compensate(
    machine: Machine,
    calibration: Calibration,
    commands: Any,
    axes: Optional[Sequence[str]] = None,
    iterations: int = 4,
    structure: Optional[ModelStructure] = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Commands corrected so that the predicted actual target position is the nominal one
    of the given commands. Only ``axes`` move (default: all prismatic joints; redundant axes
    share the correction by minimum norm); rotary joints keep the tool orientation.

    Returns (corrected commands (n, J) in file units, remaining predicted error (n, 3) mm).
    """
    st = structure if structure is not None else machine.structure()
    coef = check_calibration(machine, calibration, st)
    c0 = machine.commands_array(commands)
    machine.warn_out_of_range(c0)
    joints = machine.joints
    if axes is None:
        axes = [j.name for j in joints if j.kind == "prismatic"]
    unknown = [a for a in axes if a not in machine.joint_names]
    if unknown:
        raise InvalidInputError(f"compensation axes: unknown joint(s) {', '.join(unknown)} (machine has {', '.join(machine.joint_names)})")
    if not axes:
        raise InvalidInputError("compensation axes: none given")
    idx = [machine.joint_names.index(a) for a in axes]
    p = np.linalg.pinv(coef) @ np.array([g.value for g in calibration.groups])
    n = c0.shape[0]
    # Gauss-Newton on the commands of ``axes`` (Rust kernel, gagekit-kinematics chain/inverse.rs):
    # c <- c - pinv(J_axes) (P(c) + M(c) p - P(c0)), minimum-norm steps for redundant axes
    unit = machine._angle_factor()
    c, remaining = _core.nc.compensate_commands(
        machine._chain, np.ascontiguousarray(c0 * unit), np.ascontiguousarray(p), idx, int(iterations)
    )
    c = c0 + (np.asarray(c) - c0 * unit) / unit  # joints not in ``axes`` stay bit-identical
    c[:, [j for j in range(c.shape[1]) if j not in idx]] = c0[:, [j for j in range(c.shape[1]) if j not in idx]]
    remaining = np.asarray(remaining)
    worst = float(np.linalg.norm(remaining, axis=1).max()) if n else 0.0
    if worst > 1e-6:
        warnings.warn(
            f"compensation with axes {', '.join(axes)} leaves up to {worst:.2e} mm of predicted error: "
            "these axes cannot move the target in every direction",
            UserWarning,
            stacklevel=2,
        )
    machine.warn_out_of_range(c, what="corrected commands")
    return c, remaining
