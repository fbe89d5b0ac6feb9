"""Optimal error observers for a machine tool (Sec. 4.2, 4.3.1) and their simulated worth,
one job per module:

- :mod:`.space`: design variables, bounds and scaled model rows (``ObserverSpace``);
- :mod:`.zones`: the dissertation-8 zones, zones and exclusions files;
- :mod:`.design`: optimal plans (``design_observer``, ``ObserverPlan``);
- :mod:`.evaluate`: the simulation study (``evaluate_plan``, ``PlanEvaluation``).
"""

from __future__ import annotations

from .design import DEFAULT_CRITERION, DEFAULT_ZONES, FULL_SET, ObserverPlan, design_observer
from .evaluate import PlanEvaluation, evaluate_plan, prediction_rms
from .space import ObserverSpace
from .zones import Exclusions, Zone, dissertation_zones, read_exclusions, read_zones

__all__ = [
    "ObserverSpace",
    "ObserverPlan",
    "PlanEvaluation",
    "design_observer",
    "evaluate_plan",
    "dissertation_zones",
    "read_zones",
    "read_exclusions",
    "DEFAULT_CRITERION",
    "DEFAULT_ZONES",
    "FULL_SET",
    "Exclusions",
    "Zone",
    "prediction_rms",
]
