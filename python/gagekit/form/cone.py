"""Cones: least squares, minimum zone (conicity), minimum circumscribed and maximum
inscribed, with the half angle free or fixed (the dissertation's Sec. 7.2 item 6: conicity
by the projection model's machinery; issue 25 §3).

The deviation of a point is its distance **normal to the cone surface**, measured in the
point's axial half plane: with z the axial coordinate and rho the distance to the axis,
d = rho cos(psi) - z sin(psi) - D for the cone of half angle psi passing at normal distance
D from the axis point (positive away from the axis). The minimum zone is two coaxial cones
of the same half angle enclosing the points with the least normal separation -- the ISO
1101 profile of a conical surface without datums; its width is the conicity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

from .. import _core
from ..errors import ConfigError
from .criteria import SHAPE_CRITERIA, criterion_name
from .fits import Certificate, _cert, _fit_dict, _points, _radii, _vec

__all__ = ["ConeFit", "fit_cone"]


@dataclass(frozen=True)
class ConeFit:
    """A fitted cone.

    ``point`` is the axis point of the **reference section** (the plane normal to the axis
    through the foot of the points' centroid), ``direction`` the unit axis along which the
    radius grows, ``apex`` the cone's apex, ``half_angle`` the half apex angle (rad; JSON
    also ``half_angle_deg`` and the full ``apex_angle``), ``radius`` the radius at the
    reference section (least squares, circumscribed, inscribed; for the minimum zone the
    mean of ``inner_radius`` and ``outer_radius``, the zone's two cones there) and
    ``distance`` = radius cos(half_angle), the normal distance from ``point`` to the cone.
    ``form_error``: the normal width of the points about this cone (the zone width for the
    minimum zone). ``certificate``: min / max signed normal deviation, recomputed from the
    reported cone. ``gap`` (Chebyshev cones): the decrease a linear step of the local
    search predicts within 1e-7 of the part's size about the result -- 0 certifies a local
    optimum to first order (mm).
    """

    criterion: str
    n_points: int
    point: tuple[float, float, float]
    direction: tuple[float, float, float]
    apex: tuple[float, float, float]
    half_angle: float
    radius: float
    distance: float
    form_error: float
    certificate: Certificate
    fixed_angle: bool = False
    inner_radius: Optional[float] = None
    outer_radius: Optional[float] = None
    control_points: tuple[int, ...] = ()
    gap: float = 0.0
    evaluations: int = 0
    shape: str = field(default="cone", init=False)

    @property
    def apex_angle(self) -> float:
        """The full apex angle (rad)."""
        return 2.0 * self.half_angle

    def radius_at(self, z: float) -> float:
        """Radius of the cone at axial coordinate ``z`` (mm, along ``direction``) from the
        reference section."""
        return self.radius + z * math.tan(self.half_angle)

    def to_dict(self) -> dict[str, Any]:
        d = _fit_dict(
            self,
            **_radii(self),
            axis_point=list(self.point),
            axis_direction=list(self.direction),
            apex=list(self.apex),
            half_angle=self.half_angle,
            half_angle_deg=math.degrees(self.half_angle),
            apex_angle=self.apex_angle,
            distance=self.distance,
            fixed_angle=self.fixed_angle,
        )
        if self.criterion != "least-squares":
            d["control_points"] = list(self.control_points)
            d["gap"] = self.gap
            d["evaluations"] = self.evaluations
        return d


def fit_cone(points: Any, criterion: str = "least-squares", *, angle: Optional[float] = None) -> ConeFit:
    """Fit a cone to (n, 3) points (mm).

    Parameters
    ----------
    criterion
        ``least-squares`` (``lsq``): the sum of squared normal deviations (Forbes'
        parametrisation, Levenberg-Marquardt from algebraic cones about the principal
        axes; as the NIST reference fits define it). ``minimum-zone`` (``mz``, conicity):
        two coaxial cones of one half angle enclosing the points with the least normal
        separation. ``min-circumscribed`` (``mc``) / ``max-inscribed`` (``mi``): the cone
        containing every point of least radius at the reference section / containing no
        point of greatest radius there (with a fixed angle every section gives the same
        cone). With a free angle the MC / MI cone need not be unique: when fewer than six
        points touch it, optima form a ridge along which the radius changes by ~1e-9 of the
        part's size while the angle moves by ~1e-4 degrees; the radius is then determined,
        the angle (and the form about it) only to that level -- fix the angle (``angle``)
        for a unique cone. The Chebyshev cones are found as the cylinders are (Sec. 6.3): sequential
        linear programming on the minimax problem in axis offset, tilt, half angle and
        radii from the least-squares cone, with basin hopping; deterministic.
    angle
        Fix the **half** apex angle to this many degrees, strictly between 0 and 90
        (default: free).

    Raises
    ------
    InvalidInputError
        fewer than 6 points, NaN / infinite coordinates.
    DegenerateGeometryError
        coincident, collinear or coplanar points; points on a cylinder (a free half angle
        below 1e-7 rad) or a plane.
    ConfigError
        an unknown criterion, a half angle outside (0, 90) degrees.
    """
    crit = criterion_name(criterion, SHAPE_CRITERIA["cone"], "cone")
    pts = _points(points, (3,), "cone")
    half = None
    if angle is not None:
        try:
            deg = float(angle)
        except (TypeError, ValueError):
            raise ConfigError(f"cone: the half angle must be a number of degrees in (0, 90), got {angle!r}") from None
        if not (0.0 < deg < 90.0):
            raise ConfigError(f"cone: the half angle must lie strictly between 0 and 90 degrees, got {angle!r}")
        half = math.radians(deg)
    c = _core.form.cone_fit(pts, crit, half)
    zone = crit == "minimum-zone"
    control = list(c.control_in) + [i for i in c.control_out if i not in c.control_in]
    return ConeFit(
        crit, len(pts), _vec(c.point), _vec(c.direction), _vec(c.apex), float(c.half_angle), float(c.radius),
        float(c.distance), float(c.form_error), _cert(c), fixed_angle=bool(c.fixed_angle),
        inner_radius=float(c.r_in) if zone else None, outer_radius=float(c.r_out) if zone else None,
        control_points=tuple(int(i) for i in control), gap=float(c.gap), evaluations=int(c.evaluations),
    )
