"""The comparison pipeline: points in, :class:`CompareResult` out (one function,
:func:`compare`, so a streaming reader can feed it chunk by chunk later).

Alignment (``matrix``: the 4x4 applied to the scan, row-major):

- ``none``: the scan is already in the CAD's coordinates;
- ``best-fit``: least squares of the signed distances, robust (Tukey weights) and from
  any initial pose (principal axes and their flips, then point-to-plane ICP), Rust kernel
  ``gagekit-mesh::align``;
- ``minimax``: the smallest largest |deviation| (Chebyshev), a sequence of LPs from the
  best fit, with its certificate: the exact largest |distance| and the LP optimum at the
  final pose (equal at the optimum), ``gagekit-mesh::minimax``;
- ``datums``: the datum reference frame of the drawing (ISO 5459) simulated on the scan and
  placed on the CAD's (:mod:`.datums`).

``lock`` keeps chosen degrees of freedom (x, y, z, rx, ry, rz: rotations about the CAD's
axes, R = Rz Ry Rx). Deviations are positive outside the material (along the outward
normal), as PolyWorks and ZEISS INSPECT report them; points farther than ``max_distance``
from the model are counted (``n_beyond``) and get NaN, never dropped.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

import numpy as np

from .._util import as_points
from ..errors import ConfigError, DegenerateGeometryError
from .model import CadModel, transform  # noqa: F401  (transform is also reached from here)

__all__ = ["compare", "CompareResult", "ALIGN_METHODS", "DOF_NAMES", "parse_lock", "transform", "vertex_deviations"]

ALIGN_METHODS = ("none", "best-fit", "minimax", "datums")
DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")
HISTOGRAM_BINS = 40


def parse_lock(lock: Any) -> tuple[bool, ...]:
    """Free flags of the six degrees of freedom from a lock list ("x,y,rz" or a sequence)."""
    if lock is None or lock == "":
        return (True,) * 6
    names = [s.strip().lower() for s in (lock.split(",") if isinstance(lock, str) else lock)]
    bad = [n for n in names if n not in DOF_NAMES]
    if bad:
        raise ConfigError(f"--lock: unknown degree(s) of freedom {', '.join(map(repr, bad))}; choose from {','.join(DOF_NAMES)}")
    return tuple(n not in names for n in DOF_NAMES)


@dataclass(frozen=True)
class CompareResult:
    """Everything ``gagekit compare --json`` prints, and the per-point arrays."""

    n_points: int
    cad: dict
    alignment: dict
    deviation: np.ndarray = field(repr=False)  # per input point (NaN beyond max_distance)
    face: np.ndarray = field(repr=False)  # per input point: face index (-1 beyond)
    aligned: np.ndarray = field(repr=False)  # the points after the alignment (CAD frame)
    faces: tuple = ()
    signed: bool = True
    method: str = ""
    max_distance: Optional[float] = None
    seconds: float = 0.0
    model: Any = field(default=None, repr=False)

    @property
    def used(self) -> np.ndarray:
        return np.isfinite(self.deviation)

    @property
    def n_used(self) -> int:
        return int(self.used.sum())

    @property
    def n_beyond(self) -> int:
        return self.n_points - self.n_used

    def statistics(self) -> dict[str, Any]:
        d = self.deviation[self.used]
        if len(d) == 0:
            raise DegenerateGeometryError("compare: no point lies within --max-distance of the model")
        lo, hi = float(d.min()), float(d.max())
        counts, edges = np.histogram(d, bins=HISTOGRAM_BINS, range=(lo, hi) if hi > lo else (lo - 1e-9, hi + 1e-9))
        return {
            "min": lo, "max": hi, "mean": float(d.mean()), "sd": float(d.std(ddof=1)) if len(d) > 1 else 0.0,
            "rms": float(np.sqrt(np.mean(d * d))), "profile": 2.0 * float(np.abs(d).max()),
            "histogram": {"edges": edges.tolist(), "counts": counts.tolist()},
        }

    def face_statistics(self) -> list[dict[str, Any]]:
        u = self.used
        d, f = self.deviation[u], self.face[u]
        out = []
        for face in self.faces:
            sel = d[f == face.index]
            row: dict[str, Any] = {"index": face.index, "id": face.id, "name": face.name, "kind": face.kind, "n": int(len(sel))}
            if len(sel):
                row.update(min=float(sel.min()), max=float(sel.max()), mean=float(sel.mean()),
                           rms=float(np.sqrt(np.mean(sel * sel))))
            out.append(row)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "n_points": self.n_points,
            "n_used": self.n_used,
            "n_beyond": self.n_beyond,
            "cad": self.cad,
            "alignment": self.alignment,
            "deviations": self.statistics(),
            "faces": self.face_statistics(),
            "signed": self.signed,
            "distance_method": self.method,
            "max_distance": self.max_distance,
            "seconds": self.seconds,
        }


def _rms(d: np.ndarray) -> float:
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d * d))) if len(d) else 0.0


def compare(points: Any, model: CadModel, align: str = "none", lock: Any = None, max_distance: Optional[float] = None,
            part: Any = None) -> CompareResult:
    """Align ``points`` ((n, 3), mm) to ``model`` and measure every point's signed
    deviation (see the module docstring). ``part``: a PART.toml spec (``align="datums"``)."""
    t0 = time.perf_counter()
    if align not in ALIGN_METHODS:
        raise ConfigError(f"--align {align!r}: choose one of {', '.join(ALIGN_METHODS)}")
    if max_distance is not None and not (np.isfinite(max_distance) and max_distance > 0):
        raise ConfigError(f"--max-distance must be a positive number, got {max_distance}")
    pts = as_points(points)
    free = list(parse_lock(lock))
    mesh = model.mesh
    before = model.distances(pts, max_distance).distance if align != "none" else None
    alignment: dict[str, Any] = {"method": align, "locked": [n for n, f in zip(DOF_NAMES, free) if not f]}
    matrix = np.eye(4)
    iterations = 0
    if align in ("best-fit", "minimax"):
        fit = mesh.best_fit(pts, None, free, max_distance, True)
        matrix = np.array(fit.matrix)
        iterations = fit.iterations
        if align == "minimax":
            mm = mesh.minimax(pts, np.ascontiguousarray(matrix), free, max_distance)
            matrix = np.array(mm.matrix)
            iterations += mm.iterations
            alignment["certificate"] = {"max_abs_deviation": mm.max_abs, "lp_optimum": mm.lp_optimum,
                                        "gap": mm.max_abs - mm.lp_optimum, "active_points": mm.active,
                                        "on": "the tessellation" if model.refine is not None else "the mesh"}
    elif align == "datums":
        from .datums import datum_alignment

        matrix, info = datum_alignment(pts, model, part, max_distance)
        alignment.update(info)
    aligned = transform(pts, matrix) if align != "none" else np.ascontiguousarray(pts)
    dist = model.distances(aligned, max_distance)
    rms_after = _rms(dist.distance)
    alignment.update(matrix=matrix.tolist(), rms_before=_rms(before) if before is not None else rms_after,
                     rms_after=rms_after, iterations=int(iterations))
    return CompareResult(int(len(pts)), model.to_dict(), alignment, dist.distance, dist.face, aligned, model.faces,
                         dist.signed, model.method, max_distance, time.perf_counter() - t0, model)


def vertex_deviations(model: CadModel, triangle: np.ndarray, deviation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The deviation map on the model's vertices (``compare --report``, the studio): per
    vertex the mean deviation of the points whose nearest triangle has it as a corner,
    and the count of those points (0: no point near; its mean is then 0).

    ``triangle``: each point's nearest triangle (-1: none, e.g. beyond ``max_distance``);
    ``deviation``: each point's signed deviation (NaN: not used)."""
    tri = np.asarray(triangle, dtype=np.int64)
    d = np.asarray(deviation, dtype=np.float64)
    ok = (tri >= 0) & np.isfinite(d)
    corners = np.asarray(model.triangles)[tri[ok]].ravel()
    nv = len(model.vertices)
    total = np.bincount(corners, weights=np.repeat(d[ok], 3), minlength=nv)
    count = np.bincount(corners, minlength=nv)
    return np.where(count > 0, total / np.maximum(count, 1), 0.0), count


def write_deviations(path: Any, result: CompareResult) -> None:
    """One deviation per input point, in input order (NaN beyond ``max_distance``): ``.npy``
    (the 1-D array), ``.csv`` (x, y, z after the alignment, deviation, face index) or
    ``.ply`` (the aligned points with a ``deviation`` property, a scalar field for
    CloudCompare)."""
    from pathlib import Path

    from .._files import atomic_path
    from ..errors import FileFormatError

    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".npy", ".csv", ".ply"):
        raise FileFormatError(f"{p}: --deviations writes .npy, .csv or .ply files, not '{suffix}'")
    with atomic_path(p) as tmp:
        if suffix == ".npy":
            np.save(tmp, result.deviation)
        elif suffix == ".csv":
            a = result.aligned
            data = np.column_stack([a, result.deviation, result.face])
            np.savetxt(tmp, data, delimiter=",", header="x,y,z,deviation,face", comments="", fmt=["%.9g"] * 4 + ["%d"])
        else:
            a = result.aligned
            head = ("ply\nformat binary_little_endian 1.0\ncomment gagekit compare: deviation in mm, positive outside "
                    f"the material, nan beyond max-distance\nelement vertex {len(a)}\nproperty double x\nproperty double y\n"
                    "property double z\nproperty double deviation\nend_header\n").encode("ascii")
            body = np.empty(len(a), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("deviation", "<f8")])
            body["x"], body["y"], body["z"], body["deviation"] = a[:, 0], a[:, 1], a[:, 2], result.deviation
            with open(tmp, "wb") as fh:
                fh.write(head)
                body.tofile(fh)
