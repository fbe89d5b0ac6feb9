"""The CAD model as gagekit uses it: a triangle mesh in millimetres whose triangles know
their CAD face, the faces (STEP ids and names), and the distance kernel built once.

Distances come from the Rust kernel ``gagekit-mesh`` (:class:`gagekit._core.mesh.Mesh`): a BVH
over the triangles, the exact closest point of the nearest triangle, the sign from the
angle-weighted pseudonormal (Baerentzen and Aanaes 2005), positive outside the material.
A STEP model adds a refinement on its exact faces (:mod:`.step`), so its distances are
to the exact surface, not to the tessellation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import numpy as np

__all__ = ["CadFace", "CadModel", "Distances", "transform"]


@dataclass(frozen=True)
class CadFace:
    """One face of the model: ``index`` (0-based, the order of ``faces``), ``id`` (the STEP
    entity number ``#id`` of its ADVANCED_FACE, or the group's number for meshes),
    ``name`` (the STEP name or the OBJ group; may be empty) and the surface ``kind``."""

    index: int
    id: int
    name: str
    kind: str = "mesh"

    @property
    def label(self) -> str:
        return self.name or f"#{self.id}"

    def to_dict(self) -> dict[str, Any]:
        return {"index": self.index, "id": self.id, "name": self.name, "kind": self.kind}


@dataclass(frozen=True)
class Distances:
    """Per point: the signed distance (mm; NaN where beyond ``max_distance``), the nearest
    triangle and face (-1 beyond), the closest point of the surface; ``signed`` is False
    for an open mesh (distances are then unsigned)."""

    distance: np.ndarray
    triangle: np.ndarray
    face: np.ndarray
    foot: Optional[np.ndarray]
    n_beyond: int
    signed: bool
    refined: int = 0


@dataclass(eq=False)
class CadModel:
    """A CAD model read by :func:`gagekit.cad.read_cad` (millimetres)."""

    path: str
    format: str
    unit: str
    vertices: np.ndarray
    triangles: np.ndarray
    triangle_face: np.ndarray
    faces: tuple[CadFace, ...]
    warnings: tuple[str, ...] = ()
    method: str = "exact distances to the mesh's triangles"
    #: exact-surface refinement (STEP): (points, distances, triangles, feet) -> (distances, refined count)
    refine: Optional[Callable[..., Any]] = field(default=None, repr=False)
    _mesh: Any = field(default=None, repr=False)

    @property
    def mesh(self):
        """The kernel's mesh (BVH, topology, pseudonormals), built on first use."""
        if self._mesh is None:
            from .. import _core

            self._mesh = _core.mesh.Mesh(np.ascontiguousarray(self.vertices, dtype=np.float64),
                                    np.ascontiguousarray(self.triangles, dtype=np.int64))
        return self._mesh

    @property
    def signed(self) -> bool:
        return bool(self.mesh.signed)

    def face_index(self, key: Any, where: str = "faces") -> int:
        """The index of the face named by ``key``: a STEP id (int, or "#12") or a name."""
        from ..errors import ConfigError

        if isinstance(key, bool):
            raise ConfigError(f"{where}: {key!r} is not a face id or name")
        if isinstance(key, str) and key.startswith("#") and key[1:].isdigit():
            key = int(key[1:])
        if isinstance(key, int):
            for f in self.faces:
                if f.id == key:
                    return f.index
            raise ConfigError(f"{where}: no face has the id #{key} in {self.path}")
        if isinstance(key, str):
            hits = [f.index for f in self.faces if f.name == key]
            if len(hits) == 1:
                return hits[0]
            if len(hits) > 1:
                raise ConfigError(f"{where}: {len(hits)} faces are named {key!r} in {self.path}; use their ids")
            raise ConfigError(f"{where}: no face is named {key!r} in {self.path}")
        raise ConfigError(f"{where}: {key!r} is not a face id or name")

    def distances(self, points: Any, max_distance: Optional[float] = None, foot: bool = False) -> Distances:
        """Signed distances of (n, 3) points (mm) to the model's surface (see the module
        docstring); a STEP model's are refined onto its exact faces."""
        pts = np.ascontiguousarray(points, dtype=np.float64)
        want_foot = foot or self.refine is not None
        d, tri, ft, beyond, signed = self.mesh.distances(pts, max_distance, False, want_foot)
        refined = 0
        if self.refine is not None and len(pts):
            d, refined = self.refine(pts, d, tri, ft)
        face = np.where(tri >= 0, self.triangle_face[np.maximum(tri, 0)], -1)
        return Distances(d, tri, face, ft if foot else None, int(beyond), bool(signed), refined)

    def to_dict(self) -> dict[str, Any]:
        return {"file": self.path, "unit": self.unit, "faces": len(self.faces), "triangles": int(len(self.triangles))}


def transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4x4 rigid motion to (n, 3) points."""
    m = np.asarray(matrix, dtype=float)
    return np.ascontiguousarray(points @ m[:3, :3].T + m[:3, 3])
