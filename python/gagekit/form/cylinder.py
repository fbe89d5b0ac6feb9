"""Cylinders: least squares, minimum circumscribed (MCC), maximum inscribed (MIC) and
minimum zone (MZC) by the projection model of Sec. 6.3.

The axis direction is a = (sin t cos f, sin t sin f, cos t) with the polar angle
t in [0, pi/2] and the azimuth f in [-pi, pi] (the half sphere, Tables 6.2/6.4);
the points are projected along it by q = [I2 0] Ry(-t) Rz(-f) p (Eq. 6.12 as
corrected in ERRATA item 1), and the projected 2-D set is fitted exactly
(Eqs. 6.13-6.15).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from .fits import Certificate, _points, _vec, normalize_criterion

__all__ = ["CylinderFit", "fit_cylinder", "axis_angles"]

_ALLOWED = ("least-squares", "min-circumscribed", "max-inscribed", "minimum-zone")


def axis_angles(direction: Any) -> tuple[float, float]:
    """(theta, phi) of a direction, flipped into the upper half sphere (theta <= pi/2)."""
    a = np.asarray(direction, dtype=float)
    a = a / np.linalg.norm(a)
    if a[2] < 0 or (a[2] == 0 and (a[1] < 0 or (a[1] == 0 and a[0] < 0))):
        a = -a
    return float(math.acos(min(1.0, max(-1.0, a[2])))), float(math.atan2(a[1], a[0]))


@dataclass(frozen=True)
class CylinderFit:
    """A fitted cylinder.

    ``radius`` is the fitted radius (least squares, circumscribed, inscribed); for the
    minimum zone ``inner_radius`` / ``outer_radius`` bound the zone and ``radius`` is their
    mean. ``form_error`` is the cylindricity about this axis (max - min distance to the
    axis; the zone width for the minimum zone). ``certificate``: min and max distance of
    the input points to the reported axis, recomputed in 3-D.
    """

    criterion: str
    n_points: int
    axis_point: tuple[float, float, float]
    axis_direction: tuple[float, float, float]
    theta: float
    phi: float
    radius: float
    form_error: float
    certificate: Certificate
    inner_radius: Optional[float] = None
    outer_radius: Optional[float] = None
    control_points: tuple[int, ...] = ()
    iterations: int = 0
    evaluations: int = 0
    shape: str = field(default="cylinder", init=False)

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "shape": self.shape,
            "criterion": self.criterion,
            "n_points": self.n_points,
            "form_error": self.form_error,
            "radius": self.radius,
        }
        if self.criterion == "minimum-zone":
            d["inner_radius"] = self.inner_radius
            d["outer_radius"] = self.outer_radius
        d.update(
            axis_point=list(self.axis_point),
            axis_direction=list(self.axis_direction),
            theta=self.theta,
            phi=self.phi,
            control_points=list(self.control_points),
            certificate=self.certificate.to_dict(),
        )
        if self.criterion != "least-squares":
            d["iterations"] = self.iterations
            d["evaluations"] = self.evaluations
        return d


def fit_cylinder(points: Any, criterion: str = "least-squares", seed: int = 0) -> CylinderFit:
    """Fit a cylinder to (n, 3) points.

    criterion: ``least-squares`` (``lsq``; orthogonal distances, Levenberg-Marquardt from the
    principal axes), ``min-circumscribed`` (``mcc``, Eq. 6.13), ``max-inscribed`` (``mic``,
    Eq. 6.15) or ``minimum-zone`` (``mzc``, Eq. 6.14). ``seed`` fixes the particle swarm.
    """
    crit = normalize_criterion(criterion, _ALLOWED, "cylinder")
    pts = _points(points, (3,), "cylinder")
    point, direction, radius, ext = _core.form_cylinder_lsq(pts)
    cert = Certificate(float(ext[0]), float(ext[1]))
    theta, phi = axis_angles(direction)
    return CylinderFit(
        crit, len(pts), _vec(point), _vec(direction), theta, phi, float(radius),
        cert.max_distance - cert.min_distance, cert,
    )
