"""Identification of the error model from tracker measurements (Sec. 3.1.5, 3.2), prediction
and compensation.

Step 1 fits the tracker frame T0 to an ideal machine in closed form (Kabsch/Horn; any
placement of the tracker, no small-angle assumption). The residuals left, expressed in the
table frame, are the machine's *nominal errors* (Table 3.2). Step 2 fits the identifiable
groups (Eq. 3.14) to them by least squares (Eq. 3.17, 3.18), with standard uncertainties from
sigma^2 (M^T M)^-1 and the condition number of the column-equilibrated matrix.

Methods:

- ``"joint"`` (default): step 2 also estimates a small correction of the frame (three small
  rotations and three translations, Eq. 3.11), iterated to convergence. This removes the bias
  of ERRATA item 6. A rigid motion of the table frame is partly in the span of the groups
  (for the example machine: a rotation about and a shift along the B axis, i.e. ``T1.beta``
  and the y-translation group); those directions cannot be told from the tracker placement,
  so the frame takes them and the groups concerned are reported as ``frame_confounded``
  (value 0, no uncertainty). Volumetric errors differ only by that rigid motion, which part
  set-up (work offsets) takes up anyway.
- ``"two-step"``: the dissertation's procedure, frame fixed after step 1, all groups fitted;
  the frame-confounded groups are then estimated relative to the step-1 frame (and flagged).
"""


from __future__ import annotations

import math
import warnings
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateGeometryError, InvalidInputError
from .calibration import NOISE_FLOOR_FACTOR, Calibration, GroupEstimate, ResidualStats, load_calibration
from .frame import Frame, frame_columns, rigid_fit, rotation_from_vector  # noqa: F401  (importable from here)
from .model import Machine, ModelStructure
from .observations import Observations
from .predict import compensate, predict, predict_uncertainty

__all__ = [
    "Frame",
    "ResidualStats",
    "GroupEstimate",
    "Calibration",
    "identify",
    "predict",
    "predict_uncertainty",
    "compensate",
    "load_calibration",
    "NOISE_FLOOR_FACTOR",
]

METHODS = ("joint", "two-step")
_MAX_ITER = 10
#: Mean nominal error (mm) beyond which the data are more likely wrong than the machine.
_SUSPICIOUS_MM = 2.0


def _as_obs(machine: Machine, obs: Any, what: str) -> Observations:
    if isinstance(obs, Observations):
        if tuple(obs.joint_names) != tuple(machine.joint_names):
            raise InvalidInputError(
                f"{what}: joints {', '.join(obs.joint_names)} do not match the machine's {', '.join(machine.joint_names)}"
            )
        return obs
    commands, measured = obs
    return Observations(machine.commands_array(commands, what), np.asarray(measured, float), tuple(machine.joint_names))



def _solve(a: np.ndarray, b: np.ndarray, names: list[str]) -> _core.kinematics.LeastSquares:
    try:
        return _core.kinematics.lstsq(np.ascontiguousarray(a), np.ascontiguousarray(b))
    except DegenerateGeometryError:
        norms = np.linalg.norm(a, axis=0)
        norms[norms == 0] = 1.0
        _, s, vt = np.linalg.svd(a / norms, full_matrices=False)
        w = vt[-1]
        worst = [names[j] for j in np.argsort(-np.abs(w))[:3] if abs(w[j]) > 0.1]
        raise DegenerateGeometryError(
            "the observations cannot separate all groups (condition number "
            f"{s[0] / max(s[-1], 1e-300):.2e}); weakest combination involves {', '.join(worst)}: "
            "measure at more, better spread commands (all joints over their ranges)"
        ) from None


def _confounded(machine: Machine, structure: ModelStructure) -> list[int]:
    """Groups whose effect is a rigid motion of the table frame (in the span of the frame
    columns): ordered identifiability of [frame | groups] over a rich set of commands."""
    cmds = machine.sample_commands(1000, seed=1)
    p = machine.nominal(cmds)
    a = np.hstack([frame_columns(p), structure.reduce(machine.design_matrix(cmds))])
    powers = [1, 1, 1, 0, 0, 0] + [machine.parameter_length_powers[j] for j in structure.leaders]
    res = _core.kinematics.identifiability(a, machine.length_scale(cmds), powers)
    lead = set(res.leaders)
    return [k for k in range(len(structure.groups)) if 6 + k not in lead]


def identify(
    machine: Machine,
    observations: Any,
    test: Any = None,
    method: str = "joint",
    test_frame: str = "same",
    structure: Optional[ModelStructure] = None,
) -> Calibration:
    """Identify the groups of Eq. 3.14 from tracker observations (Sec. 3.1.5).

    ``observations`` and ``test``: :class:`Observations` (or ``(commands, measured)``).
    ``method``: ``"joint"`` (default; frame correction estimated with the groups) or
    ``"two-step"`` (the dissertation's procedure). ``test_frame``: ``"same"`` uses the
    identified tracker frame for the test set (same set-up), ``"refit"`` fits a frame to the
    test set's model-predicted positions (a new set-up). The test set's nominal errors always
    use its own best-fit frame (Table 3.2).
    """
    if method not in METHODS:
        raise InvalidInputError(f"method must be 'joint' or 'two-step', got {method!r}")
    if test_frame not in ("same", "refit"):
        raise InvalidInputError(f"test_frame must be 'same' or 'refit', got {test_frame!r}")
    obs = _as_obs(machine, observations, "observations")
    machine.warn_out_of_range(obs.commands, what=obs.source or "observations")
    st = structure if structure is not None else machine.structure()
    n = len(obs)
    n_groups = st.rank
    if n < n_groups:
        raise DegenerateGeometryError(
            f"{n} observations are fewer than the {n_groups} identifiable groups: measure at least "
            f"{n_groups} points spread over the workspace (the dissertation used 290)"
        )
    p_nom = machine.nominal(obs.commands)
    m_red = st.reduce(machine.design_matrix(obs.commands))
    frame1 = rigid_fit(p_nom, obs.measured)  # Step 1 (Eq. 3.10 - 3.12)
    nominal_res = frame1.to_table(obs.measured) - p_nom
    fit = float(np.linalg.norm(nominal_res, axis=1).mean())
    if fit > _SUSPICIOUS_MM:
        warnings.warn(
            f"the ideal machine fits the observations to only {fit:.3g} mm on average: check the units "
            f"(mm, angle_unit = {machine.angle_unit!r}), the column names and the tool offset",
            UserWarning,
            stacklevel=2,
        )
    group_names = [g.name for g in st.groups]
    frame_names = ["frame.alpha0", "frame.beta0", "frame.gamma0", "frame.x0", "frame.y0", "frame.z0"]
    conf = _confounded(machine, st)
    if method == "two-step":
        sol = _solve(m_red, nominal_res.reshape(-1), group_names)
        frame, iterations, cols = frame1, 1, list(range(n_groups))
        x = np.asarray(sol.x)
        values = x
        model_res = nominal_res.reshape(-1) - m_red @ x
        k = n_groups
    else:
        cols = [c for c in range(n_groups) if c not in conf]
        a = np.hstack([m_red[:, cols], frame_columns(p_nom)])
        names = [group_names[c] for c in cols] + frame_names
        frame, iterations, converged = frame1, 0, False
        for iterations in range(1, _MAX_ITER + 1):
            r = (frame.to_table(obs.measured) - p_nom).reshape(-1)
            sol = _solve(a, r, names)
            x = np.asarray(sol.x)
            small = x[len(cols) :]
            frame = frame.corrected(small)
            if np.abs(small[:3]).max() < 1e-13 and np.abs(small[3:]).max() < 1e-10:
                converged = True
                break
        if not converged:
            warnings.warn(
                f"the frame correction did not settle in {_MAX_ITER} iterations (last step {np.abs(small).max():.1e}): "
                "errors this large are beyond the first-order model",
                UserWarning,
                stacklevel=2,
            )
        r = (frame.to_table(obs.measured) - p_nom).reshape(-1)
        sol = _solve(a, r, names)
        x = np.asarray(sol.x)
        frame = frame.corrected(x[len(cols) :])
        values = np.zeros(n_groups)
        values[cols] = x[: len(cols)]
        model_res = (frame.to_table(obs.measured) - p_nom).reshape(-1) - m_red @ values
        k = a.shape[1]
    dof = 3 * n - k
    if dof <= 0:
        raise DegenerateGeometryError(f"{n} observations give {3 * n} equations for {k} unknowns: measure more points")
    sigma = math.sqrt(float(sol.rss) / dof)
    cov = np.asarray(sol.cov_unscaled) * sigma**2
    std = np.full(n_groups, np.nan)
    std[cols] = np.sqrt(np.diag(cov)[: len(cols)])
    gcov = np.zeros((n_groups, n_groups))
    gcov[np.ix_(cols, cols)] = cov[: len(cols), : len(cols)]
    frame_std = None
    if method == "joint":
        fs = np.sqrt(np.diag(cov)[len(cols) :])
        frame_std = {name.split(".")[1]: float(v) for name, v in zip(frame_names, fs)}
    units = machine.parameter_units()
    groups = tuple(
        GroupEstimate(
            name=g.name,
            leader=g.leader,
            terms=dict(g.terms),
            value=float(values[i]),
            std=None if (method == "joint" and i in conf) else float(std[i]),
            unit=units[st.leaders[i]],
            frame_confounded=i in conf,
        )
        for i, g in enumerate(st.groups)
    )
    cal = Calibration(
        machine=machine.name,
        method=method,
        rank=st.rank,
        condition_number=float(sol.condition_number),
        groups=groups,
        unidentifiable=tuple(st.no_effect),
        frame=frame,
        residuals=ResidualStats.of(nominal_res, model_res),
        sigma=sigma,
        dof=dof,
        frame_step1=frame1,
        iterations=iterations,
        frame_std=frame_std,
        covariance=gcov,
        point_residuals={"nominal": nominal_res.reshape(-1, 3), "model": model_res.reshape(-1, 3)},
    )
    if test is not None:
        tobs = _as_obs(machine, test, "test observations")
        machine.warn_out_of_range(tobs.commands, what=tobs.source or "test observations")
        cal = _with_test(machine, cal, tobs, test_frame, st)
    return cal


def _with_test(machine: Machine, cal: Calibration, tobs: Observations, test_frame: str, st: ModelStructure) -> Calibration:
    p = machine.nominal(tobs.commands)
    if len(tobs) < 3:
        raise DegenerateGeometryError(f"test set: {len(tobs)} observations; at least 3 are needed")
    own = rigid_fit(p, tobs.measured)
    nominal = own.to_table(tobs.measured) - p
    predicted = p + predict(machine, cal, tobs.commands, structure=st)
    frame = cal.frame if test_frame == "same" else rigid_fit(predicted, tobs.measured)
    model = frame.to_table(tobs.measured) - predicted
    points = {**(cal.point_residuals or {}), "test_nominal": nominal, "test_model": model}
    return Calibration(**{**cal.__dict__, "test": ResidualStats.of(nominal, model), "point_residuals": points})

