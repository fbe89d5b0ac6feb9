"""The schema of a ``[measurement]`` table: an instrument's error model (JCGM 101 Monte Carlo).

A table of its own file or of a PART.toml / gage file (``--measurement FILE``); read by
:func:`gagekit.uncertainty.model.measurement_model`, whose keys (``MODEL_KEYS``) these are.
"""

from __future__ import annotations

from typing import Literal, Optional, Union

from ._engine import Table
from ._types import NonNegative, Vec3

__all__ = ["MeasurementTable"]



class MeasurementTable(Table):
    """``[measurement]``: the instrument's error model, lengths mm."""

    sigma: Union[NonNegative, Literal["auto"], None] = None
    """Per-point noise (mm; each coordinate N(0, sigma^2), along the line of sight with origin), or "auto"."""
    origin: Optional[Vec3] = None
    """The scanner's position [x, y, z] (mm): noise and offset along the line of sight."""
    sigma_per_m: Optional[NonNegative] = None
    """Added noise per metre of range (mm/m), with origin."""
    probing: Optional[NonNegative] = None
    """Probing form error P_FTU (ISO 10360-5), mm."""
    scale_ppm: Optional[NonNegative] = None
    """Length-dependent part of MPE_E, um/m (uniform +-)."""
    cte: Optional[NonNegative] = None
    """Coefficient of thermal expansion, 1/K."""
    delta_t: Optional[NonNegative] = None
    """Half-width of the temperature deviation from 20 C, K (uniform +-)."""
    offset: Optional[NonNegative] = None
    """Standard uncertainty of a systematic offset, mm."""
