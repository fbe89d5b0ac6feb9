"""Datum alignment (``--align datums``): the datum reference frame of the drawing (ISO
5459), simulated on the scan and on the CAD model, and the rigid motion that puts the
scan's frame on the CAD's.

1. The scan is brought near the CAD by the robust best fit (:mod:`.compare`), so that the
   drawing's feature regions (given in the CAD's coordinates) find their points.
2. The main datum frame (the longest datum sequence of the drawing's callouts, as
   ``gagekit inspect`` reports it) is simulated on the scan's points with the inspection
   code (:class:`gagekit.inspect.datums.DatumSystem`: Chebyshev tangent planes, maximum
   inscribed / minimum circumscribed axes, constrained in precedence order).
3. The same frame is simulated on the CAD surface (its vertices and a dense sample of its
   triangles inside each feature's region): the nominal frame.
4. The motion maps the scan's frame onto the CAD's; what the datums leave free
   (translations along a datum plane, the rotation about a lone primary axis...) stays as
   the best fit placed it.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from ..errors import ConfigError

__all__ = ["datum_alignment", "surface_sample", "main_datums", "cad_frame"]


def main_datums(spec) -> tuple[str, ...]:
    """The longest datum sequence of the callouts (first in drawing order)."""
    best: tuple[str, ...] = ()
    for t in spec.tolerances:
        if len(t.datums) > len(best):
            best = tuple(t.datums)
    if not best:
        if spec.datums:
            return tuple(list(spec.datums)[:3])
        raise ConfigError(f"{spec.source}: --align datums needs [datums] in the drawing")
    return best


def surface_sample(model, per_triangle: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Points on the CAD surface and their faces: a fixed pattern of interior points of
    every triangle (barycentric), so that a face's datum is simulated on its whole area."""
    v, t = model.vertices, model.triangles
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    pats = [(1 / 3, 1 / 3), (2 / 3, 1 / 6), (1 / 6, 2 / 3), (1 / 6, 1 / 6)][:per_triangle]
    pts = np.concatenate([a + u * (b - a) + w * (c - a) for u, w in pats])
    return np.ascontiguousarray(pts), np.tile(model.triangle_face, len(pats))


def _frame(points: np.ndarray, spec, letters: tuple[str, ...], cad=None):
    from ..inspect.datums import DatumSystem
    from ..inspect.features import extract

    needed = {spec.datums[k].feature for k in letters}
    feats = extract(points, {n: spec.features[n] for n in needed}, spec.source, cad)
    return DatumSystem(spec, feats).frame(letters)


def cad_frame(model, spec, letters: tuple[str, ...]):
    """The datum frame ``letters`` simulated on the CAD surface: the nominal frame."""
    from .context import CadContext

    pts, face = surface_sample(model)
    return _frame(pts, spec, letters, CadContext(model, np.zeros(len(pts)), face))


def datum_alignment(points: np.ndarray, model, spec, max_distance: Optional[float]) -> tuple[np.ndarray, dict[str, Any]]:
    """(4x4 matrix applied to the scan, details) of the datum alignment (module docstring)."""
    if spec is None:
        raise ConfigError("--align datums needs --part PART.toml")
    from .model import transform

    letters = main_datums(spec)
    fit = model.mesh.best_fit(points, None, [True] * 6, max_distance, True)
    m0 = np.array(fit.matrix)
    moved = transform(points, m0)
    cad = None
    if any(spec.features[spec.datums[k].feature].faces for k in letters):
        from .context import CadContext

        d = model.distances(moved, max_distance)
        cad = CadContext(model, d.distance, d.face)
    scan_frame = _frame(moved, spec, letters, cad)
    nominal = cad_frame(model, spec, letters)
    # R maps the scan frame's axes onto the CAD frame's: R = A_cad^T A_scan (rows are axes)
    R = nominal.axes.T @ scan_frame.axes
    u, _, vt = np.linalg.svd(R)
    R = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    t = nominal.origin - R @ scan_frame.origin
    free = nominal.free_translations
    if len(free):
        t = t - free.T @ (free @ t)  # the datums leave these translations free: keep the best fit's
    m1 = np.eye(4)
    m1[:3, :3], m1[:3, 3] = R, t
    info = {"datums": list(letters), "scan_frame": scan_frame.to_dict(), "cad_frame": nominal.to_dict(),
            "prealignment": m0.tolist()}
    return m1 @ m0, info
