"""STEP models (AP203 / AP214 / AP242) through OpenCASCADE (``cadquery-ocp`` or
``cadquery-ocp-novtk``: ``pip install gagekit[cad]``).

Reading: ``STEPControl_Reader``; the geometry arrives in millimetres whatever the file
declares (OpenCASCADE converts from the file's ``LENGTH_UNIT``; the declared unit is
reported). Faces keep their STEP identity: the entity number ``#id`` of each
``ADVANCED_FACE`` and its name (the first attribute), matched to OpenCASCADE's faces in
the order the file's shells list them.

Distances within 1 um of the exact surface -- the method:

1. tessellate every face with ``BRepMesh_IncrementalMesh`` (linear deflection
   :data:`DEFLECTION` = 0.5 um, angular 0.05 rad): every triangle lies within 0.5 um of
   its face; the kernel gives the exact distance to the tessellation and the triangle,
   hence the face, of the closest point;
2. refine on the exact face: for a plane the tessellation is the face (exact); for a
   cylinder, cone or sphere the distance to the exact surface is computed in closed form
   (radial distance minus radius, the distance to the cone's generatrix, |p - c| - r),
   and for any other surface (torus, B-spline...) by ``GeomAPI_ProjectPointOnSurf``
   within the face's parameter bounds; the refined value is kept when it is within twice
   the deflection of the tessellation's distance (the closest point is then inside the
   face; near a face's boundary the tessellation's distance stands, exact to the
   deflection of the boundary's polygon, 0.5 um). The sign is the face's outward side.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FileFormatError
from .model import CadFace

__all__ = ["read_step", "DEFLECTION", "ocp_available", "MISSING"]

#: Linear deflection of the tessellation (mm).
DEFLECTION = 5e-4
ANGULAR = 0.05
MISSING = "install gagekit[cad] (OpenCASCADE, the cadquery-ocp wheel) to read STEP files"


def ocp_available() -> bool:
    import importlib.util

    return importlib.util.find_spec("OCP") is not None


def _file_faces(text: str) -> tuple[list[int], dict[int, str], str]:
    """(face ids in shell order, id -> name, declared length unit) from the STEP text."""
    names = {int(m.group(1)): m.group(2).replace("''", "'")
             for m in re.finditer(r"#(\d+)\s*=\s*(?:ADVANCED_FACE|FACE_SURFACE)\s*\(\s*'((?:[^']|'')*)'", text)}
    order: list[int] = []
    for m in re.finditer(r"=\s*(?:CLOSED_SHELL|OPEN_SHELL)\s*\(\s*'(?:[^']|'')*'\s*,\s*\(([^)]*)\)", text):
        order.extend(int(x) for x in re.findall(r"#(\d+)", m.group(1)))
    unit = "mm"
    u = re.search(r"LENGTH_UNIT\s*\(\s*\)\s*NAMED_UNIT\s*\(\s*\*\s*\)\s*SI_UNIT\s*\(\s*([.$A-Z]*)\s*,\s*\.METRE\.", text)
    if u:
        unit = {".MILLI.": "mm", ".CENTI.": "cm", ".MICRO.": "um", "$": "m"}.get(u.group(1), u.group(1).strip(".").lower() + "m")
    elif re.search(r"CONVERSION_BASED_UNIT\s*\(\s*'INCH'", text, flags=re.I):
        unit = "in"
    elif re.search(r"CONVERSION_BASED_UNIT\s*\(\s*'FOOT'", text, flags=re.I):
        unit = "ft"
    return order, names, unit


def read_step(p: Path) -> dict[str, Any]:
    """Read and tessellate a STEP file; returns the parts of a :class:`~.model.CadModel`."""
    if not ocp_available():
        raise MissingExtraError(MISSING)
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    from .._files import read_text

    text = read_text(p, "STEP file")
    if "ISO-10303-21" not in text[:200]:
        raise FileFormatError(f"{p}: not a STEP file (it does not begin with ISO-10303-21)")
    order, names, unit = _file_faces(text)
    reader = STEPControl_Reader()
    if reader.ReadFile(str(p)) != IFSelect_RetDone:
        raise FileFormatError(f"{p}: OpenCASCADE cannot read this STEP file")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape is None or shape.IsNull():
        raise FileFormatError(f"{p}: the STEP file holds no shape")
    faces = []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        faces.append(TopoDS.Face(ex.Current()))
        ex.Next()
    if not faces:
        raise FileFormatError(f"{p}: the STEP model has no faces (not a solid or a surface model)")
    warnings = []
    if len(order) != len(faces):
        order = sorted(names) if len(names) == len(faces) else list(range(1, len(faces) + 1))
        if len(names) != len(faces):
            warnings.append(f"{p}: the faces could not be matched to their STEP ids; they are numbered 1..{len(faces)}")
    BRepMesh_IncrementalMesh(shape, DEFLECTION, False, ANGULAR, True)
    verts, tris, tri_face, cad_faces, surfaces = [], [], [], [], []
    base = 0
    for k, f in enumerate(faces):
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(f, loc)
        fid = order[k]
        ad = BRepAdaptor_Surface(f)
        kind = _KINDS.get(int(ad.GetType()), "other")
        cad_faces.append(CadFace(k, fid, names.get(fid, ""), kind))
        surfaces.append((f, ad, kind))
        if tri is None:
            warnings.append(f"{p}: face #{fid} could not be tessellated and is left out")
            continue
        trsf = loc.Transformation()
        nn = tri.NbNodes()
        pts = np.empty((nn, 3))
        for i in range(nn):
            q = tri.Node(i + 1).Transformed(trsf)
            pts[i] = (q.X(), q.Y(), q.Z())
        nt = tri.NbTriangles()
        tt = np.empty((nt, 3), dtype=np.int64)
        for i in range(nt):
            tt[i] = tri.Triangle(i + 1).Get()
        tt -= 1
        if f.Orientation() == TopAbs_REVERSED:
            tt = tt[:, [0, 2, 1]]
        verts.append(pts)
        tris.append(tt + base)
        tri_face.append(np.full(nt, k, dtype=np.int64))
        base += nn
    if not tris:
        raise FileFormatError(f"{p}: no face of the STEP model could be tessellated")
    v = np.concatenate(verts)
    t = np.concatenate(tris)
    # faces share their boundary nodes: weld them (equal to 1e-9 mm) so the mesh is closed
    key = np.round(v / 1e-9).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    v = v[first]
    t = inv.ravel()[t]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    tf = np.concatenate(tri_face)
    return {"vertices": v, "triangles": t[keep], "triangle_face": tf[keep], "faces": cad_faces, "unit": unit,
            "warnings": warnings, "surfaces": surfaces}


def _kinds() -> dict[int, str]:
    try:
        from OCP.GeomAbs import (GeomAbs_BSplineSurface, GeomAbs_Cone, GeomAbs_Cylinder, GeomAbs_Plane,
                                 GeomAbs_Sphere, GeomAbs_Torus)
    except ImportError:  # pragma: no cover - without the extra
        return {}
    return {int(GeomAbs_Plane): "plane", int(GeomAbs_Cylinder): "cylinder", int(GeomAbs_Cone): "cone",
            int(GeomAbs_Sphere): "sphere", int(GeomAbs_Torus): "torus", int(GeomAbs_BSplineSurface): "bspline"}


_KINDS = _kinds()


class MissingExtraError(FileFormatError):
    """A STEP file without the ``cad`` extra installed."""


def make_refiner(surfaces: list, mesh: Any, triangle_face: np.ndarray):
    """The exact-face refinement of a STEP model's distances (module docstring, step 2)."""
    from OCP.gp import gp_Pnt

    fn = mesh.face_normals()
    info = []
    for k, (face, ad, kind) in enumerate(surfaces):
        tris = np.flatnonzero(triangle_face == k)
        if kind == "plane" or len(tris) == 0:
            info.append(None)
            continue
        if kind == "cylinder":
            c = ad.Cylinder()
            ax = c.Axis()
            info.append(("cylinder", _xyz(ax.Location()), _xyz(ax.Direction()), c.Radius()))
        elif kind == "sphere":
            s = ad.Sphere()
            info.append(("sphere", _xyz(s.Location()), None, s.Radius()))
        elif kind == "cone":
            c = ad.Cone()
            info.append(("cone", _xyz(c.Apex()), _xyz(c.Axis().Direction()), c.SemiAngle()))
        else:
            info.append(("other", face, ad, None))

    def refine(pts: np.ndarray, d: np.ndarray, tri: np.ndarray, foot: np.ndarray):
        from OCP.BRep import BRep_Tool
        from OCP.BRepTools import BRepTools
        from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

        out = d.copy()
        ok = tri >= 0
        faces = np.where(ok, triangle_face[np.maximum(tri, 0)], -1)
        refined = 0
        for k, inf in enumerate(info):
            if inf is None:
                continue
            sel = np.flatnonzero(faces == k)
            if len(sel) == 0:
                continue
            p = pts[sel]
            n_out = fn[tri[sel]]  # outward normals of the nearest triangles
            kind = inf[0]
            if kind in ("cylinder", "sphere", "cone"):
                o, a, r = inf[1], inf[2], inf[3]
                v = p - o
                if kind == "sphere":
                    radial = v
                    rho = np.linalg.norm(v, axis=1)
                    dist = rho - r
                    s = np.sign(np.einsum("ij,ij->i", n_out, radial))
                elif kind == "cylinder":
                    h = v @ a
                    radial = v - np.outer(h, a)
                    rho = np.linalg.norm(radial, axis=1)
                    dist = rho - r
                    s = np.sign(np.einsum("ij,ij->i", n_out, radial))
                else:
                    h = v @ a
                    radial = v - np.outer(h, a)
                    rho = np.linalg.norm(radial, axis=1)
                    al = r  # semi-angle
                    dist = rho * math.cos(al) - h * math.sin(al)
                    # the outward side: along the cone's normal (cos al radial - sin al axis)
                    nr = radial / np.maximum(rho, 1e-300)[:, None]
                    cone_n = math.cos(al) * nr - math.sin(al) * a
                    s = np.sign(np.einsum("ij,ij->i", n_out, cone_n))
                new = s * dist
            else:
                face, ad = inf[1], inf[2]
                surf = BRep_Tool.Surface_s(face)
                u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
                new = np.array(d[sel], dtype=float)
                for j, q in enumerate(p):
                    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*q), surf, u0, u1, v0, v1)
                    if proj.NbPoints() > 0:
                        new[j] = math.copysign(float(proj.LowerDistance()), d[sel[j]] if d[sel[j]] != 0 else 1.0)
            good = np.isfinite(new) & (np.abs(new - d[sel]) <= 2 * DEFLECTION + 1e-12) & (new != 0) | (np.abs(new) < 1e-15)
            out[sel[good]] = new[good]
            refined += int(good.sum())
        return out, refined

    return refine



def _xyz(v: Any) -> np.ndarray:
    return np.array([v.X(), v.Y(), v.Z()])
