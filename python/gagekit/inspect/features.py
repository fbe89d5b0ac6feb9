"""The scan's points of each feature and their associated (least-squares) geometry.

Each feature's points are the scan's points inside its region box (Sec. 5.4.1). Its
least-squares fit (ISO 14405 / ASME B89.4.10 geometric fits, :mod:`gagekit.form`) is the
reference for the point deviations shown in the report and the source of a cylinder's
or cone's **derived axis**:

- ``axis = "least-squares"`` (default): the least-squares axis limited to the span of the
  feature's points projected onto it -- a segment, what CMM software reports; its two
  end points stand for it in every convex tolerance zone (a segment lies in a convex
  zone when its ends do);
- ``axis = "median-line"``: the centres of the least-squares circles of ``sections``
  equal slices across the least-squares axis (the extracted median line, ISO 12180-1
  Sec. 3.3.4 / ISO 17450-3); the zone then contains every section centre.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateGeometryError
from ..form import fit_circle, fit_circle_3d, fit_cone, fit_cylinder, fit_line, fit_plane, fit_sphere
from .._rotation import rotation_from_vector
from .spec import MIN_POINTS, Feature

__all__ = ["FeatureData", "extract"]


def _unit(v: Any) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


@dataclass
class FeatureData:
    """A feature's points (``indices`` into the scan) and its fits, computed once."""

    spec: Feature
    indices: np.ndarray
    points: np.ndarray
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def shape(self) -> str:
        return self.spec.shape

    def box_axes(self) -> np.ndarray:
        """The region box's axes as rows (they move with the part); a feature given by CAD
        faces has the model's axes."""
        if self.spec.region is None:
            return np.eye(3)
        return rotation_from_vector(self.spec.region.rotation).T

    # -- least-squares fits ------------------------------------------------------------
    def lsq(self):
        if "lsq" not in self._cache:
            p, shape = self.points, self.shape
            if shape in ("slot", "tab"):
                fit = self.width_fit()
            elif shape == "plane":
                fit = fit_plane(p)
            elif shape == "line":
                fit = fit_line(p)
            elif shape == "circle":
                fit = fit_circle_3d(p)
            elif shape == "sphere":
                fit = fit_sphere(p)
            elif shape == "cylinder":
                fit = fit_cylinder(p, warm=self._cache.get("warm", {}).get("least-squares"))
            else:
                fit = fit_cone(p)
            self._cache["lsq"] = fit
        return self._cache["lsq"]

    def faces(self) -> tuple[np.ndarray, np.ndarray]:
        """The two faces of a slot or tab: the points split at the largest gap of their
        heights along ``direction`` (first face: the lower heights)."""
        if "faces" not in self._cache:
            d = _unit(self.spec.direction)
            h = self.points @ d
            order = np.argsort(h, kind="stable")
            gaps = np.diff(h[order])
            k = int(np.argmax(gaps)) + 1
            if k < 3 or len(h) - k < 3:
                raise DegenerateGeometryError(
                    f"feature '{self.name}': a {self.shape} needs two faces across its 'direction' with at least 3 points each; "
                    f"its points split into {k} and {len(h) - k} (check the region and the direction)")
            self._cache["faces"] = (np.ascontiguousarray(self.points[np.sort(order[:k])]),
                                    np.ascontiguousarray(self.points[np.sort(order[k:])]))
        return self._cache["faces"]

    def width_fit(self) -> "WidthFit":
        """Two parallel least-squares planes of a slot or tab (one normal for both faces:
        the eigenvector of least variance of the pooled, per-face centred points)."""
        a, b = self.faces()
        ca, cb = a.mean(axis=0), b.mean(axis=0)
        q = np.vstack([a - ca, b - cb])
        n = np.linalg.svd(q, full_matrices=False)[2][2]
        if float(n @ (cb - ca)) < 0:
            n = -n
        return WidthFit(self.shape, ca, cb, n, float((cb - ca) @ n), len(self.points))

    def sign_hint(self) -> np.ndarray:
        """The direction that fixes the sign of an axis: the feature's ``direction``, else
        the third axis of its region box (both move with the part)."""
        if self.spec.direction is not None:
            return _unit(self.spec.direction)
        return self.box_axes()[2]

    def axis_line(self) -> tuple[np.ndarray, np.ndarray]:
        """(point, unit direction) of the least-squares axis (cylinder, cone), the normal
        through the centre (circle) or the line (line), signed by :meth:`sign_hint`."""
        fit = self.lsq()
        if self.shape in ("cylinder", "cone"):
            p, d = np.array(fit.point), _unit(fit.direction)
        elif self.shape == "circle":
            p, d = np.array(fit.center), _unit(fit.normal)
        elif self.shape == "line":
            p, d = np.array(fit.point), _unit(fit.direction)
        else:
            raise DegenerateGeometryError(f"feature '{self.name}': a {self.shape} has no axis")
        if self.shape != "cone" and float(d @ self.sign_hint()) < 0:
            d = -d
        return p, d

    def chebyshev_cylinder(self, criterion: str) -> Any:
        """The minimax cylinder ``criterion`` (minimum-zone, min-circumscribed,
        max-inscribed) of the points, searched within 10 degrees of the least-squares axis
        (seed 0), computed once: cylindricity, a datum axis and a size share it. A Monte
        Carlo trial's feature holds the measured fits' axes in ``_cache["warm"]``
        ({criterion: (point, direction)}): the fit then starts from there
        (:func:`gagekit.form.fit_cylinder` ``warm=``; exact local method without basin
        hopping, the global search where it cannot decide). (A trial's plane holds the measured flatness
        zone's normal as ``"slab"``: :meth:`min_zone`.)"""
        key = ("cylinder", criterion)
        if key not in self._cache:
            _, d = self.axis_line()
            warm = self._cache.get("warm", {}).get(criterion)
            self._cache[key] = fit_cylinder(self.points, criterion, seed=0, axis=tuple(d), max_tilt=10.0, warm=warm)
        return self._cache[key]

    def min_zone(self) -> tuple[float, np.ndarray]:
        """(width, normal) of the minimum zone of the points (flatness, ISO 12781; exact: the
        minimum width of the set, hull facets and antipodal edge pairs), computed once: the
        flatness callout and the free datum plane share it. The normal points into the
        material (against ``outward``) when the feature has one."""
        if "mz" not in self._cache:
            near = self._cache.get("warm", {}).get("slab")  # a Monte Carlo trial: the measured zone's normal
            if near is not None:
                from ..form.active import thinnest_slab_near

                width, n = thinnest_slab_near(self.points, near)
            else:
                normal, _, _, width = _core.gdt.slab(self.points, "free", (0.0, 0.0, 1.0), 0.0)
                n = np.array(normal)
            if self.spec.outward is not None and float(n @ np.asarray(self.spec.outward)) > 0:
                n = -n  # the zone's normal reported into the material, as a datum frame's axis
            self._cache["mz"] = (float(width), n)
        return self._cache["mz"]

    def plane_normal_out(self) -> np.ndarray:
        """Least-squares normal of a plane feature, turned to its ``outward``."""
        n = _unit(self.lsq().normal)
        return n if float(n @ np.asarray(self.spec.outward)) >= 0 else -n

    # -- derived axis ------------------------------------------------------------------
    def axis_points(self, method: Optional[str] = None, sections: Optional[int] = None) -> np.ndarray:
        """The derived axis as points: the two ends of the least-squares axis limited to
        the span of the points, or the section centres of the median line."""
        method = method or self.spec.axis
        sections = sections or self.spec.sections
        key = ("axis", method, sections)
        if key not in self._cache:
            p0, d = self.axis_line()
            if self.shape == "circle":
                pts = p0[None, :]
            elif method == "least-squares":
                t = (self.points - p0) @ d
                pts = np.array([p0 + t.min() * d, p0 + t.max() * d])
            else:
                pts = np.array([c for c, _ in self.section_circles(sections)])
            self._cache[key] = pts
        return self._cache[key]

    def sections(self, count: int, origin: Optional[np.ndarray] = None, direction: Optional[np.ndarray] = None):
        """Indices of the points in ``count`` equal slices across an axis (default: the
        least-squares axis) covering the points' span; empty slices are skipped."""
        if origin is None or direction is None:
            origin, direction = self.axis_line()
        t = (self.points - origin) @ direction
        lo, hi = float(t.min()), float(t.max())
        if hi <= lo:
            return [np.arange(len(t))]
        k = np.minimum(((t - lo) / (hi - lo) * count).astype(np.int64), count - 1)
        order = np.argsort(k, kind="stable")
        bounds = np.searchsorted(k[order], np.arange(count + 1))
        return [order[bounds[i]:bounds[i + 1]] for i in range(count) if bounds[i + 1] > bounds[i]]

    def section_circles(self, count: int) -> list[tuple[np.ndarray, Any]]:
        """Least-squares circle of each section (projected along the least-squares axis):
        (centre in 3-D at the section's mean height, 2-D points) per section with >= 3 points."""
        p0, d = self.axis_line()
        u, v = _basis(d)
        out = []
        for idx in self.sections(count, p0, d):
            if len(idx) < 3:
                continue
            q = self.points[idx] - p0
            xy = np.ascontiguousarray(np.column_stack([q @ u, q @ v]))
            c = _core.form.fit_circle(xy, "least-squares").center
            h = float((q @ d).mean())
            out.append((p0 + c[0] * u + c[1] * v + h * d, xy))
        if len(out) < 2:
            raise DegenerateGeometryError(
                f"feature '{self.name}': fewer than 2 of its {count} sections hold 3 points; the median line needs more points")
        return out

    # -- deviations for the report -----------------------------------------------------
    def deviations(self) -> np.ndarray:
        """Signed deviation of every point from the least-squares feature (mm; positive
        outside the material for planes, away from the axis/centre otherwise)."""
        if "dev" in self._cache:
            return self._cache["dev"]
        if self.shape == "surface":  # from the CAD faces
            self._cache["dev"] = np.asarray(self._cache["cad"].distance)[self.indices]
            return self._cache["dev"]
        fit, p = self.lsq(), self.points
        if self.shape in ("slot", "tab"):
            # from each face's plane, positive into the air (out of the slot's walls, off the tab)
            h = (p - fit.point) @ fit.normal
            half = 0.5 * fit.size
            side = np.where(h >= 0, 1.0, -1.0)
            dev = side * h - half
            dev = dev if self.shape == "tab" else -dev
        elif self.shape == "plane":
            dev = (p - np.array(fit.point)) @ self.plane_normal_out()
        elif self.shape == "line":
            p0, d = self.axis_line()
            q = p - p0
            dev = np.linalg.norm(q - np.outer(q @ d, d), axis=1)
        elif self.shape == "sphere":
            dev = np.linalg.norm(p - np.array(fit.center), axis=1) - fit.radius
        elif self.shape == "cone":
            p0, d = np.array(fit.point), _unit(fit.direction)
            q = p - p0
            t = q @ d
            rho = np.linalg.norm(q - np.outer(t, d), axis=1)
            half = 0.5 * fit.apex_angle
            dev = rho * np.cos(half) - t * np.sin(half) - fit.distance
        else:  # cylinder, circle: radial
            p0, d = self.axis_line()
            q = p - p0
            r = np.linalg.norm(q - np.outer(q @ d, d), axis=1)
            dev = r - fit.radius
        self._cache["dev"] = dev
        return dev

    def to_dict(self) -> dict[str, Any]:
        if self.shape == "surface":  # its nominal is the CAD faces: no associated feature
            return {"shape": self.shape, "n_points": int(len(self.points)), "faces": list(self.spec.faces)}
        d = self.lsq().to_dict()
        d = {"shape": self.shape, "n_points": int(len(self.points)), "least_squares": d}
        if self.shape in ("cylinder", "cone"):
            d["derived_axis"] = {"method": self.spec.axis, "points": self.axis_points().tolist()}
        return d


@dataclass(frozen=True)
class WidthFit:
    """Least-squares slot / tab: two parallel planes through the face centroids
    ``point_a``, ``point_b`` with the common ``normal`` (from face a to face b); ``size``
    their distance (ISO 14405-1 GG of a width)."""

    shape: str
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    size: float
    n_points: int

    @property
    def point(self) -> np.ndarray:
        """A point of the median plane."""
        return 0.5 * (self.point_a + self.point_b)

    def to_dict(self) -> dict[str, Any]:
        return {"criterion": "least-squares", "median_point": self.point.tolist(), "normal": self.normal.tolist(),
                "size": self.size, "n_points": self.n_points}


def _basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The orthonormal pair of gagekit-gdt's vec3::basis (Frisvad, Duff et al.)."""
    s = 1.0 if d[2] >= 0 else -1.0
    a = -1.0 / (s + d[2])
    b = d[0] * d[1] * a
    return np.array([1.0 + s * d[0] * d[0] * a, s * b, -s * d[0]]), np.array([b, s + d[1] * d[1] * a, -d[1]])


def extract(points: np.ndarray, features: dict[str, Feature], source: str = "part", cad: Any = None) -> dict[str, FeatureData]:
    """Cut every feature's points out of the scan (one parallel pass over the boxes); a
    feature given by CAD ``faces`` takes the points nearest to them (``cad``: a
    :class:`gagekit.cad.features.CadContext` over the same points)."""
    from ..cloud.regions import classify

    names = [n for n in features if features[n].region is not None]
    idx = dict(zip(names, classify(points, [features[n].region for n in names]))) if names else {}
    cut = []
    for name, f in features.items():
        if name in idx:
            ids = idx[name]
        else:
            if cad is None:
                raise DegenerateGeometryError(f"{source}: [[feature]] '{name}': 'faces' needs the [part] cad model")
            ids = cad.indices(f, f"{source}: [[feature]] '{name}'")
        cut.append((ids, points[ids]))
    return _feature_data(features, cut, source, cad)


def extract_stream(chunks, features: dict[str, Feature], source: str = "part") -> tuple[int, dict[str, FeatureData]]:
    """:func:`extract` of a streamed scan (chunks in file order, :mod:`gagekit.cloud.streamed`):
    (number of points, the features), the same points and point numbers as a whole read."""
    from ..cloud.streamed import cut_stream

    if any(f.region is None for f in features.values()):
        raise DegenerateGeometryError(f"{source}: features given by CAD 'faces' need the whole scan (not streamed)")
    names = list(features)
    p = cut_stream(chunks, [features[n].region for n in names], ["all"] * len(names))
    return p.count, _feature_data(features, [(r.index_array(), r.point_array()) for r in p.regions], source)


def _feature_data(features: dict[str, Feature], cut: list, source: str, cad: Any = None) -> dict[str, FeatureData]:
    out: dict[str, FeatureData] = {}
    for name, (ids, pts) in zip(list(features), cut):
        f = features[name]
        what = "'region' holds" if f.region is not None else "its faces hold"
        need = MIN_POINTS[f.shape]
        if len(ids) < need:
            raise DegenerateGeometryError(
                f"{source}: [[feature]] '{name}': {what} {len(ids)} point(s) of the scan; a {f.shape} needs at "
                f"least {need} (check the region's center, size and rotation, and the scan's units)")
        fd = FeatureData(f, ids, np.ascontiguousarray(pts))
        if cad is not None:
            fd._cache["cad"] = cad
        out[name] = fd
    return out
