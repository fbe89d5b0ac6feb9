"""Features of a drawing located by CAD faces, and the profile of a surface (ISO 1101
Sec. 18.7 / ISO 1660).

**Points of a feature.** With ``[part] cad = "MODEL.step"`` a feature may give ``faces``
(STEP ids or names) instead of a region: its points are the scan points whose nearest
point of the model lies on one of those faces, within ``band`` mm of the surface. The
default band is 3 times the RMS of those points' deviations (the points within 1 mm of
the faces): it follows the scan's noise and the part's own deviations, so outliers
(clutter, the fixture) drop out; ``band`` (per feature or in ``[part]``) sets it.

**Profile of a surface** (``characteristic = "profile"`` on a ``shape = "surface"``
feature). The zone is bounded by two surfaces offset +-t/2 from the CAD faces, or from the
faces offset by ``offset`` (ISO 1101 UZ); the measured value is its smallest width t that
holds every point:

- without datums the zone floats: the minimax (Chebyshev) fit of the feature's points
  alone to the model (Rust ``gagekit-mesh::minimax``, from their best fit), measured
  = 2 max |d - offset|, with the LP certificate in the details;
- with datums it is fixed in the datum frame: the scan's datum frame (simulated by
  :mod:`gagekit.inspect.datums`) is put on the CAD's (the same datums simulated on the
  model's surface, :mod:`.datums`) and measured = 2 max |d - offset|; the degrees of
  freedom the datums leave free (along CAD axes) are optimised by the same minimax.

**Profile of a line** (``characteristic = "profile-line"``, ISO 1101 Sec. 18.6): the same
zone in each of a set of parallel sections (:func:`line_profile`), the worst section the
measured value.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .context import BAND_REACH, CadContext  # noqa: F401  (CadContext is also reached from here)

__all__ = ["CadContext", "surface_profile", "line_profile"]

def _free_in_cad_axes(frame) -> list[bool]:
    """The datum frame's free motions as free CAD-axis degrees of freedom (x, y, z, rx,
    ry, rz): a translation along a CAD axis is free when the frame leaves it free; the
    rotation about the frame's z when z lies along a CAD axis."""
    free = [False] * 6
    T = frame.free_translations
    for k in range(3):
        e = np.eye(3)[k]
        if len(T) and np.linalg.norm(T @ e) > 1.0 - 1e-9:
            free[k] = True
    if frame.free_rotation:
        z = frame.axes[2]
        k = int(np.argmax(np.abs(z)))
        if abs(z[k]) > 1.0 - 1e-9:
            free[3 + k] = True
    return free


def _datum_pose(tol, fd, system, pts: np.ndarray, off: float) -> tuple[np.ndarray, dict[str, Any]]:
    """The 4x4 that puts the scan's datum frame of ``tol`` on the CAD's; the degrees of
    freedom the datums leave free (along CAD axes) optimised by the minimax of ``pts``."""
    from .datums import cad_frame

    model = fd._cache["cad"].model
    frame = system.frame(tol.datums)
    nominal = cad_frame(model, system.spec, tuple(tol.datums))
    R = nominal.axes.T @ frame.axes
    u, _, vt = np.linalg.svd(R)
    R = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = R, nominal.origin - R @ frame.origin
    details: dict[str, Any] = {}
    free = _free_in_cad_axes(nominal)
    if any(free):
        mm = model.mesh.minimax(pts, np.ascontiguousarray(m), free, None, off)
        m = np.array(mm.matrix)
        details["free"] = [n for n, f in zip(("x", "y", "z", "rx", "ry", "rz"), free) if f]
    details.update(matrix=m.tolist(), datum_frame=list(tol.datums))
    return m, details


def surface_profile(tol, fd, system) -> tuple[float, dict[str, Any]]:
    """(measured width, details) of the profile of a surface (module docstring)."""
    from .model import transform

    ctx: CadContext = fd._cache["cad"]
    model = ctx.model
    mesh = model.mesh
    pts = np.ascontiguousarray(fd.points)
    off = float(tol.offset)
    details: dict[str, Any] = {"faces": list(fd.spec.faces), "offset": off}
    if not tol.datums:
        fit = mesh.best_fit(pts, None, [True] * 6, None, False)
        mm = mesh.minimax(pts, np.ascontiguousarray(np.array(fit.matrix)), [True] * 6, None, off)
        m = np.array(mm.matrix)
        d = model.distances(transform(pts, m)).distance - off
        details.update(certificate={"max_abs_deviation": mm.max_abs, "lp_optimum": mm.lp_optimum}, matrix=m.tolist())
        return 2.0 * float(np.abs(d).max()), details
    m, more = _datum_pose(tol, fd, system, pts, off)
    d = model.distances(transform(pts, m)).distance - off
    details.update(more)
    return 2.0 * float(np.abs(d).max()), details


def line_profile(tol, fd, system) -> tuple[float, dict[str, Any]]:
    """(measured width, details) of the profile of a line (ISO 1101 Sec. 18.6) on a
    surface feature: the feature's points cut into parallel sections across ``direction``
    (``sections`` equal slices of the points' span, as roundness sections are, or slices
    ``spacing`` mm thick), in each the deviations of the section's points from the CAD
    surface (their signed distances; in a section plane that holds the surface normal,
    the distance to the nominal line), the zone width per section, the worst section the
    measured value.

    - with datums the zones are fixed in the datum frame (the pose of the profile of a
      surface with the same datums, :func:`surface_profile`): width = 2 max |d - offset|;
    - without datums each section's zone floats in its own plane: the minimax
      (Chebyshev) fit of that section's points alone, over the two translations in the
      plane and the rotation about ``direction`` (``gagekit-mesh::minimax`` from their
      best fit, the model turned so that ``direction`` is its z axis), width =
      2 max |d - offset| after it, with the LP certificate per section.
    """
    from .. import _core
    from ..errors import DegenerateGeometryError
    from .model import transform

    ctx: CadContext = fd._cache["cad"]
    model = ctx.model
    pts = np.ascontiguousarray(fd.points)
    off = float(tol.offset)
    u = np.asarray(tol.direction, dtype=float)
    u = u / np.linalg.norm(u)
    t = pts @ u
    if tol.spacing is not None:
        count = max(1, int(math.ceil((float(t.max()) - float(t.min())) / tol.spacing - 1e-9)))
    else:
        count = tol.sections or fd.spec.sections
    slices = [idx for idx in fd.sections(count, np.zeros(3), u) if len(idx) >= 3]
    if not slices:
        raise DegenerateGeometryError(f"feature '{fd.name}': no section across {u.round(6).tolist()} holds 3 points")
    details: dict[str, Any] = {"faces": list(fd.spec.faces), "offset": off, "direction": u.tolist(),
                               "sections_asked": int(count)}
    rows = []
    if tol.datums:
        m, more = _datum_pose(tol, fd, system, pts, off)
        d_all = model.distances(transform(pts, m)).distance - off
        details.update(more)
        for idx in slices:
            d = d_all[idx]
            rows.append({"position": float(t[idx].mean()), "n": int(len(idx)), "min": float(d.min()), "max": float(d.max()),
                         "width": 2.0 * float(np.abs(d).max())})
    else:
        # the section frame: columns a, b, u; a point p of the CAD is (p @ B) there
        a = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
        a /= np.linalg.norm(a)
        B = np.column_stack([a, np.cross(u, a), u])
        Bh = np.eye(4)
        Bh[:3, :3] = B
        mesh = _core.mesh.Mesh(np.ascontiguousarray(model.vertices @ B), np.ascontiguousarray(model.triangles))
        free = [True, True, False, False, False, True]  # in-plane translations, rotation about the normal
        for idx in slices:
            q = np.ascontiguousarray(pts[idx] @ B)
            fit = mesh.best_fit(q, None, free, None, False)
            mm = mesh.minimax(q, np.ascontiguousarray(np.array(fit.matrix)), free, None, off)
            m = Bh @ np.array(mm.matrix) @ Bh.T  # the section's motion in CAD coordinates
            d = model.distances(transform(pts[idx], m)).distance - off
            rows.append({"position": float(t[idx].mean()), "n": int(len(idx)), "min": float(d.min()), "max": float(d.max()),
                         "width": 2.0 * float(np.abs(d).max()), "matrix": m.tolist(),
                         "certificate": {"max_abs_deviation": mm.max_abs, "lp_optimum": mm.lp_optimum}})
    worst = max(range(len(rows)), key=lambda k: rows[k]["width"])
    details.update(sections=rows, worst_section=worst)
    return rows[worst]["width"], details
