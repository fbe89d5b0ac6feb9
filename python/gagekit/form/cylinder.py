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
import warnings as _warnings
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError
from .criteria import SHAPE_CRITERIA, criterion_name
from .fits import Certificate, _cert, _fit_dict, _points, _radii, _vec
from .search import DEFAULT_MAX_TILT, outside_warning, search_settings

__all__ = ["CylinderFit", "fit_cylinder", "axis_angles", "DEFAULT_MAX_TILT"]

_ALLOWED = SHAPE_CRITERIA["cylinder"]


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

    ``arc_deg`` is the angle the points cover around the axis; ``warnings`` says when the
    fit is poorly determined (``ill_posed`` for a maximum inscribed cylinder of an arc
    below 90 degrees, Sec. 6.2.2).

    ``radius`` is the fitted radius (least squares, circumscribed, inscribed); for the
    minimum zone ``inner_radius`` / ``outer_radius`` bound the zone and ``radius`` is their
    mean. ``form_error`` is the cylindricity about this axis (max - min distance to the
    axis; the zone width for the minimum zone). ``certificate``: min and max distance of
    the input points to the reported axis, recomputed in 3-D.
    """

    criterion: str
    n_points: int
    point: tuple[float, float, float]
    direction: tuple[float, float, float]
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
    arc_deg: float = 360.0
    ill_posed: bool = False
    warnings: tuple[str, ...] = ()
    tilt_deg: Optional[float] = None
    reference_axis: Optional[tuple[float, float, float]] = None
    warm_fallback: Optional[bool] = None
    shape: str = field(default="cylinder", init=False)

    @property
    def axis_point(self) -> tuple[float, float, float]:
        """Deprecated alias of :attr:`point` (the JSON key stays ``axis_point``)."""
        _warnings.warn("CylinderFit.axis_point is deprecated; use point", DeprecationWarning, stacklevel=2)
        return self.point

    @property
    def axis_direction(self) -> tuple[float, float, float]:
        """Deprecated alias of :attr:`direction` (the JSON key stays ``axis_direction``)."""
        _warnings.warn("CylinderFit.axis_direction is deprecated; use direction", DeprecationWarning, stacklevel=2)
        return self.direction

    def to_dict(self) -> dict[str, Any]:
        d = _fit_dict(
            self,
            **_radii(self),
            axis_point=list(self.point),
            axis_direction=list(self.direction),
            theta=self.theta,
            phi=self.phi,
            control_points=list(self.control_points),
        )
        if self.criterion != "least-squares":
            d["iterations"] = self.iterations
            d["evaluations"] = self.evaluations
            d["tilt_deg"] = self.tilt_deg
        d["arc_deg"] = self.arc_deg
        d["ill_posed"] = self.ill_posed
        d["warnings"] = list(self.warnings)
        return d


def fit_cylinder(
    points: Any,
    criterion: str = "least-squares",
    seed: int = 0,
    *,
    particles: int = 20,
    iterations: int = 300,
    stall_iterations: int = 6,
    refine_starts: int = 8,
    hop_rounds: int = 3,
    axis: Optional[Any] = None,
    max_tilt: float = DEFAULT_MAX_TILT,
    warm: Optional[tuple[Any, Any]] = None,
) -> CylinderFit:
    """Fit a cylinder to (n, 3) points (mm).

    Parameters
    ----------
    criterion
        ``least-squares`` (``lsq``): orthogonal distances, Levenberg-Marquardt from the
        principal axes (matches the NIST reference fits).
        ``min-circumscribed`` (``mcc``, Eq. 6.13), ``max-inscribed`` (``mic``, Eq. 6.15),
        ``minimum-zone`` (``mzc``, cylindricity, Eq. 6.14): the projection model of
        Sec. 6.3 -- the points are projected along the axis (theta, phi) by Eq. 6.12
        (ERRATA item 1) and the 2-D set is fitted exactly (MC, MI within MC, MZ); a seeded
        parallel PSO searches (theta, phi) (the least-squares axis is one particle), and
        local searches by sequential linear programming on the same minimax problem
        (Eqs. 6.13-6.15, in axis tilt, axis offset and radii) refine the best particles
        to double precision; every candidate axis is scored by the exact 2-D fit.
    seed
        Seed of the swarm: the same seed gives the same result on any number of threads.
    particles, iterations, stall_iterations
        Swarm size, maximum iterations and the number of iterations without improvement
        after which the swarm stops (the dissertation uses 20 particles, 2000 iterations).
    refine_starts
        Local searches from this many of the swarm's best distinct particles.
    hop_rounds
        Rounds of basin hopping: 8 local searches restarted 1e-4 rad around the best axis,
        repeated while they improve it (minimum-zone landscapes have long narrow valleys
        with several local minima some 1e-5 rad apart). 0 disables.
    axis, max_tilt
        The Chebyshev fits (MCC, MIC, MZC) search axis directions within ``max_tilt``
        degrees (default 10) of a reference axis: the nominal ``axis`` (x, y, z) when
        given, else the least-squares axis. ``max_tilt=0`` fixes the orientation;
        ``max_tilt=90`` searches the whole upper half sphere (theta in [0, pi/2], phi in
        [-pi, pi], Sec. 6.4) -- deterministically: the exact objective on a grid of 469
        directions (tilt every 7.5 degrees), local searches from its 12 best distinct
        directions, and the seeded swarm's optimum only where it is lower by more than
        1e-9 of the part's size, so the seed does not change the result. Over all orientations, the minimum circumscribed cylinder of
        a short bore can lie across the bore, a size with no meaning for the feature. The
        result reports ``tilt_deg``, the angle between the fitted and the reference axis;
        when the free search finds a better optimum outside the cone, ``warnings`` gives
        its value (a better one inside the cone replaces the result).
    warm
        (point, direction) of the axis of a fit of nearby points -- a Monte Carlo trial
        starts from the measured fit: the exact local method (the 2-D fit along that
        direction, the SLP local search, basin hopping) runs from it, above 2000 points on
        an active subset grown until every point lies inside the fitted cylinder(s), and
        the global search above runs only when the local method cannot decide (the axis
        on the cone's boundary, no convergence, the MIC of a partial arc);
        ``warm_fallback`` says which. The free search outside the cone is skipped (no
        ``outside`` warning). Least squares: Levenberg-Marquardt from that direction
        alone (not from the principal axes too).

    Returns
    -------
    CylinderFit
        With the certificate: min / max distance of the points to the reported axis,
        recomputed in 3-D.

    Raises
    ------
    InvalidInputError, DegenerateGeometryError, ConfigError
    """
    crit = criterion_name(criterion, _ALLOWED, "cylinder")
    pts = _points(points, (3,), "cylinder")
    nominal, tilt_rad = search_settings(axis, max_tilt, "cylinder")
    start = None
    if warm is not None:
        try:
            wp, wd = (tuple(float(x) for x in np.asarray(v, dtype=float).reshape(3)) for v in warm)
        except (TypeError, ValueError):
            raise ConfigError(f"cylinder: warm must be (point, direction), two 3-vectors, got {warm!r}") from None
        start = (wp, wd)
    if crit == "least-squares":
        ls = _core.form_cylinder_lsq(pts, None, None if start is None else start[1])
        arc = math.degrees(ls.arc)
        # the angles of the least-squares axis as numpy computed them before the kernel
        # returned complete fits (its BLAS norm can differ from nalgebra's by an ulp, and
        # the JSON stays byte-identical); the minimax cylinders report the kernel's
        theta, phi = axis_angles(ls.direction)
        return CylinderFit(
            crit, len(pts), _vec(ls.point), _vec(ls.direction), theta, phi, float(ls.radius),
            float(ls.form_error), _cert(ls),
            arc_deg=float(arc), warnings=tuple(_arc_warnings(crit, arc)),
        )
    for name, v in (("particles", particles), ("iterations", iterations), ("stall_iterations", stall_iterations), ("refine_starts", refine_starts), ("hop_rounds", hop_rounds)):
        if int(v) < (1 if name == "particles" else 0):
            raise ConfigError(f"cylinder: {name} must be a positive integer, got {v}")
    if seed < 0:
        raise ConfigError(f"cylinder: seed must be a non-negative integer, got {seed}")
    r = _core.form_cylinder_fit(
        pts, crit, int(seed), int(particles), int(iterations), int(stall_iterations),
        nominal, tilt_rad, int(refine_starts), int(hop_rounds), start,
    )
    cert = _cert(r)
    if crit == "min-circumscribed":
        radius, form_error, control = r.r_out, cert.max_distance - cert.min_distance, r.control_out
        inner = outer = None
    elif crit == "max-inscribed":
        radius, form_error, control = r.r_in, cert.max_distance - cert.min_distance, r.control_in
        inner = outer = None
    else:
        radius, inner, outer = r.radius, r.r_in, r.r_out
        form_error = outer - inner
        control = list(r.control_in) + [i for i in r.control_out if i not in r.control_in]
    arc = math.degrees(r.arc)
    warnings = _arc_warnings(crit, arc)
    if r.at_limit:
        warnings.append(
            f"the axis lies on the boundary of the search cone (max_tilt = {float(max_tilt):g} degrees from the "
            "reference axis): the points alone would tilt it further; give the nominal axis (axis=...) or check the data"
        )
    if r.outside is not None:
        warnings.append(outside_warning(crit, r.outside, max_tilt))
    return CylinderFit(
        crit, len(pts), _vec(r.point), _vec(r.direction), float(r.theta), float(r.phi),
        float(radius), float(form_error), cert,
        inner_radius=None if inner is None else float(inner),
        outer_radius=None if outer is None else float(outer),
        control_points=tuple(int(i) for i in control),
        iterations=int(r.iterations),
        evaluations=int(r.evaluations),
        arc_deg=float(arc),
        ill_posed=bool(r.ill_posed),
        warnings=tuple(warnings),
        tilt_deg=math.degrees(r.tilt),
        reference_axis=_vec(r.reference),
        warm_fallback=r.warm_fallback,
    )


#: Below this arc (degrees) around the axis a maximum inscribed cylinder is ill-posed
#: (the kernel's constant, gagekit-form ``cylinder::MIN_ARC``).
MIN_ARC_DEG = _core.CYLINDER_MIN_ARC_DEG


def _arc_warnings(crit: str, arc: float) -> list[str]:
    warnings: list[str] = []
    if arc < MIN_ARC_DEG:
        if crit == "max-inscribed":
            warnings.append(
                f"the points cover only {arc:.1f} degrees around the axis (< {MIN_ARC_DEG:.0f}): the "
                "maximum inscribed cylinder is ill-posed and its radius is not a meaningful size"
            )
        else:
            warnings.append(f"the points cover only {arc:.1f} degrees around the axis: axis and radius are poorly determined")
    return warnings
