"""The nominal geometry of a QIF feature as gagekit needs it: the PART.toml shape, its
region box (Sec. 5.4.1) and points sampled on the nominal surface.

The sampled points serve twice: the importer simulates the datums on them (the same
:class:`~gagekit.inspect.datums.DatumSystem` the inspection runs) to express basic
locations in each datum reference frame, and a synthetic scan made from the nominals
checks a model end to end.

Regions (all in the model's frame, mm): a plane -- the bounding rectangle of its boundary
(``PolyLine``) in the plane, shrunk by ``inset`` on every side, ``2 band`` thick; a
cylinder -- a box along the axis, ``diameter + 2 band`` square, the length less ``inset``
at each end (so the faces it meets stay out); a circle -- ``diameter + 2 band`` square,
``2 band`` thick; a sphere -- a cube of ``diameter + 2 band``; a line -- its length less
``inset`` at each end, ``2 band`` square. The scan must be in the model's coordinate
system (align it first).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from .._rotation import rotation_vector
from .model import FeatureNominal

__all__ = ["SHAPE_OF", "Region", "feature_region", "sample_feature", "basis"]

#: QIF feature type -> PART.toml shape
SHAPE_OF = {"Plane": "plane", "Cylinder": "cylinder", "Circle": "circle", "Sphere": "sphere", "Line": "line", "Cone": "cone"}

#: side of the square region of a plane the model gives no boundary for (mm)
DEFAULT_PLANE_SIZE = 10.0


@dataclass
class Region:
    center: tuple
    size: tuple
    rotation: tuple
    note: str = ""

    def to_dict(self) -> dict:
        return {"center": list(self.center), "size": list(self.size), "rotation": list(self.rotation)}


def basis(n: Any) -> np.ndarray:
    """Rows u, v, n: a right-handed orthonormal frame with third axis ``n``; u is the
    world axis most normal to n, projected (boxes align with an axis-parallel part)."""
    n = np.asarray(n, dtype=float)
    n = n / np.linalg.norm(n)
    k = int(np.argmin(np.abs(n)))
    e = np.zeros(3)
    e[k] = 1.0
    if k == 2 and abs(n[0]) < 0.9:  # prefer x as the box's first axis when it lies in the plane
        e = np.array([1.0, 0.0, 0.0])
    u = e - (e @ n) * n
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(n, u), n])


def _rot(B: np.ndarray) -> tuple:
    return tuple(float(x) for x in rotation_vector(B.T))


def _missing(f: FeatureNominal, keys: tuple) -> Optional[str]:
    miss = [k for k in keys if f.geometry.get(k) is None]
    return f"the model gives no {', '.join(miss)} for {f.kind} feature nominal {f.id}" if miss else None


def slots_supported() -> bool:
    """Whether the installed PART.toml reader has the two-face ``slot`` / ``tab`` shapes
    (issue 25)."""
    from ..inspect.spec import SHAPES

    return "slot" in SHAPES and "tab" in SHAPES


def shape_of(f: FeatureNominal) -> Optional[str]:
    """The PART.toml shape of a QIF feature nominal, or None."""
    if f.kind == "OppositeParallelPlanes" and slots_supported():
        return "slot" if f.internal else "tab"
    return SHAPE_OF.get(f.kind)


def problem(f: FeatureNominal) -> Optional[str]:
    """Why this feature cannot become a PART.toml feature, or None."""
    if shape_of(f) is None:
        return f"{'an' if f.kind[0] in 'AEIOU' else 'a'} {f.kind} feature (gagekit's shapes: plane, cylinder, cone, circle, sphere, line" + \
            (", slot, tab)" if slots_supported() else ")")
    if f.kind == "OppositeParallelPlanes":
        return _missing(f, ("point", "normal", "width", "length_vector", "length", "depth"))
    need = {"Plane": ("location", "normal"), "Cylinder": ("point", "direction", "diameter"),
            "Cone": ("point", "direction", "diameter", "half_angle", "large_end"),
            "Circle": ("center", "normal", "diameter"), "Sphere": ("center", "diameter"), "Line": ("location", "direction")}
    return _missing(f, need[f.kind])


def _plane_extent(f: FeatureNominal, B: np.ndarray):
    g = f.geometry
    pl = g.get("polyline")
    if pl is None or len(pl) < 3:
        h = DEFAULT_PLANE_SIZE / 2
        return np.array([-h, -h]), np.array([h, h]), "the model gives no boundary (PolyLine): a 10 mm square about its Location"
    uv = (pl - g["location"]) @ B[:2].T
    return uv.min(axis=0), uv.max(axis=0), ""


def feature_region(f: FeatureNominal, band: float, inset: float) -> Region:
    """The region box of a feature (module docstring)."""
    g = f.geometry
    if f.kind == "Plane":
        B = basis(g["normal"])
        lo, hi, note = _plane_extent(f, B)
        c2 = (lo + hi) / 2
        size = np.maximum(hi - lo - 2 * inset, (hi - lo) / 2)
        center = g["location"] + c2[0] * B[0] + c2[1] * B[1]
        return Region(tuple(center), (float(size[0]), float(size[1]), 2 * band), _rot(B), note)
    if f.kind == "Cylinder":
        B = basis(g["direction"])
        d = g["diameter"]
        L, note = g.get("length"), ""
        if L is None:
            L, note = d, "the model gives no length: one diameter long from its AxisPoint"
        Lr = L - 2 * inset if L > 4 * inset else L / 2
        center = g["point"] + g["direction"] * L / 2
        return Region(tuple(center), (d + 2 * band, d + 2 * band, Lr), _rot(B), note)
    if f.kind == "OppositeParallelPlanes":
        B = _slot_axes(g)
        L, D = g["length"], g["depth"]
        size = (L - 2 * inset if L > 4 * inset else L / 2, D - 2 * inset if D > 4 * inset else D / 2, g["width"] + 2 * band)
        return Region(tuple(g["point"]), size, _rot(B))
    if f.kind == "Cone":
        B = basis(g["direction"])
        t0, t1 = _cone_span(g)
        d = _cone_diameter(g, max(abs(t0), abs(t1)))
        L = t1 - t0
        Lr = L - 2 * inset if L > 4 * inset else L / 2
        center = g["point"] + g["direction"] * (t0 + t1) / 2
        return Region(tuple(center), (d + 2 * band, d + 2 * band, Lr), _rot(B))
    if f.kind == "Circle":
        B = basis(g["normal"])
        d = g["diameter"]
        return Region(tuple(g["center"]), (d + 2 * band, d + 2 * band, 2 * band), _rot(B))
    if f.kind == "Sphere":
        d = g["diameter"] + 2 * band
        return Region(tuple(g["center"]), (d, d, d), (0.0, 0.0, 0.0))
    # Line
    n = g.get("normal")
    d = g["direction"]
    if n is None or abs(float(n @ d)) > 1e-6:
        B = basis(d)
        B = np.array([B[2], B[0], B[1]])
    else:
        B = np.array([d, n, np.cross(d, n)])
    L, note = g.get("length"), ""
    if L is None:
        L, note = 10.0, "the model gives no length: 10 mm from its Location"
    Lr = L - 2 * inset if L > 4 * inset else L / 2
    return Region(tuple(g["location"] + d * L / 2), (Lr, 2 * band, 2 * band), _rot(B), note)


def _slot_axes(g: dict) -> np.ndarray:
    """Rows: along the slot's length, along its depth, across its width (the centre
    plane's normal). QIF gives the CenterPlane (its Point at the middle of the slot), the
    LengthVector and the Length and Depth."""
    n = np.asarray(g["normal"], dtype=float)
    L = np.asarray(g["length_vector"], dtype=float)
    L = L - (L @ n) * n
    L /= np.linalg.norm(L)
    return np.array([L, np.cross(n, L), n])


def _cone_span(g: dict) -> tuple:
    """The cone's extent along its Direction from the AxisPoint (QIF: ``Diameter`` at the
    AxisPoint, the cone widening along ``Direction`` from ``SmallEndDistance`` (default 0)
    to ``LargeEndDistance``)."""
    t0 = g.get("small_end") or 0.0
    return float(t0), float(g["large_end"])


def _cone_diameter(g: dict, t: Any) -> Any:
    return g["diameter"] + 2 * np.asarray(t) * math.tan(math.radians(g["half_angle"]))


def _inside(poly: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Even-odd rule: which 2-D points lie inside the closed polygon."""
    x, y = pts[:, 0], pts[:, 1]
    inside = np.zeros(len(pts), dtype=bool)
    a = poly
    b = np.roll(poly, -1, axis=0)
    for (x1, y1), (x2, y2) in zip(a, b):
        cond = (y1 > y) != (y2 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
        inside ^= cond & (x < xi)
    return inside


def sample_feature(f: FeatureNominal, n: int = 2000) -> np.ndarray:
    """About ``n`` points on the feature's nominal surface (deterministic grid)."""
    g = f.geometry
    if f.kind == "Plane":
        B = basis(g["normal"])
        pl = g.get("polyline")
        lo, hi, _ = _plane_extent(f, B)
        h = math.sqrt(max((hi - lo).prod(), 1e-12) / n)
        us = np.arange(lo[0] + h / 2, hi[0], h)
        vs = np.arange(lo[1] + h / 2, hi[1], h)
        uv = np.array(np.meshgrid(us, vs)).reshape(2, -1).T
        if pl is not None and len(pl) >= 3:
            uv = uv[_inside((pl - g["location"]) @ B[:2].T, uv)]
        return g["location"] + uv @ B[:2]
    if f.kind == "Cylinder":
        B = basis(g["direction"])
        r = g["diameter"] / 2
        L = g.get("length") or g["diameter"]
        m = max(int(math.sqrt(n)), 8)
        t = np.linspace(0.0, 2 * math.pi, m, endpoint=False)
        z = np.linspace(0.0, L, m)
        T, Z = np.meshgrid(t, z)
        T, Z = T.ravel(), Z.ravel()
        return g["point"] + np.outer(r * np.cos(T), B[0]) + np.outer(r * np.sin(T), B[1]) + np.outer(Z, B[2])
    if f.kind == "OppositeParallelPlanes":  # the two faces, width apart about the centre plane
        B = _slot_axes(g)
        m = max(int(math.sqrt(n / 2)), 4)
        a, b = np.meshgrid(np.linspace(-g["length"] / 2, g["length"] / 2, m), np.linspace(-g["depth"] / 2, g["depth"] / 2, m))
        face = g["point"] + np.outer(a.ravel(), B[0]) + np.outer(b.ravel(), B[1])
        return np.vstack([face + B[2] * g["width"] / 2, face - B[2] * g["width"] / 2])
    if f.kind == "Cone":
        B = basis(g["direction"])
        t0, t1 = _cone_span(g)
        m = max(int(math.sqrt(n)), 8)
        T, Z = np.meshgrid(np.linspace(0.0, 2 * math.pi, m, endpoint=False), np.linspace(t0, t1, m))
        T, Z = T.ravel(), Z.ravel()
        r = _cone_diameter(g, Z) / 2
        return g["point"] + np.outer(r * np.cos(T), B[0]) + np.outer(r * np.sin(T), B[1]) + np.outer(Z, B[2])
    if f.kind == "Circle":
        B = basis(g["normal"])
        r = g["diameter"] / 2
        t = np.linspace(0.0, 2 * math.pi, min(n, 720), endpoint=False)
        return g["center"] + np.outer(r * np.cos(t), B[0]) + np.outer(r * np.sin(t), B[1])
    if f.kind == "Sphere":
        k = np.arange(n) + 0.5
        phi = np.arccos(1 - 2 * k / n)
        th = math.pi * (1 + 5 ** 0.5) * k
        u = np.stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)], axis=1)
        return g["center"] + g["diameter"] / 2 * u
    L = g.get("length") or 10.0
    t = np.linspace(0.0, L, min(n, 500))
    return g["location"] + np.outer(t, g["direction"])
