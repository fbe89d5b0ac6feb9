"""Thermal error tracking (Sec. 4.3.2-4.3.4), one job per module:

- :mod:`.cycles`: the cycles CSV (``Cycles``, ``read_cycles``);
- :mod:`.track`: tracking and the temperature model (``track``, ``TrackResult``);
- :mod:`.history`: the per-machine SQLite history (``History``, ``read_history``);
- :mod:`.simulate`: the simulator's thermal mode (``simulate_cycles``).

The drift figure (Fig. 4.8) is drawn by :mod:`gagekit.report.machine`.
"""

from __future__ import annotations

from typing import Any

from .cycles import Cycles, read_cycles
from .history import History, read_history
from .simulate import HEAT_PROFILE, simulate_cycles
from .track import TrackResult, track

__all__ = ["Cycles", "TrackResult", "read_cycles", "track", "History", "read_history", "simulate_cycles", "plot_drift", "drift_figure", "HEAT_PROFILE"]


def __getattr__(name: str) -> Any:
    # The figures live in report/ (plotting only there); kept importable from here.
    if name in ("plot_drift", "drift_figure"):
        from ...report import machine as _report

        return getattr(_report, name)
    raise AttributeError(name)
