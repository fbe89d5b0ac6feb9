"""Cylinders: least squares, minimum circumscribed (MCC), maximum inscribed (MIC) and
minimum zone (MZC) by the projection model of Sec. 6.3.

The axis direction is a = (sin t cos f, sin t sin f, cos t) with the polar angle
t in [0, pi/2] and the azimuth f in [-pi, pi] (the half sphere, Tables 6.2/6.4);
the points are projected along it by q = [I2 0] Ry(-t) Rz(-f) p (Eq. 6.12 as
corrected in ERRATA item 1), and the projected 2-D set is fitted exactly
(Eqs. 6.13-6.15). The result, :class:`CylinderFit`, is the Rust object
(``gagekit_form::result::CylinderResult``: radius, zone, control points, arc, the
search cone and their warnings, assembled once there).
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core
from .._core.form import CylinderFit
from ..errors import ConfigError
from .fits import _points
from .search import DEFAULT_MAX_TILT, search_settings

__all__ = ["CylinderFit", "fit_cylinder", "axis_angles", "DEFAULT_MAX_TILT"]



def axis_angles(direction: Any) -> tuple[float, float]:
    """(theta, phi) of a direction, flipped into the upper half sphere (theta <= pi/2)."""
    try:
        d = np.asarray(direction, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ConfigError(f"axis_angles: a direction is three numbers (x, y, z), got {direction!r}") from None
    return _core.form.axis_angles((float(d[0]), float(d[1]), float(d[2])))


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
    pts = _points(points, (3,), "cylinder")
    nominal, tilt = search_settings(axis, max_tilt, "cylinder")
    start = None
    if warm is not None:
        try:
            wp, wd = (tuple(float(x) for x in np.asarray(v, dtype=float).reshape(3)) for v in warm)
        except (TypeError, ValueError):
            raise ConfigError(f"cylinder: warm must be (point, direction), two 3-vectors, got {warm!r}") from None
        start = (wp, wd)
    return _core.form.fit_cylinder(
        pts, str(criterion), int(seed), int(particles), int(iterations), int(stall_iterations),
        nominal, tilt, int(refine_starts), int(hop_rounds), start,
    )
