"""Compare a scan with its CAD model: signed deviations, best-fit / minimax / datum
alignment, per-face statistics (ISO 1101 profile of a surface, ISO 1660).

- :func:`read_cad` reads STEP (OpenCASCADE, the ``cad`` extra), STL, OBJ and PLY meshes
  into a :class:`CadModel` (millimetres; faces with their STEP ids and names);
- :func:`compare` aligns the points and returns a :class:`CompareResult`: one signed
  deviation per point, positive outside the material (:mod:`.compare`);
- the distance, best-fit and minimax kernels are Rust (``gagekit-mesh``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

from ..errors import FileFormatError
from .compare import ALIGN_METHODS, CompareResult, compare, parse_lock
from .model import CadFace, CadModel, Distances

__all__ = ["read_cad", "CadModel", "CadFace", "Distances", "compare", "CompareResult", "ALIGN_METHODS",
           "parse_lock", "CAD_SUFFIXES"]

CAD_SUFFIXES = (".step", ".stp", ".stl", ".obj", ".ply", ".3mf")


def read_cad(path: Any, units: Optional[str] = None) -> CadModel:
    """Read a CAD model (by its extension): STEP (``.step``/``.stp``, its declared unit;
    needs ``gagekit[cad]``), 3MF (its declared unit), STL, OBJ or PLY with faces
    (``units``, default mm).

    Raises :class:`~gagekit.errors.FileFormatError` for a file that cannot be read and
    :class:`~gagekit.errors.DegenerateGeometryError` / ``InvalidInputError`` for a mesh
    with degenerate triangles or non-finite vertices (when the kernel builds it).
    """
    import numpy as np

    from .._files import input_file, read_bytes, read_text
    from ..cloud import units as _units

    p = input_file(path, "CAD file")
    suffix = p.suffix.lower()
    override = _units.check_units(units)
    warnings: list[str] = []
    refine = None
    if suffix in (".step", ".stp"):
        from . import step

        parts = step.read_step(p)
        unit = parts["unit"]
        if override is not None and override != unit:
            warnings.append(f"{p}: a STEP file declares its unit ({unit}); --cad-units {override} is ignored")
        v, t, faces, tf = parts["vertices"], parts["triangles"], parts["faces"], parts["triangle_face"]
        warnings += parts["warnings"]
        method = (f"exact faces: tessellation within {step.DEFLECTION * 1000:g} um (BRepMesh), closest face from the "
                  "kernel, distance refined on the exact surface (closed form for planes, cylinders, cones, spheres; "
                  "GeomAPI_ProjectPointOnSurf otherwise)")
        fmt = "step"
    else:
        from . import meshes

        unit = override or "mm"
        if suffix == ".3mf":
            v, t, faces, tf, unit = meshes.read_3mf(p)
            if override is not None and override != unit:
                warnings.append(f"{p}: a 3MF file declares its unit ({unit}); --cad-units {override} is ignored")
        elif suffix == ".stl":
            v, t, faces, tf = meshes.read_stl(p, read_bytes(p, "CAD file"))
        elif suffix == ".obj":
            v, t, faces, tf = meshes.read_obj(p, read_text(p, "CAD file"))
        elif suffix == ".ply":
            v, t, faces, tf = meshes.read_ply_mesh(p)
        else:
            raise FileFormatError(f"{p}: unknown CAD format '{suffix}'; gagekit reads STEP (.step, .stp), STL, OBJ, PLY and 3MF meshes")
        s = _units.scale_to_mm(unit)
        if s != 1.0:
            v = v * s
        method = "exact distances to the mesh's triangles"
        fmt = suffix[1:]
    model = CadModel(str(p), fmt, unit, np.ascontiguousarray(v, dtype=np.float64), np.ascontiguousarray(t, dtype=np.int64),
                     np.asarray(tf, dtype=np.int64), tuple(faces), tuple(warnings), method)
    mesh = model.mesh  # validates: typed errors for NaN vertices, degenerate triangles, no faces
    if not mesh.signed:
        model.warnings = model.warnings + (f"{p}: {mesh.reason}",)
    if fmt == "step":
        from . import step

        refine = step.make_refiner(parts["surfaces"], mesh, model.triangle_face)
        model.refine = refine
    return model
