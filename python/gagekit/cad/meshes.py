"""Mesh files: STL (ASCII and binary), OBJ, PLY with faces. They carry no unit: the
caller gives it (``--cad-units``, default mm).

- STL: binary when the size is 84 + 50 n bytes for the count n in its header (some binary
  files begin with ``solid`` too), ASCII otherwise (``vertex x y z`` lines). Corners are
  welded where their coordinates are equal (STL repeats them per facet).
- OBJ: ``v`` and ``f`` lines (``f a/b/c ...``, negative indices, polygons split into fans);
  ``g`` / ``o`` groups become faces, so per-face statistics follow the file's groups.
- PLY (plyfile): ``vertex`` x, y, z and ``face`` ``vertex_indices`` (or ``vertex_index``).
- 3MF (3D Manufacturing Format core specification 1.3): a zip whose start part (named by
  ``_rels/.rels``, else ``3D/3dmodel.model``) is one XML ``<model unit="...">``; every
  ``<build><item>`` places an ``<object>`` (a ``<mesh>`` of ``<vertex x y z>`` and
  ``<triangle v1 v2 v3>``, or ``<components>`` of other objects) by its 3x4 ``transform``
  (row vectors: ``[x y z 1] M``). Each build item becomes a face (its object's ``name``).
  The unit is the file's (``micron``, ``millimeter`` (default), ``centimeter``, ``inch``,
  ``foot``, ``meter``), read with the standard library's XML parser (expat: no external
  entities, bounded entity expansion).

Every malformed file is a :class:`~gagekit.errors.FileFormatError` naming it.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import FileFormatError
from .model import CadFace

__all__ = ["read_stl", "read_obj", "read_ply_mesh", "read_3mf", "weld", "UNITS_3MF"]

#: The unit names of 3MF's ``<model unit>`` and gagekit's.
UNITS_3MF = {"micron": "um", "millimeter": "mm", "centimeter": "cm", "inch": "in", "foot": "ft", "meter": "m"}
_NS_3MF = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"
#: Largest uncompressed model part read (bytes): a zip bomb stops here, not in memory.
MAX_3MF_MODEL = 2 * 1024 ** 3


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


def _binary_size_note(data: bytes) -> str:
    """Why ``data`` is no binary STL, in numbers: its header's triangle count against its size."""
    if len(data) < 84:
        return f"a binary STL has an 84-byte header, the file has {len(data)} bytes"
    n = int.from_bytes(data[80:84], "little")
    want = 84 + 50 * n
    cut = "cut short" if len(data) < want else "extra bytes"
    return f"as a binary STL its header declares {n} triangles ({want} bytes), the file has {len(data)} bytes ({cut})"


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
        raise FileFormatError(f"{p}: neither a binary STL ({_binary_size_note(data)}) nor an ASCII one (not text)") from None
    if not text.lstrip().lower().startswith("solid"):
        raise FileFormatError(f"{p}: not an STL file: {_binary_size_note(data)}; an ASCII STL would begin with 'solid'")
    nums = re.findall(r"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)", text, flags=re.M)
    if not nums:
        # many binary STLs begin their header with "solid" too: say both readings
        raise FileFormatError(f"{p}: read as an ASCII STL (it begins with 'solid') it holds no 'vertex' lines; {_binary_size_note(data)}")
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


def read_3mf(p: Path) -> tuple[np.ndarray, np.ndarray, list[CadFace], np.ndarray, str]:
    """(vertices, triangles, faces, triangle face, unit) of a 3MF file (module docstring)."""
    import re as _re
    import xml.etree.ElementTree as ET
    import zipfile

    try:
        zf = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError) as exc:
        raise FileFormatError(f"{p}: not a 3MF file (a 3MF file is a zip archive: {exc})") from None
    with zf:
        names = set(zf.namelist())
        part = None
        if "_rels/.rels" in names:
            try:
                rels = ET.fromstring(zf.read("_rels/.rels"))
            except ET.ParseError as exc:
                raise FileFormatError(f"{p}: _rels/.rels is not valid XML ({exc})") from None
            for r in rels.iter():
                if r.tag.endswith("Relationship") and str(r.get("Type", "")).endswith("/3dmodel"):
                    part = str(r.get("Target", "")).lstrip("/")
                    break
        if part is None or part not in names:
            part = "3D/3dmodel.model" if "3D/3dmodel.model" in names else next(
                (n for n in sorted(names) if n.lower().endswith(".model")), None)
        if part is None:
            raise FileFormatError(f"{p}: the 3MF archive holds no 3D model part (3D/3dmodel.model)")
        if zf.getinfo(part).file_size > MAX_3MF_MODEL:
            raise FileFormatError(f"{p}: the 3MF model part is larger than {MAX_3MF_MODEL} bytes uncompressed")
        try:
            root = ET.fromstring(zf.read(part))
        except ET.ParseError as exc:
            raise FileFormatError(f"{p}: {part} is not valid XML ({exc})") from None
        except (zipfile.BadZipFile, OSError, EOFError) as exc:
            raise FileFormatError(f"{p}: {part} cannot be read from the archive ({exc})") from None
    if root.tag != f"{_NS_3MF}model":
        raise FileFormatError(f"{p}: {part} is not a 3MF core <model> (root element {root.tag!r})")
    unit_name = root.get("unit", "millimeter")
    if unit_name not in UNITS_3MF:
        raise FileFormatError(f"{p}: unknown 3MF unit {unit_name!r}; the specification allows {', '.join(UNITS_3MF)}")
    objects = {}
    for obj in root.iter(f"{_NS_3MF}object"):
        objects[obj.get("id")] = obj

    def number(e, key: str) -> float:
        try:
            v = float(e.get(key, ""))
        except ValueError:
            raise FileFormatError(f"{p}: <{e.tag.split('}')[-1]}> has {key}={e.get(key)!r}, not a number") from None
        return v

    def matrix(text) -> np.ndarray:
        m = np.eye(4)
        if text is None:
            return m
        try:
            vals = [float(x) for x in _re.split(r"\s+", text.strip())]
        except ValueError:
            vals = []
        if len(vals) != 12:
            raise FileFormatError(f"{p}: transform {text!r} is not 12 numbers")
        m[:, :3] = np.array(vals).reshape(4, 3)
        return m  # row vectors: [x y z 1] @ m

    def mesh_of(oid, seen: tuple) -> list[tuple[np.ndarray, np.ndarray]]:
        if oid not in objects:
            raise FileFormatError(f"{p}: a build item or component names object {oid!r}, which is not defined")
        if oid in seen:
            raise FileFormatError(f"{p}: object {oid!r} contains itself through its components")
        obj = objects[oid]
        mesh = obj.find(f"{_NS_3MF}mesh")
        if mesh is not None:
            vx = mesh.find(f"{_NS_3MF}vertices")
            tx = mesh.find(f"{_NS_3MF}triangles")
            v = np.array([[number(e, "x"), number(e, "y"), number(e, "z")]
                          for e in (vx if vx is not None else [])], dtype=np.float64).reshape(-1, 3)
            try:
                t = np.array([[int(e.get("v1")), int(e.get("v2")), int(e.get("v3"))]
                              for e in (tx if tx is not None else [])], dtype=np.int64).reshape(-1, 3)
            except (TypeError, ValueError):
                raise FileFormatError(f"{p}: object {oid!r}: a <triangle> needs integer v1, v2, v3") from None
            if len(t) and (t.min() < 0 or t.max() >= len(v)):
                raise FileFormatError(f"{p}: object {oid!r}: a triangle names a vertex that does not exist "
                                      f"({len(v)} vertices)")
            return [(v, t)]
        out = []
        comps = obj.find(f"{_NS_3MF}components")
        for c in (comps if comps is not None else []):
            m = matrix(c.get("transform"))
            for v, t in mesh_of(c.get("objectid"), seen + (oid,)):
                out.append((np.column_stack([v, np.ones(len(v))]) @ m[:, :3], t))
        return out

    build = root.find(f"{_NS_3MF}build")
    items = list(build.iter(f"{_NS_3MF}item")) if build is not None else []
    if not items:
        raise FileFormatError(f"{p}: the 3MF model has no <build><item> (nothing to make)")
    verts, tris, tface, faces = [], [], [], []
    base = 0
    for k, item in enumerate(items):
        m = matrix(item.get("transform"))
        oid = item.get("objectid")
        n0 = sum(len(t) for t in tris)
        for v, t in mesh_of(oid, ()):
            verts.append(np.column_stack([v, np.ones(len(v))]) @ m[:, :3])
            tris.append(t + base)
            base += len(v)
        n = sum(len(t) for t in tris) - n0
        name = objects[oid].get("name") or f"object {oid}"
        faces.append(CadFace(k, int(oid) if str(oid).isdigit() else k, name))
        tface.append(np.full(n, k, dtype=np.int64))
    t = np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)
    if len(t) == 0:
        raise FileFormatError(f"{p}: the 3MF model holds no triangles")
    return np.concatenate(verts), t, faces, np.concatenate(tface), UNITS_3MF[unit_name]
