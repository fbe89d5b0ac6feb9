"""The 3-2-1 datum frame of Sec. 5.4.1 (Eqs. 5.13-5.19).

The locator surfaces are scanned in the scanner frame. Their support planes are
found in sequence, each by the virtual-gage LP (Eq. 5.13 "can be reduced to the
linear programming formulation given in Eq. 5.5") on the convex-hull vertices of
its points, re-linearised about the exact rotation:

* primary (z): min over the plane of the largest distance of its points, with all
  points on the locator side (Eq. 5.13);
* secondary (y): the same with the normal kept perpendicular to the primary normal
  (Eq. 5.14);
* tertiary (x): normal n_x = n_y x n_z, placed against its points (Eq. 5.15).

Sign convention: each datum normal points from the locators towards the part, and
the plane touches its locator points on the part side - where the part rests. The
part side of a datum is where the other two datums' points are (the mean of their
centroids): the locators of a 3-2-1 fixture all touch the part, each on a face that
stands on the material side of the other two. Only the datum regions' points decide
it, never the whole cloud, which holds more than the part (a fixture, the machine
table, a second part). The origin solves the three
plane equations (Eq. 5.16); C_L^S has the normals as columns and the origin as
translation (Eq. 5.17), and H = (C_L^S)^-1 brings the cloud into the part frame
(Eqs. 5.18-5.19).

Of each datum's points the fit needs only their convex-hull vertices (the support LPs:
a linear constraint that holds at the hull vertices holds everywhere) and their first and
second moments (the least-squares start directions and the part side): :class:`DatumStats`,
from the compensated sums of ``_core.cloud.point_moments``, which a streamed read
continues chunk by chunk to the same bits. So a datum region costs the same memory
whether it holds a thousand points or a hundred million.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _core
from ..errors import DegenerateGeometryError, NumericalError


@dataclass(frozen=True)
class DatumPlane:
    """A fitted datum plane n . r + d = 0 in the scanner frame (n towards the part)."""

    name: str
    regions: tuple[str, ...]
    normal: tuple[float, float, float]
    d: float
    points: int
    filtered_points: int
    zone: float
    """largest distance of a datum point from its plane (mm): the flatness of the support"""

    def to_dict(self) -> dict:
        return {"name": self.name, "regions": list(self.regions), "normal": list(self.normal), "d": self.d,
                "points": self.points, "filtered_points": self.filtered_points, "zone": self.zone}


@dataclass(frozen=True)
class Alignment:
    """The 3-2-1 frame: datum planes, the locator frame C_L^S (Eq. 5.17) and H (Eq. 5.19)."""

    primary: DatumPlane
    secondary: DatumPlane
    tertiary: DatumPlane
    origin: tuple[float, float, float]
    frame: np.ndarray
    """C_L^S, 4x4: part frame -> scanner frame"""
    H: np.ndarray
    """(C_L^S)^-1, 4x4: scanner frame -> part frame"""

    def to_part(self, points: np.ndarray) -> np.ndarray:
        """Scanner-frame points in the part frame (H applied)."""
        return apply(self.H, points)

    def to_dict(self) -> dict:
        return {"primary": self.primary.to_dict(), "secondary": self.secondary.to_dict(),
                "tertiary": self.tertiary.to_dict(), "origin": list(self.origin),
                "C_LS": self.frame.tolist(), "H": self.H.tolist()}


@dataclass(frozen=True)
class DatumStats:
    """The count, centroid and scatter matrix sum (p - mean)(p - mean)^T of a datum's
    points, from the flat moments of its regions (``_core.cloud.point_moments`` or
    ``cut_chunk``'s ``moments``), merged region by region by the parallel-axis rule
    (``_core.cloud.moments_scatter``)."""

    n: int
    mean: np.ndarray
    scatter: np.ndarray

    @staticmethod
    def of_moments(moments) -> "DatumStats":
        n, mean, scatter = _core.cloud.moments_scatter([np.ascontiguousarray(a, dtype=np.float64) for a in moments])
        return DatumStats(int(n), mean, scatter)

    @staticmethod
    def of_points(points: np.ndarray) -> "DatumStats":
        """Of (n, 3) points in order (one region)."""
        return DatumStats.of_moments([_core.cloud.point_moments(np.ascontiguousarray(points, dtype=np.float64))])

    def axes(self, scatter: "np.ndarray | None" = None) -> tuple[np.ndarray, np.ndarray]:
        """(singular values, right singular vectors as rows) of the centred points, largest
        first, from the eigen-decomposition of the scatter matrix (or of ``scatter``)."""
        w, v = np.linalg.eigh(self.scatter if scatter is None else scatter)
        return np.sqrt(np.maximum(w[::-1], 0.0)), v[:, ::-1].T


def apply(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """A 4x4 homogeneous transform applied to (n, 3) points."""
    pts = np.asarray(points, dtype=np.float64)
    return pts @ T[:3, :3].T + T[:3, 3]


def _support(points: np.ndarray, basis: np.ndarray, axis: int, free: list[bool], extent: float):
    """Support plane by the gage LP in a local frame whose columns are ``basis``.

    In local coordinates the gage is -x_axis >= 0 (points behind the plane); the LP
    moves the points (free motions of Eq. 5.2) to minimise their largest distance.
    Returns the unit normal (scanner frame, towards the part) and d, and the zone.
    """
    c = points.mean(axis=0)
    local = (points - c) @ basis
    plane = np.zeros((1, 4))
    plane[0, axis] = -1.0
    sol = _core.gage.solve(np.ascontiguousarray(local), [0, len(local)], plane, np.ones(1), np.full(1, 10.0),
                           free, 0.3, 2.0 * extent + 1.0, groups=False)
    if sol.s[0] > 0 or sol.active_bounds:
        raise NumericalError("alignment: the support-plane fit of a datum did not settle within its search range")
    M = np.asarray(sol.matrix)
    R, t = M[:3, :3], M[:3, 3]
    e = np.zeros(3)
    e[axis] = 1.0
    n_local = R.T @ e          # plane in local coords: n_local . r' + t[axis] <= 0 for all points
    n = basis @ n_local
    d = float(t[axis] - n @ c)
    return n, d, float(sol.q[0])


def _oriented(n: np.ndarray, towards: np.ndarray) -> np.ndarray:
    return n if n @ towards >= 0 else -n


def _material_side(groups: dict, key: str) -> np.ndarray:
    """A point on the material side of datum ``key``: the mean of the centroids of the
    other two datums' points (see the module docstring)."""
    return np.mean([groups[k][1].mean for k in ("primary", "secondary", "tertiary") if k != key], axis=0)


def fit_321(groups: dict) -> Alignment:
    """Fit the 3-2-1 frame.

    ``groups`` maps ``"primary"``, ``"secondary"``, ``"tertiary"`` to
    ``(region names, DatumStats of all their points, hull-vertex points)`` in the scanner
    frame; the part side of each datum comes from the other datums' points
    (:func:`_material_side`).
    """
    for key in ("primary", "secondary", "tertiary"):
        if groups[key][1].n == 0:
            raise DegenerateGeometryError(f"alignment: the {key} datum ({', '.join(groups[key][0])}) has no points")
    fitted = {}
    # primary: least-squares normal as the start, then Eq. 5.13
    names, allp, pts = groups["primary"]
    if len(pts) < 3:
        raise DegenerateGeometryError(f"alignment: the primary datum ({', '.join(names)}) has {len(pts)} "
                                      "points; a plane needs at least 3")
    c = pts.mean(axis=0)
    sv, vt = allp.axes()
    # from the scatter matrix: exactly collinear points leave rounding of about 1e-8 of
    # the largest singular value
    if allp.n < 2 or sv[1] <= 1e-6 * max(sv[0], 1e-300):
        raise DegenerateGeometryError(f"alignment: the primary datum points ({', '.join(names)}) are collinear; "
                                      "they do not determine a plane")
    extent = float(np.ptp(np.vstack([g[2] for g in groups.values() if len(g[2])]), axis=0).max())
    nz0 = _oriented(vt[2], _material_side(groups, "primary") - c)
    e1 = np.cross([0.0, 1.0, 0.0], nz0)
    if np.linalg.norm(e1) < 0.5:
        e1 = np.cross([1.0, 0.0, 0.0], nz0)
    e1 /= np.linalg.norm(e1)
    basis = np.column_stack([e1, np.cross(nz0, e1), nz0])
    nz, dz, zone = _support(pts, basis, 2, [False, True, True, False, False, True], extent)
    fitted["primary"] = (nz, dz, zone)

    # secondary: normal perpendicular to nz (Eq. 5.14); start: across the points'
    # main direction in the plane perpendicular to nz
    names, allp, pts = groups["secondary"]
    if len(pts) < 2:
        raise DegenerateGeometryError(f"alignment: the secondary datum ({', '.join(names)}) has {len(pts)} "
                                      "points; it needs at least 2")
    c = pts.mean(axis=0)
    sv3, vt3 = allp.axes()
    if allp.n >= 3 and sv3[1] > 1e-6 * max(1.0, extent):
        # the points span a plane: it must stand across the primary
        cosang = abs(vt3[2] @ nz)
        if cosang > math.cos(math.radians(45.0)):
            raise DegenerateGeometryError(
                f"alignment: the secondary datum ({', '.join(names)}) is at {math.degrees(math.acos(min(1.0, cosang))):.1f} "
                "deg to the primary; it must be roughly perpendicular to determine the y direction")
        ny0 = vt3[2] - (vt3[2] @ nz) * nz
    else:
        # collinear points: the plane through their line perpendicular to the primary
        P = np.eye(3) - np.outer(nz, nz)
        sv, vt = allp.axes(P @ allp.scatter @ P)
        if sv[0] <= 1e-9 * max(1.0, extent):
            raise DegenerateGeometryError(f"alignment: the secondary datum points ({', '.join(names)}) lie on a line "
                                          "parallel to the primary normal; they do not determine a plane")
        ny0 = np.cross(nz, vt[0])
    side = _material_side(groups, "secondary") - c
    ny0 = _oriented(ny0 / np.linalg.norm(ny0), side)
    if abs(ny0 @ side) < 1e-9:
        raise DegenerateGeometryError("alignment: the primary and tertiary datums lie in the plane of the secondary; "
                                      "cannot tell which side the part is on")
    basis = np.column_stack([np.cross(ny0, nz), ny0, nz])
    ny, dy, zone = _support(pts, basis, 1, [True, False, False, False, True, False], extent)
    ny = ny - (ny @ nz) * nz
    ny /= np.linalg.norm(ny)
    fitted["secondary"] = (ny, dy, zone)

    # tertiary: n_x = n_y x n_z, placed against its points (Eq. 5.15)
    names, allp, pts = groups["tertiary"]
    if len(pts) < 1:
        raise DegenerateGeometryError(f"alignment: the tertiary datum ({', '.join(names)}) has no points")
    nx = np.cross(ny, nz)
    c = pts.mean(axis=0)
    if nx @ (_material_side(groups, "tertiary") - c) <= 0:
        raise DegenerateGeometryError(
            f"alignment: the part lies on the -x side of the tertiary datum ({', '.join(names)}); with the primary "
            "(z) and secondary (y) datums given, x = y cross z must point into the part: check the datum regions")
    h = pts @ nx
    dx = float(-h.max())
    fitted["tertiary"] = (nx, dx, float(h.max() - h.min()))

    N = np.vstack([fitted[k][0] for k in ("tertiary", "secondary", "primary")])
    dvec = np.array([fitted[k][1] for k in ("tertiary", "secondary", "primary")])
    if abs(np.linalg.det(N)) < 1e-9:
        raise DegenerateGeometryError("alignment: the datum planes do not determine a frame")
    origin = -np.linalg.solve(N, dvec)                       # Eq. 5.16
    C = np.eye(4)
    C[:3, :3] = N.T                                          # columns n_x, n_y, n_z (Eq. 5.17)
    C[:3, 3] = origin
    H = np.eye(4)
    H[:3, :3] = N                                            # (C_L^S)^-1 (Eq. 5.19)
    H[:3, 3] = -N @ origin
    planes = {}
    for key, label in (("primary", "z"), ("secondary", "y"), ("tertiary", "x")):
        n, d, zone = fitted[key]
        planes[key] = DatumPlane(label, tuple(groups[key][0]), tuple(float(v) for v in n), float(d),
                                 groups[key][1].n, len(groups[key][2]), zone)
    return Alignment(planes["primary"], planes["secondary"], planes["tertiary"],
                     tuple(float(v) for v in origin), C, H)
