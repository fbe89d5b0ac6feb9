"""Where the Chebyshev fits of an axis search (issue 13): within ``max_tilt`` degrees of a
reference axis -- a nominal axis, else the least-squares one. The range and the axis are
checked, and the degrees converted, by the kernel (``gagekit_form::cylinder::Search``)."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError

__all__ = ["DEFAULT_MAX_TILT", "search_settings"]

#: Default largest tilt (degrees) of a Chebyshev fit's axis from its reference axis (the
#: kernel's constant, gagekit-form ``cylinder::DEFAULT_MAX_TILT``, in degrees).
DEFAULT_MAX_TILT = _core.form.DEFAULT_MAX_TILT_DEG


def search_settings(axis: Any, max_tilt: Any, shape: str) -> tuple[Optional[tuple[float, float, float]], float]:
    """The nominal axis (3 floats or None) and ``max_tilt`` (degrees) as numbers for the
    kernel, or a :class:`ConfigError` when they cannot be read as such."""
    try:
        t = float(max_tilt)
    except (TypeError, ValueError):
        raise ConfigError(f"{shape}: max_tilt must be a number of degrees in [0, 90], got {max_tilt!r}") from None
    if axis is None:
        return None, t
    try:
        a = np.asarray(axis, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ConfigError(f"{shape}: axis must be three numbers (x, y, z), got {axis!r}") from None
    if a.shape != (3,):
        raise ConfigError(f"{shape}: axis must be three finite numbers (x, y, z), got {axis!r}")
    return (float(a[0]), float(a[1]), float(a[2])), t
