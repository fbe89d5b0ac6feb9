"""Where the Chebyshev fits of an axis search (issue 13): within ``max_tilt`` degrees of a
reference axis -- a nominal axis, else the least-squares one."""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError

__all__ = ["DEFAULT_MAX_TILT", "search_settings", "outside_warning"]

#: Default largest tilt (degrees) of a Chebyshev fit's axis from its reference axis (the
#: kernel's constant, gagekit-form ``cylinder::DEFAULT_MAX_TILT``, in degrees).
DEFAULT_MAX_TILT = _core.form.DEFAULT_MAX_TILT_DEG


def search_settings(axis: Any, max_tilt: Any, shape: str) -> tuple[Optional[tuple[float, float, float]], float]:
    """The nominal axis (3 floats or None) and ``max_tilt`` in rad, checked: the axis must
    have 3 finite components and a non-zero length, ``max_tilt`` lie in [0, 90] degrees."""
    try:
        t = float(max_tilt)
    except (TypeError, ValueError):
        raise ConfigError(f"{shape}: max_tilt must be a number of degrees in [0, 90], got {max_tilt!r}") from None
    if not (0.0 <= t <= 90.0):
        raise ConfigError(f"{shape}: max_tilt must be between 0 and 90 degrees, got {max_tilt!r}")
    if axis is None:
        nominal = None
    else:
        try:
            a = np.asarray(axis, dtype=float).ravel()
        except (TypeError, ValueError):
            raise ConfigError(f"{shape}: axis must be three numbers (x, y, z), got {axis!r}") from None
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ConfigError(f"{shape}: axis must be three finite numbers (x, y, z), got {axis!r}")
        if not np.any(a):
            raise ConfigError(f"{shape}: the axis {tuple(a.tolist())} has zero length; give a direction such as (0, 0, 1)")
        nominal = (float(a[0]), float(a[1]), float(a[2]))
    return nominal, (math.pi / 2 if t == 90.0 else math.radians(t))


def outside_warning(crit: str, outside: Any, max_tilt: float) -> str:
    """The warning for a better optimum of the free search outside the cone."""
    what = "zone width" if crit == "minimum-zone" else "radius"
    return (
        f"a search over all orientations finds a better {crit} {what}, {outside.value:.9g} mm, "
        f"with the axis {math.degrees(outside.tilt):.2f} degrees from the reference axis, outside "
        f"max_tilt = {float(max_tilt):g} degrees (it is not reported; pass max_tilt=90 to accept it)"
    )


