"""The inspection result: every callout's measured value against its tolerance."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["CalloutResult", "InspectionResult"]


@dataclass(frozen=True)
class CalloutResult:
    """One callout: ``measured`` (mm) against ``tolerance`` (mm); ``zone`` says whether both
    are a width or a diameter; ``margin = tolerance - measured`` (negative when it fails)."""

    feature: str
    characteristic: str
    tolerance: float
    measured: float
    zone: str
    datums: tuple[str, ...]
    n_points: int
    element: str
    name: str = ""
    angle: float | None = None
    details: dict = field(default_factory=dict)
    #: the margin of a two-sided callout (size, distance, angle) or of a zone with a
    #: material bonus, else ``None`` (``tolerance - measured``)
    margin_value: float | None = None
    #: further top-level JSON keys: ``upper_limit``, ``lower_limit``, ``local_sizes``, ``bonus``, ...
    extra: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        if self.margin_value is not None:
            return self.margin_value >= 0.0
        return self.measured <= self.tolerance

    @property
    def margin(self) -> float:
        if self.margin_value is not None:
            return self.margin_value
        return self.tolerance - self.measured

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "feature": self.feature,
            "characteristic": self.characteristic,
            "tolerance": self.tolerance,
            "measured": self.measured,
            "pass": self.passed,
            "margin": self.margin,
            "datums": list(self.datums),
            "n_points": self.n_points,
            "zone": self.zone,
            "toleranced_element": self.element,
        }
        if self.name:
            d["name"] = self.name
        if self.angle is not None:
            d["angle"] = self.angle
        d.update(self.extra)
        if self.details:
            d["details"] = self.details
        return d


@dataclass(frozen=True)
class InspectionResult:
    """Datums as simulated, the main datum frame, every callout, the features' fits."""

    part: str
    n_points: int
    datums: tuple[Any, ...]
    frame: Any
    frames: tuple[Any, ...]
    tolerances: tuple[CalloutResult, ...]
    features: dict[str, Any]
    seconds: float = 0.0
    feature_data: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def deviations(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Each feature's points and their signed deviations from its least-squares fit
        (computed on first use, for the report's 3-D view)."""
        return {n: (fd.points, fd.deviations()) for n, fd in self.feature_data.items()}

    @property
    def status(self) -> str:
        return "conforming" if all(t.passed for t in self.tolerances) else "nonconforming"

    def to_dict(self) -> dict[str, Any]:
        return {
            "part": self.part,
            "n_points": self.n_points,
            "status": self.status,
            "datums": [d.to_dict() for d in self.datums],
            "frame": None if self.frame is None else self.frame.to_dict(),
            "frames": [f.to_dict() for f in self.frames],
            "tolerances": [t.to_dict() for t in self.tolerances],
            "features": {k: v.to_dict() for k, v in self.features.items()},
            "seconds": self.seconds,
        }
