"""The result of an identification (Tables 3.2-3.5): group estimates, residual statistics,
the calibration JSON and its reader."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .._util import dumps
from ..errors import FileFormatError
from .frame import Frame

__all__ = ["ResidualStats", "GroupEstimate", "Calibration", "load_calibration", "NOISE_FLOOR_FACTOR"]

#: Mean length of a 3-D vector of independent N(0, sigma) coordinates, in sigma: 2 sqrt(2/pi).
NOISE_FLOOR_FACTOR = 2.0 * math.sqrt(2.0 / math.pi)


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

        write_text(path, dumps(self) + "\n")  # atomic: temp file in the same folder, then rename

    @classmethod
    def from_dict(cls, d: dict) -> "Calibration":
        try:
            groups = tuple(
                GroupEstimate(
                    name=g["name"],
                    leader=_name(g.get("leader", next(iter(g["terms"])))),
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


def _name(v: Any) -> str:
    """A parameter name read from a calibration file (anything else: TypeError, reported
    by :meth:`Calibration.from_dict` as a damaged file)."""
    if not isinstance(v, str):
        raise TypeError(f"expected a parameter name, got {v!r}")
    return v
