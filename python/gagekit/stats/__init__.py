"""Statistical process control of the results database: capability (ISO 22514-2, AIAG),
individuals / moving-range charts with the Western Electric rules, trends over time, and
machines' parameter drift across calibrations (Fig. 4.8 across days)."""

from .collect import characteristic, collect
from .spc import D2, D4, RULES, Capability, ImrChart, Signal, capability, imr_chart, trend_per_day, western_electric

__all__ = ["D2", "D4", "RULES", "Capability", "ImrChart", "Signal", "capability", "characteristic", "collect",
           "imr_chart", "trend_per_day", "western_electric"]
