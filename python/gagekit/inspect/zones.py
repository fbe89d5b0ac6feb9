"""Tolerance zones of each characteristic (ISO 1101:2017), evaluated exactly.

``measured`` is the size of the smallest zone of the characteristic's kind that
contains the toleranced feature, with the orientation and location the datums impose
and every other degree of freedom optimised. ``tolerance`` is compared with it as a
**width** (two parallel planes / lines, two concentric circles / cylinders / spheres --
the radial separation) or a **diameter** (a cylinder or a sphere, the ISO ``⌀`` / ``S⌀``
zones); each entry says which in ``zone``.

Form (no datums)
  flatness (ISO 12781): two parallel planes of least separation -- width.
  straightness (ISO 12780): of a line with ``outward``: two parallel lines in the plane
    of the line and ``outward`` -- width; of a line without ``outward`` and of a
    cylinder's median line (always the median line, ``sections`` centres): the smallest
    cylinder -- diameter.
  roundness (ISO 12181): two concentric circles of least radial separation (minimum
    zone) in the circle's plane; for a cylinder or cone, of each of ``sections`` sections
    across the least-squares axis, the largest -- width.
  cylindricity (ISO 12180): two coaxial cylinders of least radial separation -- width.
  sphericity: two concentric spheres of least radial separation -- width.
  conicity (the dissertation's Sec. 7.2 item 6; ISO 1101 profile of a conical surface
    without datums): two coaxial cones of the same half angle -- free, or the basic
    ``half_angle`` -- of least separation measured normal to the cone surface -- width.

Orientation (ISO 1101 Sec. 18.9-18.11), the zone's orientation fixed by the datums as
far as they fix it and free otherwise; the toleranced element is the surface of a plane
or the derived axis of a cylinder / cone:
  parallelism: plane to datum plane -- planes parallel to it (width); plane to datum axis
    -- planes parallel to the axis, free to turn about it (width); axis to datum plane --
    planes parallel to it (width); axis to datum axis -- a cylinder parallel to it
    (diameter).
  perpendicularity: plane to datum plane -- planes perpendicular to it, free to turn
    about its normal (with a second datum plane: perpendicular to both) (width); plane to
    datum axis -- planes perpendicular to it (width); axis to datum plane -- a cylinder
    perpendicular to it (diameter); axis to datum axis -- planes perpendicular to it (width).
  angularity (basic ``angle`` between feature and datum): plane -- planes at the angle,
    free to turn about the datum's normal / axis (width); axis -- a cylinder at the
    angle, free to turn (diameter).
  With ``nominal.direction`` given, the zone's orientation is fixed to it (in the datum
  frame) instead.

Location
  position: of an axis -- a cylinder at the basic line ``nominal`` (diameter); of a
    sphere's centre -- a sphere (spherical diameter); of a circle's centre -- a cylinder
    along ``nominal.direction`` (or the circle's normal) (diameter); of a plane -- two
    parallel planes symmetric about the basic plane (width). Translations and the
    rotation about z that the datum frame leaves free are optimised in one kernel call
    (``gagekit_gdt::turn``: exactly for translations -- minimum circumscribed circle /
    1-D convex minimum; for the rotation alone, of a centre or of an axis along z,
    exactly -- the minimum of an upper envelope of sinusoids; otherwise a 720-point grid
    and golden-section refinement of its best local minima to machine precision; a
    plane's zone polished exactly on its active extreme points). Relative to a lone datum point every rotation is free: only the
    distance of a centre from it is located.
  coaxiality (ISO 1101 Sec. 18.13): a cylinder coaxial with the datum axis containing the
    derived axis (a circle's or sphere's centre: concentricity) -- diameter.
  profile of a plane (ISO 1660): two planes symmetric about the basic plane (width); with
    no datums the zone floats (= flatness).

Run-out (ISO 1101 Sec. 18.15-18.16), relative to the datum axis:
  circular-runout: the largest range, over ``sections`` sections across the datum axis,
    of the points' distances to the datum axis (cylinder, circle: radial; cone: normal to
    the cone of the least-squares half angle; plane: axial, over ``sections`` bands of
    radius) -- width.
  total-runout: the range of the same distances over the whole surface -- width.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import _core
from ..errors import ConfigError, DegenerateGeometryError
from ..form import fit_circle, fit_cone, fit_line, fit_sphere
from .datums import DatumSystem, SimulatedDatum
from .features import FeatureData, _unit
from .spec import Tolerance
from .zone_tools import Measurement, _element, _plane_2d

__all__ = ["Measurement", "evaluate", "ZONE_KINDS"]

#: The zone kinds and what ``tolerance`` means for them.
ZONE_KINDS = {"width": "distance between the two bounding surfaces",
              "diameter": "diameter of a cylindrical zone",
              "spherical diameter": "diameter of a spherical zone"}


# -- small exact helpers ---------------------------------------------------------------


def _slab(points: np.ndarray, mode: str, axis: Any = (0.0, 0.0, 1.0), angle: float = 0.0) -> tuple[float, np.ndarray]:
    normal, _, _, width = _core.gdt_slab(np.ascontiguousarray(points), mode, tuple(float(a) for a in axis), float(angle))
    return float(width), np.array(normal)


def _cylinder_zone(points: np.ndarray, d: np.ndarray) -> float:
    """Diameter of the smallest cylinder of direction d containing the points (the minimum
    circumscribed circle of their projection, Welzl, exact)."""
    return 2.0 * float(_core.gdt_axis_along(np.ascontiguousarray(points), tuple(float(x) for x in d), "circumscribed")[2])


# -- the evaluation ----------------------------------------------------------------------


def evaluate(tol: Tolerance, fd: FeatureData, system: DatumSystem) -> Measurement:
    """The measured value of one callout."""
    char = tol.characteristic
    if char in ("size", "distance", "angle"):
        from . import sizes

        return {"size": sizes.evaluate_size, "distance": sizes.evaluate_distance, "angle": sizes.evaluate_angle}[char](tol, fd, system)
    fn = _DISPATCH[char]
    m = fn(tol, fd, system)
    if tol.material is not None or any(tol.datum_material):
        from .material import apply_material

        m = apply_material(tol, fd, system, m)
    return m


def _flatness(tol, fd, system):
    w, n = fd.min_zone()
    return Measurement(w, "width", "surface", len(fd.points), {"zone_normal": n.tolist()})


def _straightness(tol, fd, system):
    if fd.shape == "line":
        p0, d = fd.axis_line()
        if fd.spec.outward is not None:
            o = np.asarray(fd.spec.outward, dtype=float)
            w = o - (o @ d) * d
            if np.linalg.norm(w) < 1e-9:
                raise ConfigError(f"{system.spec.source}: [[feature]] '{fd.name}': 'outward' is along the line; it must be the surface normal")
            w = _unit(w)
            q = fd.points - p0
            xy = np.ascontiguousarray(np.column_stack([q @ d, q @ w]))
            width, _, _, _ = _core.gdt_min_width_2d(xy)
            return Measurement(float(width), "width", "line in the plane of its outward normal", len(fd.points))
        fit = fit_line(fd.points, "min-circumscribed")
        return Measurement(float(fit.form_error), "diameter", "line", len(fd.points))
    count = tol.sections or fd.spec.sections
    centres = fd.axis_points("median-line", count)
    if len(centres) < 3:
        value = 0.0
    else:
        value = float(fit_line(centres, "min-circumscribed").form_error)
    return Measurement(value, "diameter", f"median line ({len(centres)} section centres)", len(fd.points))


def _roundness(tol, fd, system):
    if tol.form_filter is not None:
        return _filtered_roundness(tol, fd)
    if fd.shape == "circle":
        d = _unit(fd.lsq().normal)
        xy = _plane_2d(fd.points - np.array(fd.lsq().center), d)
        w = fit_circle(xy, "mz").form_error
        return Measurement(float(w), "width", "circle", len(fd.points))
    count = tol.sections or fd.spec.sections
    worst = 0.0
    secs = fd.section_circles(count)
    if "warm" in fd._cache:
        # a Monte Carlo trial: each section's zone on an active set from its least-squares
        # centre (gagekit.form.active: exact by verification)
        from ..form.active import minimum_zone_circle_near
        from .features import _basis

        p0, d = fd.axis_line()
        u, v = _basis(d)
        for c, xy in secs:
            worst = max(worst, float(minimum_zone_circle_near(xy, ((c - p0) @ u, (c - p0) @ v)).form_error))
        return Measurement(worst, "width", f"{len(secs)} sections", len(fd.points))
    for _, xy in secs:
        worst = max(worst, float(fit_circle(xy, "mz").form_error))
    return Measurement(worst, "width", f"{len(secs)} sections", len(fd.points))


def _filtered_roundness(tol, fd):
    """Roundness with ``filter`` / ``reference`` (ISO 12181-1/-2): RONt of the profile filtered
    by the ISO 16610-21 Gaussian filter of ``filter.upr`` (:func:`gagekit.roundness_parameters`)
    against ``reference`` (default MZCI, the ISO 1101 zone); of a cylinder or cone, the
    section of largest RONt. The row carries ``parameters``, ``filter`` and ``reference``."""
    from ..form.parameters import roundness_parameters

    reference = tol.reference or "MZCI"
    if fd.shape == "circle":
        d = _unit(fd.lsq().normal)
        profiles = [_plane_2d(fd.points - np.array(fd.lsq().center), d)]
    else:
        profiles = [xy for _, xy in fd.section_circles(tol.sections or fd.spec.sections)]
    results = [roundness_parameters(xy, tol.form_filter, tol.filter_upr, reference) for xy in profiles]
    worst = max(results, key=lambda r: r.parameters["RONt"])
    d = worst.to_dict()
    element = "circle" if fd.shape == "circle" else f"{len(results)} sections"
    extra = {"parameters": d["parameters"], "filter": {k: v for k, v in d["filter"].items() if k in ("type", "upr")},
             "reference": d["reference"]}
    return Measurement(worst.parameters["RONt"], "width", element, len(fd.points),
                       {"eccentricity": d["eccentricity"], "samples": d["resampling"]["samples"]}, extra=extra)


def _cylindricity(tol, fd, system):
    fit = fd.chebyshev_cylinder("minimum-zone")
    return Measurement(float(fit.form_error), "width", "surface", len(fd.points),
                       {"axis_point": list(fit.point), "axis_direction": list(fit.direction)})


def _sphericity(tol, fd, system):
    near = fd._cache.get("near_zone")  # a Monte Carlo trial: the measured zone (gagekit.form.active)
    if near is not None:
        from ..form.active import minimum_zone_sphere_near

        fit = minimum_zone_sphere_near(fd.points, near["center"])
    else:
        fit = fit_sphere(fd.points, "minimum-zone")
    return Measurement(float(fit.outer_radius - fit.inner_radius), "width", "surface", len(fd.points), {"center": list(fit.center)})


def _conicity(tol, fd, system):
    fit = fit_cone(fd.points, "minimum-zone", angle=tol.angle)
    return Measurement(float(fit.form_error), "width", "surface (normal to the cone)", len(fd.points),
                       {"axis_point": list(fit.point), "axis_direction": list(fit.direction), "apex": list(fit.apex),
                        "half_angle_deg": math.degrees(fit.half_angle), "fixed_angle": fit.fixed_angle})


def _direction(sim: SimulatedDatum) -> np.ndarray:
    return sim.vector


def _orientation(tol, fd, system):
    char = tol.characteristic
    sims = system.chain(tol.datums)
    d1 = sims[0]
    a = _direction(d1)
    pts, element = _element(fd)
    n_pts = len(fd.points)
    if tol.nominal_direction is not None:
        frame = system.frame(tol.datums)
        nd = frame.direction_to_scan(tol.nominal_direction)
        if fd.shape == "plane":
            w, _ = _slab(pts, "fixed", nd)
            return Measurement(w, "width", element, n_pts, {"zone_normal": nd.tolist()})
        return Measurement(_cylinder_zone(pts, nd), "diameter", element, n_pts, {"zone_axis": nd.tolist()})
    plane_datum = d1.type == "plane"
    if fd.shape == "plane":
        if char == "parallelism":
            mode, axis, ang = ("fixed", a, 0.0) if plane_datum else ("perpendicular", a, 0.0)
        elif char == "perpendicularity":
            if plane_datum and len(sims) > 1 and sims[1].type == "plane":
                mode, axis, ang = "fixed", _unit(np.cross(a, sims[1].vector)), 0.0
            else:
                mode, axis, ang = ("perpendicular", a, 0.0) if plane_datum else ("fixed", a, 0.0)
        else:
            theta = math.radians(tol.angle)
            if plane_datum:
                s = 1.0 if float(fd.plane_normal_out() @ a) >= 0 else -1.0
                mode, axis, ang = "angle", s * a, theta
            else:
                s = 1.0 if float(fd.plane_normal_out() @ a) >= 0 else -1.0
                mode, axis, ang = "angle", s * a, math.pi / 2 - theta
        w, n = _slab(pts, mode, axis, ang)
        return Measurement(w, "width", element, n_pts, {"zone_normal": n.tolist()})
    # a derived axis
    if char == "parallelism":
        if plane_datum:
            w, n = _slab(pts, "fixed", a)
            return Measurement(w, "width", element, n_pts, {"zone_normal": n.tolist()})
        return Measurement(_cylinder_zone(pts, a), "diameter", element, n_pts, {"zone_axis": a.tolist()})
    if char == "perpendicularity":
        if plane_datum:
            return Measurement(_cylinder_zone(pts, a), "diameter", element, n_pts, {"zone_axis": a.tolist()})
        w, n = _slab(pts, "fixed", a)
        return Measurement(w, "width", element, n_pts, {"zone_normal": n.tolist()})
    # angularity of an axis: a cylinder whose axis is at the basic angle, turned freely
    theta = math.radians(tol.angle)
    _, d_ls = fd.axis_line()
    s = 1.0 if float(d_ls @ a) >= 0 else -1.0
    cone = (math.pi / 2 - theta) if plane_datum else theta
    value, axis = _core.gdt_cylinder_on_cone(np.ascontiguousarray(pts), tuple(s * a), cone)
    return Measurement(float(value), "diameter", element, n_pts, {"zone_axis": list(axis)})


def _position(tol, fd, system):
    sims = system.chain(tol.datums)
    if len(sims) == 1 and sims[0].type == "point":
        return _position_about_point(tol, fd, system, sims[0])
    frame = system.frame(tol.datums)
    P0 = frame.point_to_scan(tol.nominal_point)
    n_pts = len(fd.points)
    if fd.shape == "plane":
        return _plane_location(tol, fd, frame, "surface")
    if fd.shape == "sphere":
        c = np.array(fd.lsq().center)
        r, _ = _core.gdt_position_zone(c[None, :], frame.kernel_args(), tuple(P0), None)
        return Measurement(2 * r, "spherical diameter", "centre (least-squares sphere)", n_pts, {"nominal": P0.tolist()})
    if fd.shape == "circle":
        D0 = frame.direction_to_scan(tol.nominal_direction) if tol.nominal_direction is not None else _unit(fd.lsq().normal)
        pts, element = np.array(fd.lsq().center)[None, :], "centre (least-squares circle)"
    else:
        D0 = frame.direction_to_scan(tol.nominal_direction)
        pts, element = _element(fd)
    r, _ = _core.gdt_position_zone(np.ascontiguousarray(pts), frame.kernel_args(), tuple(P0), tuple(D0))
    return Measurement(2 * r, "diameter", element, n_pts, {"nominal_point": P0.tolist(), "nominal_direction": D0.tolist()})


def _position_about_point(tol, fd, system, datum):
    """Position relative to a lone datum point: every rotation about it is free, so only
    the distance from the point is located (the zone is a spherical shell about it; for a
    centre, a sphere of diameter ``2 | |c - o| - |nominal| |``)."""
    if fd.shape not in ("sphere", "circle"):
        raise ConfigError(f"{system.spec.source}: [[tolerance]] #{tol.index + 1}: position of a {fd.shape} relative to the "
                          f"datum point {datum.letter} alone is not defined (every rotation about it is free); add a datum "
                          "plane or axis")
    c = np.array(fd.lsq().center)
    r0 = float(np.linalg.norm(np.asarray(tol.nominal_point, dtype=float)))
    value = 2.0 * abs(float(np.linalg.norm(c - datum.point)) - r0)
    return Measurement(value, "spherical diameter" if fd.shape == "sphere" else "diameter", "centre", len(fd.points),
                       {"datum_point": datum.point.tolist(), "nominal_distance": r0})


def _plane_location(tol, fd, frame, element):
    P0 = frame.point_to_scan(tol.nominal_point)
    N0 = frame.direction_to_scan(tol.nominal_direction)
    v, _ = _core.gdt_plane_location(fd.points, frame.kernel_args(), tuple(P0), tuple(N0))
    return Measurement(float(v), "width", element, len(fd.points), {"nominal_point": P0.tolist(), "nominal_normal": N0.tolist()})


def _profile(tol, fd, system):
    if fd.shape == "surface":
        from ..cad.features import surface_profile

        value, details = surface_profile(tol, fd, system)
        return Measurement(value, "width", "surface (CAD faces" + (", zone fixed by the datums)" if tol.datums else
                                                                  ", no datums: the zone floats)"), len(fd.points), details)
    if not tol.datums:
        w, n = fd.min_zone()
        return Measurement(w, "width", "surface (no datums: the zone floats)", len(fd.points), {"zone_normal": n.tolist()})
    return _plane_location(tol, fd, system.frame(tol.datums), "surface")


def _profile_line(tol, fd, system):
    from ..cad.features import line_profile

    value, details = line_profile(tol, fd, system)
    n = len(details["sections"])
    return Measurement(value, "width", f"{n} line sections of the surface (CAD faces" +
                       (", zones fixed by the datums)" if tol.datums else ", no datums: each zone floats in its plane)"),
                       len(fd.points), details)


def _coaxiality(tol, fd, system):
    d = system.datum(tol.datums[:1])
    if fd.shape in ("circle", "sphere"):
        pts, element = np.array(fd.lsq().center)[None, :], "centre"
    else:
        pts, element = _element(fd)
    q = pts - d.point
    w = q - np.outer(q @ d.vector, d.vector)
    return Measurement(2.0 * float(np.linalg.norm(w, axis=1).max()), "diameter", element, len(fd.points))


def _runout(tol, fd, system):
    d = system.datum(tol.datums[:1])
    o, a = d.point, d.vector
    q = fd.points - o
    t = q @ a
    r = np.linalg.norm(q - np.outer(t, a), axis=1)
    total = tol.characteristic == "total-runout"
    count = tol.sections or fd.spec.sections
    if fd.shape == "plane":
        dist, key, what = t, r, "axial"
    elif fd.shape == "cone":
        cone = fd.lsq()
        half = 0.5 * cone.apex_angle
        s = 1.0 if float(np.asarray(cone.direction) @ a) >= 0 else -1.0
        dist, key, what = r * math.cos(half) - s * t * math.sin(half), t, "normal to the cone"
    else:
        dist, key, what = r, t, "radial"
    if total:
        return Measurement(float(np.ptp(dist)), "width", f"surface ({what})", len(fd.points))
    if fd.shape == "circle":
        return Measurement(float(np.ptp(dist)), "width", f"circle ({what})", len(fd.points))
    lo, hi = float(key.min()), float(key.max())
    if hi <= lo:
        return Measurement(float(np.ptp(dist)), "width", f"1 section ({what})", len(fd.points))
    k = np.minimum(((key - lo) / (hi - lo) * count).astype(np.int64), count - 1)
    order = np.argsort(k, kind="stable")
    ks, ds = k[order], dist[order]
    bounds = np.searchsorted(ks, np.arange(count + 1))
    worst, used = 0.0, 0
    for i in range(count):
        seg = ds[bounds[i]:bounds[i + 1]]
        if len(seg) >= 2:
            worst = max(worst, float(seg.max() - seg.min()))
            used += 1
    if used == 0:
        raise DegenerateGeometryError(f"{system.spec.source}: [[tolerance]] #{tol.index + 1}: no section of '{fd.name}' holds 2 points")
    return Measurement(worst, "width", f"{used} {'bands' if fd.shape == 'plane' else 'sections'} ({what})", len(fd.points))


_DISPATCH = {
    "flatness": _flatness,
    "straightness": _straightness,
    "roundness": _roundness,
    "cylindricity": _cylindricity,
    "sphericity": _sphericity,
    "conicity": _conicity,
    "parallelism": _orientation,
    "perpendicularity": _orientation,
    "angularity": _orientation,
    "position": _position,
    "coaxiality": _coaxiality,
    "profile": _profile,
    "profile-line": _profile_line,
    "circular-runout": _runout,
    "total-runout": _runout,
}
