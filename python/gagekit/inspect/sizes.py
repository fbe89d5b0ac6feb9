"""Sizes (ISO 14405-1:2016), distances and angles (ISO 14405-2:2018, ASME Y14.5-2018).

**Size** of a feature of size -- a cylinder, circle, sphere, cone (in a cross-section)
or a width between two opposite parallel faces (``slot``: internal, ``tab``: external),
against its limits ``nominal + lower`` ... ``nominal + upper`` (or the ISO 286 class
``fit``, :mod:`.iso286`). The ``modifier`` says which size (ISO 14405-1 Table 1):

- ``LP`` (default) -- two-point sizes: in ``sections`` cross-sections across the
  least-squares axis (the feature's ``sections``, default 10) and ``angles`` directions
  per section (default 180: every degree of the half turn), the distance between the two
  opposite points of the scan on a line through the axis, interpolated on the scan
  (``gagekit-gdt`` ``size``, parallel), the first direction along the region box's x
  axis projected normal to the axis (so the sizes move with the part); a sphere's lines run through its least-squares
  centre in ``sections`` great half-planes about its region box's third axis; a width's
  from every point of its first face to the second face along the faces' common
  least-squares normal (interpolated on the second face's Delaunay triangulation);
  a cone's in one cross-section, the middle one of ``sections`` slices. Every local
  size must lie within the limits; ``measured`` is the local size nearest a limit (the
  one that decides), ``local_sizes`` gives n, min, max, mean. A feature scanned over
  less than half a turn has no two-point size: its least-squares size (GG) is reported
  with a warning in ``details`` and ``modifier_used = "GG"``.
- ``LS`` -- the same two-point sizes (on a sphere: through the centre).
- ``GG`` least squares, ``GX`` maximum inscribed, ``GN`` minimum circumscribed: the
  associated cylinder / circle / sphere (exact or certified, :mod:`gagekit.form`); for
  a width the two least-squares planes of a common normal, the distance of the convex
  hulls of the two faces (the widest pair of parallel planes between them, GJK), the
  minimum width of both faces (exact); a cone's: of its middle cross-section.
- ``CC`` circumference diameter (perimeter / pi), ``CA`` area diameter
  (2 sqrt(area / pi)) of each cross-section's profile (the points in angle order about
  the axis; sections not scanned all round are left out), their mean; ``CV`` volume diameter 2 sqrt(mean area / pi) (cylinders).
- rank-order statistics of the two-point sizes: ``SX`` max, ``SN`` min, ``SA`` mean,
  ``SM`` median, ``SD`` mid-range, ``SR`` range.

``margin`` is the distance of ``measured`` (of every local size for LP / LS) to the
nearer limit, negative outside; ``pass`` is ``margin >= 0``.

**Envelope requirement** (``envelope = true``: ISO 14405-1 (E); the default with
``[part] standard = "asme"``, ASME Y14.5 Rule #1): the mating size -- GN of a shaft or
tab, GX of a hole or slot -- must not pass the maximum material limit (upper for a
shaft, lower for a hole), and every two-point size must stay within the least material
limit. Both enter ``margin``; ``envelope`` in the JSON gives the mating size.

**Distance** between two features (``to``): plane-plane -- the distance of the second
plane's least-squares centroid from the first least-squares plane; a plane and an axis
or centre -- of the axis's mid-point or the centre from the plane; axis / centre to axis
/ centre -- of the second's mid-point / centre from the first's axis line, or between the
two centres. A slot or tab stands for its median plane, a circle for its centre. Limits:
``nominal + lower`` ... ``nominal + upper`` (or +-``tolerance``), mm.

**Angle** between two features (degrees): two planes -- the angle of the material
between them, 180 minus the angle of their outward normals (two faces of a block's edge:
90, a 45-degree chamfer to its base: 45, opposite faces: 0); lines, axes, a circle's
normal or a slot's normal -- the acute angle of the two lines; a plane and a line --
90 minus the acute angle of the line and the plane's normal.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError, DegenerateGeometryError
from ..form import fit_circle, fit_sphere
from .features import FeatureData, _unit
from .spec import RANK_ORDER, Tolerance
from .zone_tools import Measurement, _plane_2d

__all__ = ["evaluate_size", "evaluate_distance", "evaluate_angle", "two_point_sizes", "mating_size", "DEFAULT_ANGLES"]

#: Directions per cross-section of the two-point sizes (over the half turn: 1 degree apart).
DEFAULT_ANGLES = 180

_RANK = {
    "SX": np.max,
    "SN": np.min,
    "SA": np.mean,
    "SM": np.median,
    "SD": lambda s: 0.5 * (float(np.max(s)) + float(np.min(s))),
    "SR": np.ptp,
}


def _where(tol: Tolerance, fd: FeatureData) -> str:
    return f"[[tolerance]] #{tol.index + 1} ({tol.characteristic} of '{fd.name}')"


def _cone_section(fd: FeatureData, count: int) -> np.ndarray:
    """The points of a cone's middle cross-section (of ``count`` slices across its axis)."""
    secs = fd.sections(count)
    idx = secs[len(secs) // 2]
    if len(idx) < 3:
        raise DegenerateGeometryError(f"feature '{fd.name}': the cone's middle section holds {len(idx)} points; a size needs 3")
    return np.ascontiguousarray(fd.points[idx])


def two_point_sizes(fd: FeatureData, sections: int, angles: int = DEFAULT_ANGLES) -> np.ndarray:
    """Every two-point size of a feature of size (see the module docstring), computed
    once per (sections, angles)."""
    key = ("2p", sections, angles)
    if key in fd._cache:
        return fd._cache[key]
    shape = fd.shape
    box = fd.box_axes()
    # the directions start from the region box's x axis (its y axis if x runs along the
    # feature's axis): the box moves with the part, so the sizes are invariant
    ref = lambda d: tuple(box[0] if abs(float(box[0] @ d)) < 0.9 else box[1])  # noqa: E731
    if shape in ("slot", "tab"):
        a, b = fd.faces()
        sizes = _core.gdt_width_sizes(a, b, tuple(fd.width_fit().normal))
    elif shape == "sphere":
        c = tuple(fd.lsq().center)
        sizes = _core.gdt_two_point_sizes(fd.points, c, tuple(box[2]), tuple(box[0]), "great-circles", sections, angles)[0]
    elif shape == "circle":
        fit = fd.lsq()
        n = _unit(fit.normal)
        sizes = _core.gdt_two_point_sizes(fd.points, tuple(fit.center), tuple(n), ref(n), "axial", 1, angles)[0]
    elif shape == "cone":
        p0, d = fd.axis_line()
        sizes = _core.gdt_two_point_sizes(_cone_section(fd, sections), tuple(p0), tuple(d), ref(d), "axial", 1, angles)[0]
    else:
        p0, d = fd.axis_line()
        sizes = _core.gdt_two_point_sizes(fd.points, tuple(p0), tuple(d), ref(d), "axial", sections, angles)[0]
    if len(sizes) == 0:
        raise DegenerateGeometryError(f"feature '{fd.name}': no two opposite points found for a two-point size "
                                      "(the scan covers less than half a turn, or the faces do not face each other)")
    fd._cache[key] = sizes
    return sizes


def _section_profiles(fd: FeatureData, sections: int) -> list[np.ndarray]:
    """Each cross-section's points as 2-D coordinates about the axis (at the origin)."""
    if fd.shape == "circle":
        fit = fd.lsq()
        return [_plane_2d(fd.points - np.array(fit.center), _unit(fit.normal))]
    if fd.shape == "cone":
        p0, d = fd.axis_line()
        return [_plane_2d(_cone_section(fd, sections) - p0, d)]
    return [xy for _, xy in fd.section_circles(sections)]


def _polygon(xy: np.ndarray) -> Optional[tuple[float, float]]:
    """(perimeter, area) of the profile joined in angle order about the origin; ``None``
    for an open profile (an angular gap over 10 median spacings: a partly scanned or
    partly cut section)."""
    ang = np.arctan2(xy[:, 1], xy[:, 0])
    order = np.argsort(ang, kind="stable")
    a = ang[order]
    gaps = np.diff(np.append(a, a[0] + 2 * math.pi))
    if len(a) < 3 or gaps.max() > 10.0 * float(np.median(gaps)):
        return None
    p = xy[order]
    q = np.roll(p, -1, axis=0)
    perimeter = float(np.linalg.norm(q - p, axis=1).sum())
    area = 0.5 * abs(float((p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]).sum()))
    return perimeter, area


def mating_size(fd: FeatureData, which: str, sections: Optional[int] = None) -> float:
    """The associated size ``which`` = "GG" / "GX" / "GN" of a feature of size (mm)."""
    sections = sections or fd.spec.sections
    key = ("mating", which, sections if fd.shape == "cone" else None)
    if key in fd._cache:
        return fd._cache[key]
    shape = fd.shape
    crit = {"GG": "least-squares", "GX": "max-inscribed", "GN": "min-circumscribed"}[which]
    if shape in ("slot", "tab"):
        if which == "GG":
            v = fd.width_fit().size
        elif which == "GX":
            a, b = fd.faces()
            v = float(_core.gdt_hull_distance(a, b)[0])
        else:
            v = float(_core.gdt_slab(fd.points, "free", (0.0, 0.0, 1.0), 0.0)[3])
    elif shape == "sphere":
        v = 2.0 * float(fd.lsq().radius if which == "GG" else fit_sphere(fd.points, crit).radius)
    elif shape in ("circle", "cone"):
        xy = _section_profiles(fd, sections)[0]
        v = 2.0 * float(fit_circle(xy, crit).radius)
    else:
        if which == "GG":
            v = 2.0 * float(fd.lsq().radius)
        else:
            v = 2.0 * float(fd.chebyshev_cylinder(crit).radius)
    fd._cache[key] = v
    return v


def _stats(sizes: np.ndarray) -> dict[str, Any]:
    return {"n": int(len(sizes)), "min": float(sizes.min()), "max": float(sizes.max()), "mean": float(sizes.mean())}


def _is_internal(fd: FeatureData) -> bool:
    return fd.shape == "slot" or fd.spec.kind == "hole"


def evaluate_size(tol: Tolerance, fd: FeatureData, system: Any) -> Measurement:
    """A size callout (see the module docstring)."""
    U, L = float(tol.upper_limit), float(tol.lower_limit)
    mod = tol.modifier or "LP"
    sections = tol.sections or fd.spec.sections
    angles = tol.angles or DEFAULT_ANGLES
    where = f"{system.spec.source}: {_where(tol, fd)}"
    details: dict[str, Any] = {"sections": sections, "angles": angles} if mod in ("LP", "LS") + RANK_ORDER else {}
    extra: dict[str, Any] = {"nominal": tol.size_nominal, "upper": tol.upper, "lower": tol.lower, "modifier": mod,
                             "upper_limit": U, "lower_limit": L}
    if tol.fit:
        extra["fit"] = tol.fit
    sizes = None
    if mod in ("LP", "LS") + RANK_ORDER:
        try:
            sizes = two_point_sizes(fd, sections, angles)
        except DegenerateGeometryError as exc:
            # a partial feature (less than half a turn scanned) has no two-point size: the
            # least-squares size is reported instead, as CMM software does, with a warning
            mod = "GG"
            details["warning"] = f"{exc}; the least-squares size (GG) is reported"
            extra["modifier_used"] = "GG"
    if sizes is not None:
        extra["local_sizes"] = _stats(sizes)
        if mod in RANK_ORDER:
            measured = float(_RANK[mod](sizes))
            margin = min(U - measured, measured - L)
            element = f"{mod} of {len(sizes)} two-point sizes"
        else:
            lo, hi = float(sizes.min()), float(sizes.max())
            m_up, m_lo = U - hi, lo - L
            measured = hi if m_up <= m_lo else lo
            margin = min(m_up, m_lo)
            element = f"{len(sizes)} two-point sizes"
    elif mod in ("GG", "GX", "GN"):
        measured = mating_size(fd, mod, sections)
        margin = min(U - measured, measured - L)
        element = {"GG": "least-squares", "GX": "maximum inscribed", "GN": "minimum circumscribed"}[mod] + f" {fd.shape}"
    else:  # CC, CA, CV
        if fd.shape not in ("cylinder", "circle", "cone") or (mod == "CV" and fd.shape != "cylinder"):
            ok = "cylinders" if mod == "CV" else "cylinders, circles and cones"
            raise ConfigError(f"{where}: 'modifier' = {mod!r} applies to {ok}, not to a {fd.shape}")
        polys = [p for p in (_polygon(xy) for xy in _section_profiles(fd, sections)) if p is not None]
        if not polys:
            raise DegenerateGeometryError(f"{where}: no cross-section of '{fd.name}' is scanned all round; "
                                          f"{mod} needs a closed profile")
        if mod == "CC":
            per = [p / math.pi for p, _ in polys]
        else:
            per = [2.0 * math.sqrt(a / math.pi) for _, a in polys]
        measured = float(np.mean(per)) if mod != "CV" else 2.0 * math.sqrt(float(np.mean([a for _, a in polys])) / math.pi)
        margin = min(U - measured, measured - L)
        details["per_section"] = [float(x) for x in per]
        element = f"{len(polys)} section(s)"
    if tol.envelope:
        internal = _is_internal(fd)
        mate = mating_size(fd, "GX" if internal else "GN", sections)
        mmc = L if internal else U
        env_margin = (mate - L) if internal else (U - mate)
        if sizes is None and "warning" not in details:
            sizes = two_point_sizes(fd, sections, angles)
        if sizes is None:
            lmc_margin = env_margin  # no two-point size: the LMC side is not evaluated (see the warning)
        else:
            lmc_margin = (U - float(sizes.max())) if internal else (float(sizes.min()) - L)
        extra["envelope"] = {"mating_size": mate, "mmc_size": mmc, "mating": "GX" if internal else "GN",
                             "margin": min(env_margin, lmc_margin)}
        margin = min(margin, env_margin, lmc_margin)
    return Measurement(measured, "size", element, len(fd.points), details, margin=margin, extra=extra)


# -- distances and angles ----------------------------------------------------------------


def _locus(fd: FeatureData) -> tuple[str, np.ndarray, np.ndarray]:
    """("plane", point, normal) / ("line", point, direction) / ("centre", centre, normal or 0)."""
    shape = fd.shape
    if shape == "plane":
        return "plane", np.array(fd.lsq().point), fd.plane_normal_out()
    if shape in ("slot", "tab"):
        w = fd.width_fit()
        return "median-plane", w.point, w.normal
    if shape == "sphere":
        return "centre", np.array(fd.lsq().center), np.zeros(3)
    if shape == "circle":
        return "centre", np.array(fd.lsq().center), _unit(fd.lsq().normal)
    p0, d = fd.axis_line()
    if shape == "line":
        return "line", p0, d
    ends = fd.axis_points("least-squares")
    return "line", 0.5 * (ends[0] + ends[-1]), d


def _limits(tol: Tolerance, measured: float) -> tuple[float, dict[str, Any]]:
    U, L = float(tol.upper_limit), float(tol.lower_limit)
    return min(U - measured, measured - L), {"nominal": tol.size_nominal, "upper": tol.upper, "lower": tol.lower,
                                             "upper_limit": U, "lower_limit": L, "to": tol.to}


def _perp(q: np.ndarray, d: np.ndarray) -> float:
    return float(np.linalg.norm(q - (q @ d) * d))


def evaluate_distance(tol: Tolerance, fd: FeatureData, system: Any) -> Measurement:
    """The distance of ``fd`` and ``to`` (see the module docstring)."""
    other = system.feats[tol.to]
    ka, pa, va = _locus(fd)
    kb, pb, vb = _locus(other)
    planes = ("plane", "median-plane")
    if ka in planes:
        value, how = abs(float((pb - pa) @ va)), f"{kb} of '{other.name}' from the plane of '{fd.name}'"
    elif kb in planes:
        value, how = abs(float((pa - pb) @ vb)), f"{ka} of '{fd.name}' from the plane of '{other.name}'"
    elif ka == "line":
        value, how = _perp(pb - pa, va), f"{'mid-point' if kb == 'line' else 'centre'} of '{other.name}' from the axis of '{fd.name}'"
    elif kb == "line":
        value, how = _perp(pa - pb, vb), f"centre of '{fd.name}' from the axis of '{other.name}'"
    else:
        value, how = float(np.linalg.norm(pa - pb)), "centre to centre"
    margin, extra = _limits(tol, value)
    return Measurement(value, "distance", how, len(fd.points) + len(other.points), {}, margin=margin, extra=extra)


def evaluate_angle(tol: Tolerance, fd: FeatureData, system: Any) -> Measurement:
    """The angle (degrees) of ``fd`` and ``to`` (see the module docstring)."""
    other = system.feats[tol.to]
    ka, _, va = _locus(fd)
    kb, _, vb = _locus(other)
    if ka == "centre" and not np.any(va) or kb == "centre" and not np.any(vb):
        raise ConfigError(f"{system.spec.source}: {_where(tol, fd)}: a sphere has no direction; an angle needs planes, lines or axes")

    def acute(a: np.ndarray, b: np.ndarray) -> float:
        return math.degrees(math.acos(min(1.0, abs(float(a @ b)))))

    if ka == "plane" and kb == "plane":
        value = 180.0 - math.degrees(math.acos(max(-1.0, min(1.0, float(va @ vb)))))
        how = "between the planes, through the material"
    elif (ka in ("plane", "median-plane")) != (kb in ("plane", "median-plane")):
        value, how = 90.0 - acute(va, vb), "between the line and the plane"
    else:
        value, how = acute(va, vb), "between the lines" if ka not in ("plane", "median-plane") else "between the planes"
    margin, extra = _limits(tol, value)
    return Measurement(value, "angle", how, len(fd.points) + len(other.points), {}, margin=margin, extra=extra)
