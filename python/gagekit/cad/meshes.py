"""Mesh files: STL (ASCII and binary), OBJ, PLY with faces. They carry no unit: the
caller gives it (``--cad-units``, default mm).

- STL: binary when the size is 84 + 50 n bytes for the count n in its header (some binary
  files begin with ``solid`` too), ASCII otherwise (``vertex x y z`` lines). Corners are
  welded where their coordinates are equal (STL repeats them per facet).
- OBJ: ``v`` and ``f`` lines (``f a/b/c ...``, negative indices, polygons split into fans);
  ``g`` / ``o`` groups become faces, so per-face statistics follow the file's groups.
- PLY (plyfile): ``vertex`` x, y, z and ``face`` ``vertex_indices`` (or ``vertex_index``).

Every malformed file is a :class:`~gagekit.errors.FileFormatError` naming it.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import FileFormatError
from .model import CadFace

__all__ = ["read_stl", "read_obj", "read_ply_mesh", "weld"]


def weld(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of (m, 3, 3) triangle corners, equal corners merged."""
    flat = np.ascontiguousarray(corners.reshape(-1, 3), dtype=np.float64)
    flat = flat + 0.0  # -0.0 and 0.0 are the same corner
    view = flat.view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(view, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # vertices in order of first use
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return flat[first[order]], rank[inverse.ravel()].reshape(-1, 3).astype(np.int64)


def read_stl(p: Path, data: bytes) -> tuple[np.ndarray, np.ndarray, list[CadFace], np.ndarray]:
    if len(data) >= 84:
        n = int.from_bytes(data[80:84], "little")
        if len(data) == 84 + 50 * n and (n > 0 or not data.lstrip().startswith(b"solid")):
            if n == 0:
                raise FileFormatError(f"{p}: the binary STL holds no triangles")
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=n, offset=84)
            v, t = weld(rec["v"].astype(np.float64))
            return v, t, [CadFace(0, 0, p.stem)], np.zeros(len(t), dtype=np.int64)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise FileFormatError(f"{p}: neither a binary STL (its size does not match the triangle count) nor an ASCII one") from None
    if not text.lstrip().lower().startswith("solid"):
        raise FileFormatError(f"{p}: not an STL file (an ASCII STL begins with 'solid')")
    nums = re.findall(r"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)", text, flags=re.M)
    if not nums:
        raise FileFormatError(f"{p}: the ASCII STL holds no 'vertex' lines")
    if len(nums) % 3:
        raise FileFormatError(f"{p}: {len(nums)} vertex lines, not a multiple of 3 (a facet is cut short)")
    try:
        corners = np.array(nums, dtype=np.float64).reshape(-1, 3, 3)
    except ValueError as exc:
        raise FileFormatError(f"{p}: a vertex line holds a value that is not a number ({exc})") from None
    v, t = weld(corners)
    return v, t, [CadFace(0, 0, p.stem)], np.zeros(len(t), dtype=np.int64)


def read_obj(p: Path, text: str) -> tuple[np.ndarray, np.ndarray, list[CadFace], np.ndarray]:
    verts: list[list[float]] = []
    tris: list[tuple[int, int, int]] = []
    tri_group: list[int] = []
    groups: dict[str, int] = {}
    group = 0
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts or parts[0].startswith("#"):
            continue
        key = parts[0]
        try:
            if key == "v":
                if len(parts) < 4:
                    raise ValueError("a vertex needs x y z")
                verts.append([float(parts[1]), float(parts[2]), float(parts[3])])
            elif key == "f":
                idx = []
                for tok in parts[1:]:
                    k = int(tok.split("/")[0])
                    k = k - 1 if k > 0 else len(verts) + k
                    if not 0 <= k < len(verts):
                        raise ValueError(f"face names vertex {tok.split('/')[0]}, which is not defined before it")
                    idx.append(k)
                if len(idx) < 3:
                    raise ValueError("a face needs at least 3 vertices")
                for j in range(1, len(idx) - 1):
                    tris.append((idx[0], idx[j], idx[j + 1]))
                    tri_group.append(group)
            elif key in ("g", "o"):
                name = " ".join(parts[1:]) or "default"
                group = groups.setdefault(name, len(groups))
        except ValueError as exc:
            raise FileFormatError(f"{p}: line {lineno}: {exc}") from None
    if not tris:
        raise FileFormatError(f"{p}: the OBJ file holds no faces ('f' lines)")
    names = {v: k for k, v in groups.items()}
    used = sorted(set(tri_group))
    remap = {g: i for i, g in enumerate(used)}
    faces = [CadFace(i, i, names.get(g, p.stem)) for i, g in enumerate(used)]
    return (np.array(verts, dtype=np.float64), np.array(tris, dtype=np.int64), faces,
            np.array([remap[g] for g in tri_group], dtype=np.int64))


def read_ply_mesh(p: Path) -> tuple[np.ndarray, np.ndarray, list[CadFace], np.ndarray]:
    from plyfile import PlyData

    try:
        ply = PlyData.read(str(p))
    except Exception as exc:  # plyfile raises several types for damaged headers and bodies
        raise FileFormatError(f"{p}: not a readable PLY file ({exc})") from None
    names = [e.name for e in ply.elements]
    if "vertex" not in names:
        raise FileFormatError(f"{p}: the PLY file has no 'vertex' element")
    if "face" not in names or ply["face"].count == 0:
        raise FileFormatError(f"{p}: the PLY file has no faces (a point cloud, not a mesh); give it as the scan")
    vx = ply["vertex"]
    try:
        v = np.column_stack([np.asarray(vx[k], dtype=np.float64) for k in ("x", "y", "z")])
    except (KeyError, ValueError):
        raise FileFormatError(f"{p}: the vertices need x, y and z properties") from None
    fprops = [q.name for q in ply["face"].properties]
    key = "vertex_indices" if "vertex_indices" in fprops else ("vertex_index" if "vertex_index" in fprops else None)
    if key is None:
        raise FileFormatError(f"{p}: the faces have no 'vertex_indices' property")
    tris = []
    for poly in ply["face"][key]:
        poly = np.asarray(poly, dtype=np.int64)
        if len(poly) < 3:
            raise FileFormatError(f"{p}: a face has fewer than 3 vertices")
        for j in range(1, len(poly) - 1):
            tris.append((poly[0], poly[j], poly[j + 1]))
    t = np.array(tris, dtype=np.int64)
    if t.min() < 0 or t.max() >= len(v):
        raise FileFormatError(f"{p}: a face names a vertex that does not exist")
    return v, t, [CadFace(0, 0, p.stem)], np.zeros(len(t), dtype=np.int64)
