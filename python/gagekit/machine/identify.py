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

import json
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from .. import _core
from .._util import dumps
from ..errors import ConfigError, DegenerateGeometryError, FileFormatError, InvalidInputError
from .model import Machine, ModelStructure
from .observations import Observations

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
#: Mean length of a 3-D vector of independent N(0, sigma) coordinates, in sigma: 2 sqrt(2/pi).
NOISE_FLOOR_FACTOR = 2.0 * math.sqrt(2.0 / math.pi)
_MAX_ITER = 10
#: Mean nominal error (mm) beyond which the data are more likely wrong than the machine.
_SUSPICIOUS_MM = 2.0


def rotation_from_vector(v: Sequence[float]) -> np.ndarray:
    """Exact rotation matrix of the rotation vector ``v`` (axis times angle, rad; Rodrigues)."""
    v = np.asarray(v, dtype=np.float64)
    th = float(np.linalg.norm(v))
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    if th < 1e-12:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + math.sin(th) / th * k + (1.0 - math.cos(th)) / th**2 * k @ k


@dataclass(frozen=True)
class Frame:
    """The measurement frame T0: a tracker reading is q = rotation @ p + translation for a
    point p in the table frame (Eq. 3.10, 3.12), mm."""

    rotation: np.ndarray
    translation: np.ndarray

    def __post_init__(self) -> None:
        r = np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)
        t = np.asarray(self.translation, dtype=np.float64).reshape(3)
        if not (np.isfinite(r).all() and np.isfinite(t).all()):
            raise InvalidInputError("frame: non-finite rotation or translation")
        if np.abs(r.T @ r - np.eye(3)).max() > 1e-6 or np.linalg.det(r) < 0:
            raise InvalidInputError("frame: rotation is not a proper rotation matrix")
        object.__setattr__(self, "rotation", r)
        object.__setattr__(self, "translation", t)

    @classmethod
    def identity(cls) -> "Frame":
        return cls(np.eye(3), np.zeros(3))

    def to_tracker(self, p: np.ndarray) -> np.ndarray:
        return np.asarray(p) @ self.rotation.T + self.translation

    def to_table(self, q: np.ndarray) -> np.ndarray:
        return (np.asarray(q) - self.translation) @ self.rotation

    def corrected(self, small: np.ndarray) -> "Frame":
        """This frame followed by the small table-frame motion ``small`` = (alpha0, beta0,
        gamma0, x0, y0, z0) of Eq. 3.11: rotations about z, y, x and a translation."""
        a, b, g, x, y, z = small
        return Frame(self.rotation @ rotation_from_vector([g, b, a]), self.translation + self.rotation @ [x, y, z])

    def to_dict(self) -> dict:
        return {"rotation": self.rotation.tolist(), "translation": self.translation.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "Frame":
        try:
            return cls(np.array(d["rotation"], dtype=np.float64), np.array(d["translation"], dtype=np.float64))
        except (KeyError, TypeError, ValueError) as exc:
            raise FileFormatError(f"frame: expected rotation (3x3) and translation (3), {exc}") from None


def frame_columns(p: np.ndarray) -> np.ndarray:
    """(3n, 6) effect of a small table-frame motion (alpha0, beta0, gamma0, x0, y0, z0) on
    points p (n, 3): omega x p + tau."""
    p = np.asarray(p, dtype=np.float64)
    n = p.shape[0]
    out = np.zeros((n, 3, 6))
    for c, ax in enumerate((2, 1, 0)):
        e = np.zeros(3)
        e[ax] = 1.0
        out[:, :, c] = np.cross(e, p)
    out[:, :, 3:] = np.eye(3)
    return out.reshape(3 * n, 6)


@dataclass(frozen=True)
class ResidualStats:
    """Residual vector lengths in the form of Tables 3.4 and 3.5 (mm)."""

    n_points: int
    nominal_mean: float
    nominal_max: float
    model_mean: float
    model_max: float

    @property
    def decrease_mean_pct(self) -> float:
        return 100.0 * (1.0 - self.model_mean / self.nominal_mean) if self.nominal_mean > 0 else 0.0

    @property
    def decrease_max_pct(self) -> float:
        return 100.0 * (1.0 - self.model_max / self.nominal_max) if self.nominal_max > 0 else 0.0

    @classmethod
    def of(cls, nominal: np.ndarray, model: np.ndarray) -> "ResidualStats":
        a = np.linalg.norm(np.asarray(nominal).reshape(-1, 3), axis=1)
        b = np.linalg.norm(np.asarray(model).reshape(-1, 3), axis=1)
        return cls(len(a), float(a.mean()), float(a.max()), float(b.mean()), float(b.max()))

    def to_dict(self) -> dict:
        return {
            "n_points": self.n_points,
            "nominal": {"mean": self.nominal_mean, "max": self.nominal_max},
            "model": {"mean": self.model_mean, "max": self.model_max},
            "decrease_mean_pct": self.decrease_mean_pct,
            "decrease_max_pct": self.decrease_max_pct,
        }

    @classmethod
    def from_dict(cls, d: dict) -> "ResidualStats":
        return cls(d["n_points"], d["nominal"]["mean"], d["nominal"]["max"], d["model"]["mean"], d["model"]["max"])


@dataclass(frozen=True)
class GroupEstimate:
    """An identified group: value = sum(coef * parameter) with standard uncertainty ``std``
    (None for a group confounded with the tracker frame, which the frame takes)."""

    name: str
    leader: str
    terms: dict
    value: float
    std: Optional[float]
    unit: str
    frame_confounded: bool = False

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "terms": dict(self.terms),
            "value": self.value,
            "std": self.std,
            "unit": self.unit,
            "leader": self.leader,
            "frame_confounded": self.frame_confounded,
        }


@dataclass(frozen=True)
class Calibration:
    """The result of :func:`identify` (Tables 3.2 to 3.5).

    ``frame`` maps the table frame to the tracker frame (q = R p + t); ``frame_std`` holds
    the standard uncertainties of its small-angle correction (alpha0, beta0, gamma0 rad,
    x0, y0, z0 mm; joint method). ``sigma`` is the estimated noise per coordinate and
    ``noise_floor`` = 1.596 sigma the mean residual length that noise alone leaves.
    ``condition_number`` is s_max / s_min (ERRATA item 2) of the column-equilibrated
    least-squares matrix: the groups, plus the frame correction for the joint method.
    ``rank`` is the model's (Eq. 3.14); ``dof`` = 3n minus the unknowns actually fitted.
    """

    machine: str
    method: str
    rank: int
    condition_number: float
    groups: tuple[GroupEstimate, ...]
    unidentifiable: tuple[str, ...]
    frame: Frame
    residuals: ResidualStats
    sigma: float
    dof: int
    test: Optional[ResidualStats] = None
    frame_step1: Optional[Frame] = None
    iterations: int = 1
    frame_std: Optional[dict] = None
    #: Covariance (rank x rank) of the group values, in ``groups`` order (zero rows and columns
    #: for groups the frame takes). Propagates to predictions (:func:`predict_uncertainty`).
    covariance: Optional[np.ndarray] = field(default=None, repr=False, compare=False)
    units: dict = field(default_factory=lambda: {"length": "mm", "angle": "rad"})
    #: Per-point residual vectors (n, 3), table frame, mm: "nominal" and "model" for the
    #: identification set, "test_nominal" and "test_model" with a test set (Figure 3.12).
    #: Not part of the JSON.
    point_residuals: Optional[dict] = field(default=None, repr=False, compare=False)

    @property
    def values(self) -> dict:
        return {g.name: g.value for g in self.groups}

    @property
    def frame_confounded(self) -> list[str]:
        return [g.name for g in self.groups if g.frame_confounded]

    @property
    def noise_floor(self) -> float:
        """Mean residual length expected from noise alone: 1.596 sigma."""
        return NOISE_FLOOR_FACTOR * self.sigma

    def to_dict(self) -> dict:
        d = {
            "machine": self.machine,
            "method": self.method,
            "rank": self.rank,
            "condition_number": self.condition_number,
            "groups": [g.to_dict() for g in self.groups],
            "unidentifiable": list(self.unidentifiable),
            "frame_confounded": self.frame_confounded,
            "frame": self.frame.to_dict(),
            "residuals": self.residuals.to_dict(),
            "sigma": self.sigma,
            "noise_floor": self.noise_floor,
            "dof": self.dof,
            "iterations": self.iterations,
            "units": dict(self.units),
        }
        if self.frame_std is not None:
            d["frame_std"] = dict(self.frame_std)
        if self.covariance is not None:
            d["covariance"] = np.asarray(self.covariance).tolist()
        if self.frame_step1 is not None:
            d["frame_step1"] = self.frame_step1.to_dict()
        if self.test is not None:
            d["test"] = {"residuals": self.test.to_dict()}
        return d

    def save(self, path: Union[str, Path]) -> None:
        from .._files import write_text

        write_text(path, dumps(self) + "\n")

    @classmethod
    def from_dict(cls, d: dict) -> "Calibration":
        try:
            groups = tuple(
                GroupEstimate(
                    name=g["name"],
                    leader=g.get("leader", next(iter(g["terms"]))),
                    terms={k: float(v) for k, v in g["terms"].items()},
                    value=float(g["value"]) if g["value"] is not None else 0.0,
                    std=g.get("std"),
                    unit=g.get("unit", ""),
                    frame_confounded=bool(g.get("frame_confounded", False)),
                )
                for g in d["groups"]
            )
            return cls(
                machine=d.get("machine", ""),
                method=d.get("method", ""),
                rank=int(d["rank"]),
                condition_number=float(d.get("condition_number", float("nan"))),
                groups=groups,
                unidentifiable=tuple(d.get("unidentifiable", ())),
                frame=Frame.from_dict(d["frame"]),
                residuals=ResidualStats.from_dict(d["residuals"]),
                sigma=float(d.get("sigma", float("nan"))),
                dof=int(d.get("dof", 0)),
                test=ResidualStats.from_dict(d["test"]["residuals"]) if d.get("test") else None,
                frame_step1=Frame.from_dict(d["frame_step1"]) if d.get("frame_step1") else None,
                iterations=int(d.get("iterations", 1)),
                frame_std=d.get("frame_std"),
                covariance=np.array(d["covariance"], dtype=np.float64) if d.get("covariance") is not None else None,
            )
        except (KeyError, TypeError, ValueError, AttributeError, StopIteration) as exc:
            raise FileFormatError(f"calibration: malformed ({type(exc).__name__}: {exc})") from None


def load_calibration(path: Union[str, Path]) -> Calibration:
    """Read a calibration JSON written by ``gagekit machine identify --out``."""
    from .._files import read_text

    p = Path(path)
    text = read_text(p, "calibration JSON")
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{p}: not a calibration JSON ({exc})") from None
    if not isinstance(d, dict):
        raise FileFormatError(f"{p}: not a calibration JSON (top level is not an object)")
    try:
        return Calibration.from_dict(d)
    except FileFormatError as exc:
        raise FileFormatError(f"{p}: {exc}") from None


def _as_obs(machine: Machine, obs: Any, what: str) -> Observations:
    if isinstance(obs, Observations):
        if tuple(obs.joint_names) != tuple(machine.joint_names):
            raise InvalidInputError(
                f"{what}: joints {', '.join(obs.joint_names)} do not match the machine's {', '.join(machine.joint_names)}"
            )
        return obs
    commands, measured = obs
    return Observations(machine.commands_array(commands, what), np.asarray(measured, float), tuple(machine.joint_names))


def _rigid(src: np.ndarray, dst: np.ndarray) -> Frame:
    r, t, _ = _core.machine_rigid_fit(np.ascontiguousarray(src), np.ascontiguousarray(dst))
    return Frame(r, t)


def _solve(a: np.ndarray, b: np.ndarray, names: list[str]) -> dict:
    try:
        return _core.machine_lstsq(np.ascontiguousarray(a), np.ascontiguousarray(b))
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
    res = _core.machine_identifiability(a, machine.length_scale(cmds), powers)
    lead = set(res["leaders"])
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
    frame1 = _rigid(p_nom, obs.measured)  # Step 1 (Eq. 3.10 - 3.12)
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
        x = np.asarray(sol["x"])
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
            x = np.asarray(sol["x"])
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
        x = np.asarray(sol["x"])
        frame = frame.corrected(x[len(cols) :])
        values = np.zeros(n_groups)
        values[cols] = x[: len(cols)]
        model_res = (frame.to_table(obs.measured) - p_nom).reshape(-1) - m_red @ values
        k = a.shape[1]
    dof = 3 * n - k
    if dof <= 0:
        raise DegenerateGeometryError(f"{n} observations give {3 * n} equations for {k} unknowns: measure more points")
    sigma = math.sqrt(float(sol["rss"]) / dof)
    cov = np.asarray(sol["cov_unscaled"]) * sigma**2
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
        condition_number=float(sol["condition_number"]),
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
    own = _rigid(p, tobs.measured)
    nominal = own.to_table(tobs.measured) - p
    predicted = p + predict(machine, cal, tobs.commands, structure=st)
    frame = cal.frame if test_frame == "same" else _rigid(predicted, tobs.measured)
    model = frame.to_table(tobs.measured) - predicted
    points = {**(cal.point_residuals or {}), "test_nominal": nominal, "test_model": model}
    return Calibration(**{**cal.__dict__, "test": ResidualStats.of(nominal, model), "point_residuals": points})


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
    machine.warn_out_of_range(commands)
    c = _coefficients(machine, calibration, st)
    values = np.array([g.value for g in calibration.groups])
    p = np.linalg.pinv(c) @ values
    return machine.volumetric_error(commands, p)


def predict_uncertainty(
    machine: Machine, calibration: Calibration, commands: Any, structure: Optional[ModelStructure] = None
) -> np.ndarray:
    """Standard uncertainty (n, 3), mm, of each predicted error component from the group
    covariance: sqrt(diag(M_L Sigma M_L^T)), with M_L the reduced design matrix (Eq. 3.14).
    The uncertainty of the groups the frame takes is a rigid motion and is not included."""
    st = structure if structure is not None else machine.structure()
    _coefficients(machine, calibration, st)
    if calibration.covariance is None:
        raise ConfigError("calibration has no covariance (written by an older gagekit?): identify again")
    cov = np.asarray(calibration.covariance, dtype=np.float64)
    if cov.shape != (st.rank, st.rank):
        raise ConfigError(f"calibration covariance is {cov.shape}, expected ({st.rank}, {st.rank})")
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
    target = machine.nominal(c0)
    coef = _coefficients(machine, calibration, st)
    p = np.linalg.pinv(coef) @ np.array([g.value for g in calibration.groups])
    c = c0.copy()
    n = c.shape[0]
    for _ in range(iterations):
        actual = machine.nominal(c) + machine.volumetric_error(c, p)
        miss = (actual - target).reshape(n, 3, 1)
        jac = machine.command_jacobian(c).reshape(n, 3, -1)[:, :, idx]
        step = np.linalg.pinv(jac) @ miss
        c[:, idx] -= step[:, :, 0]
    remaining = machine.nominal(c) + machine.volumetric_error(c, p) - target
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
