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
from dataclasses import dataclass, field, replace
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError
from .fits import Certificate, _fit_dict, _points, _vec, normalize_criterion

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
    arc_deg: float = 360.0
    ill_posed: bool = False
    warnings: tuple[str, ...] = ()
    shape: str = field(default="cylinder", init=False)

    def to_dict(self) -> dict[str, Any]:
        radii: dict[str, Any] = {"radius": self.radius}
        if self.criterion == "minimum-zone":
            radii.update(inner_radius=self.inner_radius, outer_radius=self.outer_radius)
        d = _fit_dict(
            self,
            **radii,
            axis_point=list(self.axis_point),
            axis_direction=list(self.axis_direction),
            theta=self.theta,
            phi=self.phi,
            control_points=list(self.control_points),
        )
        if self.criterion != "least-squares":
            d["iterations"] = self.iterations
            d["evaluations"] = self.evaluations
        d["arc_deg"] = self.arc_deg
        d["ill_posed"] = self.ill_posed
        d["warnings"] = list(self.warnings)
        return d


_CODES = {"min-circumscribed": "mcc", "max-inscribed": "mic", "minimum-zone": "mzc"}


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
    search_axis: Optional[Any] = None,
    max_tilt: Optional[float] = None,
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
    search_axis, max_tilt
        Restrict the search to directions within ``max_tilt`` rad of ``search_axis`` (of the
        least-squares axis when ``search_axis`` is None). Default: the upper half sphere
        theta in [0, pi/2], phi in [-pi, pi] as in Sec. 6.4. A maximum inscribed cylinder is
        only meaningful near the part's axis (Eq. 6.11 bounds the axis location): for parts
        that are not long compared to their diameter pass e.g. ``max_tilt=0.2``.

    Returns
    -------
    CylinderFit
        With the certificate: min / max distance of the points to the reported axis,
        recomputed in 3-D.

    Raises
    ------
    InvalidInputError, DegenerateGeometryError, ConfigError
    """
    crit = normalize_criterion(criterion, _ALLOWED, "cylinder")
    pts = _points(points, (3,), "cylinder")
    if crit == "least-squares":
        point, direction, radius, ext = _core.form_cylinder_lsq(pts)
        cert = Certificate(float(ext[0]), float(ext[1]))
        theta, phi = axis_angles(direction)
        return _with_arc(pts, CylinderFit(
            crit, len(pts), _vec(point), _vec(direction), theta, phi, float(radius),
            cert.max_distance - cert.min_distance, cert,
        ))
    for name, v in (("particles", particles), ("iterations", iterations), ("stall_iterations", stall_iterations), ("refine_starts", refine_starts), ("hop_rounds", hop_rounds)):
        if int(v) < (1 if name == "particles" else 0):
            raise ConfigError(f"cylinder: {name} must be a positive integer, got {v}")
    if seed < 0:
        raise ConfigError(f"cylinder: seed must be a non-negative integer, got {seed}")
    axis = None if search_axis is None else tuple(float(x) for x in np.asarray(search_axis, dtype=float).ravel())
    if axis is not None and len(axis) != 3:
        raise ConfigError("cylinder: search_axis must have 3 components")
    if axis is not None and max_tilt is None:
        raise ConfigError("cylinder: give max_tilt (rad) together with search_axis")
    d = _core.form_cylinder_fit(
        pts, _CODES[crit], int(seed), int(particles), int(iterations), int(stall_iterations),
        axis, None if max_tilt is None else float(max_tilt), int(refine_starts), int(hop_rounds),
    )
    cert = Certificate(float(d["min_distance"]), float(d["max_distance"]))
    code = _CODES[crit]
    if code == "mcc":
        radius, form_error, control = d["r_out"], cert.max_distance - cert.min_distance, d["control_out"]
        inner = outer = None
    elif code == "mic":
        radius, form_error, control = d["r_in"], cert.max_distance - cert.min_distance, d["control_in"]
        inner = outer = None
    else:
        radius, inner, outer = d["radius"], d["r_in"], d["r_out"]
        form_error = outer - inner
        control = list(d["control_in"]) + [i for i in d["control_out"] if i not in d["control_in"]]
    return _with_arc(pts, CylinderFit(
        crit, len(pts), _vec(d["point"]), _vec(d["direction"]), float(d["theta"]), float(d["phi"]),
        float(radius), float(form_error), cert,
        inner_radius=None if inner is None else float(inner),
        outer_radius=None if outer is None else float(outer),
        control_points=tuple(int(i) for i in control),
        iterations=int(d["iterations"]),
        evaluations=int(d["evaluations"]),
    ))


#: Below this arc (degrees) around the axis a maximum inscribed cylinder is ill-posed.
MIN_ARC_DEG = 90.0


def _with_arc(pts: np.ndarray, r: CylinderFit) -> CylinderFit:
    # judged about the least-squares axis for MIC (its own axis can sit anywhere inside a
    # short arc), about the fitted axis otherwise -- as for circles
    point, direction = r.axis_point, r.axis_direction
    if r.criterion == "max-inscribed":
        point, direction, _, _ = _core.form_cylinder_lsq(pts)
    arc = math.degrees(_core.form_cylinder_arc(pts, point, direction))
    warnings: list[str] = []
    ill = False
    if arc < MIN_ARC_DEG:
        if r.criterion == "max-inscribed":
            ill = True
            warnings.append(
                f"the points cover only {arc:.1f} degrees around the axis (< {MIN_ARC_DEG:.0f}): the "
                "maximum inscribed cylinder is ill-posed and its radius is not a meaningful size"
            )
        else:
            warnings.append(f"the points cover only {arc:.1f} degrees around the axis: axis and radius are poorly determined")
    return replace(r, arc_deg=float(arc), ill_posed=ill, warnings=tuple(warnings))
