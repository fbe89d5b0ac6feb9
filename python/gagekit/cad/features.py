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
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .context import BAND_REACH, CadContext  # noqa: F401  (CadContext is also reached from here)

__all__ = ["CadContext", "surface_profile"]

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


def surface_profile(tol, fd, system) -> tuple[float, dict[str, Any]]:
    """(measured width, details) of the profile of a surface (module docstring)."""
    from .datums import cad_frame
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
    frame = system.frame(tol.datums)
    nominal = cad_frame(model, system.spec, tuple(tol.datums))
    R = nominal.axes.T @ frame.axes
    u, _, vt = np.linalg.svd(R)
    R = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = R, nominal.origin - R @ frame.origin
    free = _free_in_cad_axes(nominal)
    if any(free):
        mm = mesh.minimax(pts, np.ascontiguousarray(m), free, None, off)
        m = np.array(mm.matrix)
        details["free"] = [n for n, f in zip(("x", "y", "z", "rx", "ry", "rz"), free) if f]
    d = model.distances(transform(pts, m)).distance - off
    details.update(matrix=m.tolist(), datum_frame=list(tol.datums))
    return 2.0 * float(np.abs(d).max()), details
