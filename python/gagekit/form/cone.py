"""Cones: least squares, minimum zone (conicity), minimum circumscribed and maximum
inscribed, with the half angle free or fixed (the dissertation's Sec. 7.2 item 6: conicity
by the projection model's machinery; issue 25 §3).

The deviation of a point is its distance **normal to the cone surface**, measured in the
point's axial half plane: with z the axial coordinate and rho the distance to the axis,
d = rho cos(psi) - z sin(psi) - D for the cone of half angle psi passing at normal distance
D from the axis point (positive away from the axis). The minimum zone is two coaxial cones
of the same half angle enclosing the points with the least normal separation -- the ISO
1101 profile of a conical surface without datums; its width is the conicity.

The result, :class:`ConeFit`, is the Rust object (``gagekit_form::result::ConeResult``).
"""

from __future__ import annotations

from typing import Any, Optional

from .. import _core
from .._core.form import ConeFit
from ..errors import ConfigError
from .fits import _points

__all__ = ["ConeFit", "fit_cone"]


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
    pts = _points(points, (3,), "cone")
    half = None
    if angle is not None:
        try:
            half = float(angle)
        except (TypeError, ValueError):
            raise ConfigError(f"cone: the half angle must be a number of degrees in (0, 90), got {angle!r}") from None
    return _core.form.fit_cone(pts, str(criterion), half)
