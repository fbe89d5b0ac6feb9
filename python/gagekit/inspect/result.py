"""The inspection result: every callout's measured value against its tolerance."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

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
    #: the Monte Carlo uncertainty of ``measured`` (:mod:`gagekit.uncertainty`), when computed
    uncertainty: Optional[dict] = None
    #: the uncertainty of ``margin`` (two limits or a material bonus), when computed
    margin_uncertainty: Optional[dict] = None
    #: ISO 14253-1 decision (conforming, not-proven, nonconforming) under the result's rule
    decision: Optional[str] = None

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
        if self.uncertainty is not None:
            d["uncertainty"] = self.uncertainty
        if self.margin_uncertainty is not None:
            d["margin_uncertainty"] = self.margin_uncertainty
        d["decision"] = self.decision if self.decision is not None else ("conforming" if self.passed else "nonconforming")
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
    #: the decision rule (:class:`gagekit.uncertainty.DecisionRule`); None: simple
    decision_rule: Any = None
    #: how the Monte Carlo uncertainty was computed (settings, model), when it was
    monte_carlo: Optional[dict] = None

    @property
    def rule(self) -> Any:
        from ..uncertainty.decision import parse_decision_rule

        return self.decision_rule if self.decision_rule is not None else parse_decision_rule(None, False)

    @property
    def decision(self) -> str:
        """The part's decision: its worst callout's under :attr:`rule` (ISO 14253-1)."""
        from ..uncertainty.decision import worst_decision

        return worst_decision(t.to_dict()["decision"] for t in self.tolerances)

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
            "decision_rule": self.rule.to_dict(),
            "decision": self.decision,
            "tolerances": [t.to_dict() for t in self.tolerances],
            "features": {k: v.to_dict() for k, v in self.features.items()},
            "seconds": self.seconds,
            **({} if self.monte_carlo is None else {"monte_carlo": self.monte_carlo}),
        }
