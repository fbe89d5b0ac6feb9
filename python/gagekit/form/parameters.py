"""Filtered form parameters, as a roundness instrument (Talyrond, MarForm) prints them.

- :func:`roundness_parameters`: RONt, RONp, RONv, RONq (ISO 12181-1:2011) of a closed
  profile, unfiltered or through the ISO 16610-21 Gaussian filter with its cut-off in
  undulations per revolution (ISO 12181-2: 15, 50, 150, 500, 1500 UPR), against the LSCI
  (default), MZCI, MCCI or MICI; eccentricity and the harmonic spectrum.
- :func:`straightness_parameters`: STRt, STRp, STRv, STRq (ISO 12780-1) of a 2-D profile,
  unfiltered or through the open-profile Gaussian filter (cut-off length, ends dropped) or
  the ISO 16610-22 cubic spline filter (nothing dropped).
- :func:`flatness_parameters`: FLTt, FLTp, FLTv, FLTq (ISO 12781-1), unfiltered.
- :func:`cylindricity_parameters`: CYLt, CYLp, CYLv (ISO 12180-1), unfiltered.
- :func:`gaussian_filter_closed`, :func:`gaussian_filter_open`, :func:`spline_filter_open`
  (ISO 16610-22 cubic spline, open profiles): the filters themselves.

How a scanned section is made evenly spaced (the filters need it): its least-squares
centre is found (the exact geometric fit), each point's angle and radius about it are
taken, and the radius is interpolated linearly in angle at ``samples`` equal angles
(default 3600, or ``7 UPR`` rounded up to a multiple of 360 when more). A gap wider than
``max_gap_deg`` (default two sampling intervals of ISO 12181-2's minimum of 7 points per
cut-off, ``720 / (7 UPR)`` degrees; unfiltered, the 15 UPR value 6.86 degrees) is refused,
not bridged, and a profile with fewer than ``7 UPR`` points is refused. The closed filter
is exact: harmonic ``k`` is multiplied by ``exp(-pi (alpha k / UPR)^2)``, ``alpha =
sqrt(ln 2 / pi)``, in the discrete Fourier transform. Unfiltered parameters are taken on
the measured points themselves; filtered ones on the filtered resampled profile. The
kernels are Rust (``gagekit_profile``), and the results are their Rust objects (getters and
``to_dict()`` in the binding); this module reads the arguments in.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .. import _core
from .._core.form import FlatnessParameters, RoundnessParameters, StraightnessParameters
from ..errors import ConfigError, InvalidInputError
from .fits import _points

__all__ = [
    "RoundnessParameters",
    "StraightnessParameters",
    "FlatnessParameters",
    "roundness_parameters",
    "straightness_parameters",
    "flatness_parameters",
    "cylindricity_parameters",
    "gaussian_filter_closed",
    "gaussian_filter_open",
    "spline_filter_open",
    "gaussian_transmission",
    "STANDARD_UPR",
    "ROUNDNESS_REFERENCES",
]

#: ISO 12181-2 cut-offs, undulations per revolution.
STANDARD_UPR = (15, 50, 150, 500, 1500)
#: ISO 12181-1 reference circles: least squares, minimum zone, minimum circumscribed,
#: maximum inscribed.
ROUNDNESS_REFERENCES = ("LSCI", "MZCI", "MCCI", "MICI")

_ALPHA = math.sqrt(math.log(2.0) / math.pi)


def gaussian_transmission(k: Any, upr: float) -> Any:
    """Amplitude kept of harmonic ``k`` through the Gaussian filter of ``upr`` UPR:
    ``exp(-pi (alpha k / upr)^2)`` (ISO 16610-21 Eq. 2; 0.5 at ``k = upr``)."""
    return np.exp(-math.pi * (_ALPHA * np.asarray(k, dtype=float) / float(upr)) ** 2)


def _filter_spec(filter: str, upr: Optional[float]) -> Optional[float]:
    kind = str(filter).strip().lower()
    if kind in ("none", "off", "unfiltered"):
        return None
    if kind not in ("gaussian", "gauss"):
        raise ConfigError(f"unknown filter {filter!r}; choose gaussian or none")
    if upr is None:
        raise ConfigError("a Gaussian filter needs its cut-off: upr (undulations per revolution, e.g. 50)")
    try:
        value = float(upr)
    except (TypeError, ValueError):
        raise InvalidInputError(f"upr must be a number of undulations per revolution, got {upr!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise InvalidInputError(
            f"upr must be a positive number of undulations per revolution (ISO 12181-2: 15, 50, 150, 500, 1500), got {upr!r}")
    return value


def _profile_points(points: Any) -> np.ndarray:
    pts = _points(points, (2, 3), "roundness")
    if pts.shape[1] == 3:
        const = [k for k in range(3) if np.ptp(pts[:, k]) == 0.0]
        if not const:
            raise InvalidInputError(
                "roundness: a profile is 2-D (x, y), or 3-D with one constant coordinate; project a section "
                "in any other pose into its plane first")
        pts = np.ascontiguousarray(np.delete(pts, const[-1], axis=1))
    return pts


def roundness_parameters(points: Any, filter: str = "gaussian", upr: Optional[float] = 50, reference: str = "LSCI",
                         samples: Optional[int] = None, max_gap_deg: Optional[float] = None,
                         harmonics: Optional[int] = None) -> RoundnessParameters:
    """RONt, RONp, RONv, RONq (ISO 12181-1) of a closed profile: ``filter`` ``"gaussian"``
    (ISO 16610-21, cut-off ``upr`` undulations per revolution) or ``"none"``; ``reference``
    LSCI, MZCI, MCCI or MICI. Bad input (too few points, a gap, NaN, ``upr <= 0``) raises a
    :class:`~gagekit.errors.GagekitError`."""
    u = _filter_spec(filter, upr)
    pts = _profile_points(points)
    for name, value in (("samples", samples), ("harmonics", harmonics)):
        if value is not None and (not isinstance(value, (int, np.integer)) or value < 1):
            raise InvalidInputError(f"{name} must be a positive integer, got {value!r}")
    return _core.form.roundness(pts, u, str(reference), samples, max_gap_deg, harmonics)


def straightness_parameters(points: Any, filter: str = "none", cutoff: Optional[float] = None, reference: str = "LSLI",
                            step: Optional[float] = None, max_gap: Optional[float] = None) -> StraightnessParameters:
    """STRt, STRp, STRv, STRq (ISO 12780-1) of (n, 2) points. ``filter="gaussian"`` with
    ``cutoff`` (mm): resampled at ``step`` (default the mean spacing, at most cutoff/7) and
    filtered (ISO 16610-21), one cut-off dropped at each end (ISO 16610-28);
    ``filter="spline"``: the ISO 16610-22 cubic spline filter, nothing dropped."""
    kind = str(filter).strip().lower()
    if kind in ("none", "off", "unfiltered"):
        lc = None
    elif kind in ("gaussian", "gauss", "spline"):
        if cutoff is None:
            raise ConfigError(f"a {kind} filter of an open profile needs its cut-off length (mm), e.g. 2.5")
        lc = float(cutoff)
    else:
        raise ConfigError(f"unknown filter {filter!r}; choose gaussian, spline or none")
    pts = _points(points, (2,), "straightness")
    return _core.form.straightness(pts, lc, str(reference), step, max_gap, kind == "spline")


def flatness_parameters(points: Any, reference: str = "LSPL", up: Optional[Any] = None) -> FlatnessParameters:
    """FLTt, FLTp, FLTv, FLTq (ISO 12781-1) of (n, 3) points, unfiltered."""
    pts = _points(points, (3,), "flatness")
    u = None if up is None else tuple(float(v) for v in up)
    return _core.form.flatness(pts, str(reference), u)


def cylindricity_parameters(points: Any, reference: str = "MZCY", seed: int = 0, **options: Any) -> dict[str, Any]:
    """CYLt (ISO 12180-1), with CYLp and CYLv, of (n, 3) points, unfiltered: the
    cylinder of ``reference`` (LSCY, MZCY, MCCY, MICY) by :func:`gagekit.fit_cylinder`;
    CYLp / CYLv are the largest distances outside / inside its radius (MZCY: its mean
    radius), CYLt their sum."""
    from .cylinder import fit_cylinder

    codes = {"LSCY": "least-squares", "MZCY": "minimum-zone", "MCCY": "min-circumscribed", "MICY": "max-inscribed"}
    key = str(reference).strip().upper()
    crit = codes.get(key, reference)
    fit = fit_cylinder(points, crit, seed=seed, **options)
    lo, hi = fit.certificate.min_distance, fit.certificate.max_distance
    radius = 0.5 * (lo + hi) if fit.criterion == "minimum-zone" else fit.radius
    p, v = max(hi - radius, 0.0), max(radius - lo, 0.0)
    name = {v_: k for k, v_ in codes.items()}[fit.criterion]
    return {"shape": "cylindricity", "n_points": fit.n_points, "filter": {"type": "none"}, "reference": name,
            "parameters": {"CYLt": p + v, "CYLp": p, "CYLv": v},
            "reference_cylinder": {"axis_point": list(fit.point), "axis_direction": list(fit.direction), "radius": radius},
            "warnings": list(fit.warnings), "units": "mm"}


def gaussian_filter_closed(radii: Any, upr: float) -> np.ndarray:
    """The ISO 16610-21 Gaussian mean line of a closed profile sampled at equal angles
    (exact: harmonic ``k`` times :func:`gaussian_transmission`)."""
    r = np.ascontiguousarray(np.asarray(radii, dtype=np.float64).ravel())
    return np.asarray(_core.form.profile_gaussian_closed(r, float(upr)))


def spline_filter_open(values: Any, step: float, cutoff: float) -> np.ndarray:
    """The ISO 16610-22 cubic spline mean line of an open profile sampled at ``step``
    (every sample: a straight profile is its own mean line, no end effects to drop)."""
    z = np.ascontiguousarray(np.asarray(values, dtype=np.float64).ravel())
    return np.asarray(_core.form.profile_spline_open(z, float(step), float(cutoff)))


def gaussian_filter_open(values: Any, step: float, cutoff: float) -> tuple[int, np.ndarray]:
    """The ISO 16610-21 Gaussian mean line of an open profile sampled at ``step``:
    ``(first, filtered)``, the filtered values of samples ``first .. n - first`` (one
    cut-off dropped at each end)."""
    z = np.ascontiguousarray(np.asarray(values, dtype=np.float64).ravel())
    first, out = _core.form.profile_gaussian_open(z, float(step), float(cutoff))
    return int(first), np.asarray(out)
