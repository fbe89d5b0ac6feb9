"""The studio's state on the server: one scan, one gage file, and the library calls
each request needs. No geometry lives here: regions, alignment, the gage check and
the distances come from :mod:`gagekit.cloud` and :mod:`gagekit.gage`.

The scan stays whole on the server (every count and every check uses all of its
points); the browser gets a level-of-detail subsample (LOD) for display: a fixed,
seeded choice of at most ``lod_max`` points, so the same scan always shows the same
points.
"""

from __future__ import annotations

import base64
import dataclasses
import math
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .._files import write_bytes
from ..cloud.grid import IndexedCloud
from ..cloud.io import read_points
from ..cloud.regions import Box
from ..errors import ConfigError, GagekitError, InvalidInputError
from ..gage.analysis import check_gages, datum_alignment, gage_distances, region_in_scanner
from ..gage.spec import Region
from . import specdoc
from .cadview import MAX_CAD_TRIANGLES, CadView

LOD_MAX = 1_000_000
"""Most points sent to the browser for display (a million points draw in under a second
even on a software renderer; every count and check uses all points)."""
LOD_SEED = 0


def _b64(arr: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(arr).tobytes()).decode("ascii")


@dataclass
class Scan:
    """A loaded scan: all points (indexed for region queries) and the LOD for display."""

    path: Path
    units: Optional[str]
    cloud: IndexedCloud
    lod: np.ndarray
    """indices (ascending) of the displayed points"""
    lod_cloud: IndexedCloud
    origin: np.ndarray
    """offset subtracted from the float32 display coordinates (centre of the bounding box)"""
    load_seconds: float

    @property
    def points(self) -> np.ndarray:
        return self.cloud.points

    def info(self) -> dict:
        pts = self.points
        lo, hi = self.cloud.bounds
        return {"name": self.path.name, "path": str(self.path), "units": self.units or "mm",
                "count": int(len(pts)), "lod_count": int(len(self.lod)),
                "bbox": {"min": lo.tolist(), "max": hi.tolist()}, "origin": self.origin.tolist(),
                "load_seconds": round(self.load_seconds, 3)}

    def lod_buffer(self) -> bytes:
        """The displayed points as little-endian float32 x, y, z, minus :attr:`origin`."""
        return np.ascontiguousarray(self.lod_cloud.points - self.origin, dtype="<f4").tobytes()


def display_subsample(n: int, m: int, seed: int = LOD_SEED) -> np.ndarray:
    """Ascending indices of at most ``m`` of ``n`` points: one point drawn (seeded) from
    each of ``m`` equal runs of the file order, so the subsample spreads over the whole
    scan and costs ``m`` random numbers, not ``n``."""
    if n <= m:
        return np.arange(n)
    edges = (np.arange(m + 1, dtype=np.float64) * (n / m)).astype(np.int64)
    width = np.maximum(edges[1:] - edges[:-1], 1)
    return edges[:-1] + (np.random.default_rng(seed).random(m) * width).astype(np.int64)


def load_scan(path: Path, units: Optional[str] = None, lod_max: int = LOD_MAX) -> Scan:
    """Read a scan, index it, choose its display subsample."""
    t0 = time.perf_counter()
    pts = read_points(path, units=units)
    cloud = IndexedCloud(pts)
    lod = display_subsample(len(pts), lod_max)
    lod_cloud = IndexedCloud(pts[lod])
    lo, hi = cloud.bounds
    origin = np.round((lo + hi) / 2.0, 3)
    return Scan(path, units, cloud, lod, lod_cloud, origin, time.perf_counter() - t0)


def box_of(table: Any, what: str = "region") -> Region:
    """A region table of the client's document (``center``, ``size``, ``rotation`` in
    rad, ``frame``) as a spec :class:`~gagekit.gage.spec.Region`."""
    if not isinstance(table, dict):
        raise InvalidInputError(f"{what}: expected a table with center, size and rotation")
    frame = table.get("frame", "part")
    if frame not in ("part", "scanner"):
        raise ConfigError(f"{what}: frame must be \"part\" or \"scanner\", got {frame!r}")
    for key in ("center", "size"):
        if key not in table:
            raise ConfigError(f"{what}: needs '{key}'")
    name = table.get("name") if isinstance(table.get("name"), str) and table.get("name") else "region"
    return Region(Box(table["center"], table["size"], table.get("rotation", (0.0, 0.0, 0.0)), name=name), frame)


class Session:
    """One scan, one gage file, the alignment found for it; safe to share between threads."""

    def __init__(self, scan: Scan, spec_path: Optional[Path], lod_max: int = LOD_MAX, kind: str = "gage",
                 root: Optional[Path] = None) -> None:
        self.lock = threading.RLock()
        self.scan = scan
        self.lod_max = lod_max
        self.root = (root or scan.path.parent).resolve()
        """the studio folder: a CAD model named by a drawing must lie inside it"""
        self.cad: Optional[CadView] = None
        self.cad_max_triangles = MAX_CAD_TRIANGLES
        self.spec_path: Optional[Path] = None
        self.spec_text = ""
        self.alignment = None
        self.alignment_key: Optional[str] = None
        self.alignment_error: Optional[str] = None
        self.open_spec(spec_path, kind)

    # ------------------------------------------------------------------ scan

    def replace_scan(self, path: Path, units: Optional[str]) -> dict:
        scan = load_scan(path, units, self.lod_max)
        with self.lock:
            self.scan = scan
            self.alignment = None
            self.alignment_key = None
        return scan.info()

    # ------------------------------------------------------------------ spec

    @property
    def source(self) -> str:
        return self.spec_path.name if self.spec_path is not None else "new gage file"

    def open_spec(self, path: Optional[Path], kind: str = "gage") -> dict:
        text = ""
        if path is not None and path.exists():
            from .._files import read_text

            try:  # a regular file only: opening a FIFO would block until a writer comes
                text = read_text(path, "gage file")
            except GagekitError as exc:
                raise ConfigError(f"cannot read the gage file: {exc}") from None
        with self.lock:
            self.spec_path = path
            self.spec_text = text
            self.new_kind = kind if kind in ("gage", "part") else "gage"
            self.alignment = None
            self.alignment_key = None
        return self.spec_model()

    def spec_model(self) -> dict:
        """The document for the client, with the reader's errors located by table."""
        source = self.source
        if self.spec_text.strip():
            try:
                doc = specdoc.parse_text(self.spec_text, source)
            except ConfigError as exc:
                return {"path": str(self.spec_path), "name": source, "doc": None, "parse_error": str(exc),
                        "validation": {"valid": False, "errors": [specdoc.locate(str(exc), source)], "warnings": []}}
        elif getattr(self, "new_kind", "gage") == "part":
            doc = {"part": {"name": self.spec_path.stem if self.spec_path is not None else "part"}}
        else:
            doc = {"length_unit": "mm", "motion": {"free": ["alpha", "beta", "gamma", "dx", "dy", "dz"],
                                                   "max_angle": 0.05, "max_shift": 20.0}}
        check = specdoc.validate(doc, source)
        return {"path": None if self.spec_path is None else str(self.spec_path), "name": source,
                "exists": bool(self.spec_text), "kind": specdoc.kind_of(doc), "doc": doc,
                "validation": check.to_dict()}

    def save(self, doc: Any, path: Optional[Path]) -> dict:
        """Write ``doc`` (atomically) to ``path`` or the open file, as the open file's text
        with the edits applied; the unchanged document writes the original text back byte
        for byte."""
        target = path or self.spec_path
        if target is None:
            raise ConfigError("no gage file to save to: give a file name")
        same = target == self.spec_path
        original = self.spec_text  # "save as" too keeps the open file's comments and layout
        text = specdoc.render(original, doc, target.name)
        write_bytes(target, text.encode("utf-8"))  # atomic: temporary file, then rename
        with self.lock:
            self.spec_path = target
            self.spec_text = text
        check = specdoc.validate(doc, target.name)
        return {"path": str(target), "name": target.name, "bytes": len(text.encode("utf-8")),
                "unchanged": same and text == original, "validation": check.to_dict()}

    # ------------------------------------------------------------------ CAD model

    def drawing_cad(self, doc: Any = None) -> Optional[Path]:
        """The file of the drawing's ``[part] cad`` (relative to the drawing's folder), or
        None; :class:`OutsideError` when it leads outside the studio folder."""
        if doc is None:
            try:
                doc = specdoc.parse_text(self.spec_text, self.source) if self.spec_text.strip() else None
            except ConfigError:
                return None
        part = doc.get("part") if isinstance(doc, dict) else None
        rel = part.get("cad") if isinstance(part, dict) else None
        if not isinstance(rel, str) or not rel:
            return None
        base = self.spec_path.parent if self.spec_path is not None else self.root
        full = (base / rel).resolve()
        if full != self.root and self.root not in full.parents:
            raise OutsideError(f"[part] cad: '{rel}' is outside the studio folder {self.root}")
        return full

    def cad_state(self) -> dict:
        """The open CAD model (or None) and the drawing's (relative to the studio folder)."""
        drawing, error = None, None
        try:
            full = self.drawing_cad()
            drawing = None if full is None else full.relative_to(self.root).as_posix()
        except OutsideError as exc:
            error = str(exc)
        with self.lock:
            view = self.cad
        return {"open": None if view is None else view.info(), "drawing": drawing, "drawing_error": error}

    def open_cad(self, path: Optional[Path], units: Optional[str] = None, max_distance: Optional[float] = None) -> dict:
        """Open a CAD model beside the scan: ``path`` (inside the studio folder) or, when
        None, the drawing's ``[part] cad`` (read once, shared with the inspection)."""
        from ..cad.context import cad_model

        if max_distance is not None and not (math.isfinite(max_distance) and max_distance > 0):
            raise ConfigError(f"max_distance must be a positive number of mm, got {max_distance}")
        if path is None:
            path = self.drawing_cad()
            if path is None:
                raise ConfigError(f"{self.source}: the drawing names no CAD model ([part] cad); choose a CAD file")
        if units is None and path == self.drawing_cad():
            model = cad_model(str(path))
        else:
            from ..cad import read_cad

            model = read_cad(path, units)
        view = CadView(model, path.relative_to(self.root).as_posix() if self.root in path.parents else path.name,
                       max_distance, self.cad_max_triangles)
        with self.lock:
            self.cad = view
        return view.info()

    def close_cad(self) -> dict:
        with self.lock:
            self.cad = None
        return self.cad_state()

    def cad_mesh(self) -> Optional[CadView]:
        with self.lock:
            return self.cad

    def _cad_colours(self, ctx: Any) -> Optional[dict]:
        """The open CAD model's vertex colours from every scan point's deviation (the
        inspection's distances when it is the drawing's model, else computed here)."""
        with self.lock:
            view = self.cad
        if view is None:
            return None
        pts = self.scan.points
        if ctx is not None and ctx.model is view.model and ctx.triangle is not None:
            tri, dev = ctx.triangle, ctx.distance
        else:
            d = view.model.distances(pts)
            tri, dev = d.triangle, d.distance
        return dict(view.colours(tri, dev), info=view.info())

    # ------------------------------------------------------------------ regions

    def _aligned(self, doc: Any):
        """The alignment of ``doc``'s datums (cached on the datum tables), or None."""
        if not isinstance(doc, dict) or not doc.get("alignment"):
            return None, None
        al = doc["alignment"]
        names = set()
        if isinstance(al, dict):
            for v in al.values():
                names.update(x for x in (v if isinstance(v, list) else [v]) if isinstance(x, str))
        regions = doc.get("region", [])
        datums = [r for r in (regions if isinstance(regions, list) else [])
                  if isinstance(r, dict) and isinstance(r.get("name"), str) and r["name"] in names]
        key = repr((al, datums, doc.get("angle_unit"), str(self.scan.path)))
        with self.lock:
            if key == self.alignment_key:
                return self.alignment, self.alignment_error
        check = specdoc.validate(doc, self.source)
        alignment, error = None, None
        if check.spec is None:
            error = check.errors[0]["message"]
        else:
            try:
                alignment = datum_alignment(self.scan.points, check.spec)
            except GagekitError as exc:
                error = str(exc)
        with self.lock:
            self.alignment, self.alignment_error, self.alignment_key = alignment, error, key
        return alignment, error

    def regions(self, doc: Any) -> dict:
        """Counts of every region of ``doc`` over all points, and the datum frame (for a
        drawing: every feature's region, in the scan's frame)."""
        if specdoc.kind_of(doc) == "part":
            return self._feature_regions(doc)
        alignment, error = self._aligned(doc)
        tables = doc.get("region", []) if isinstance(doc, dict) else []
        if not isinstance(tables, list):
            raise ConfigError(f"{self.source}: regions must be given as [[region]] tables")
        ang = math.pi / 180.0 if isinstance(doc, dict) and doc.get("angle_unit") == "deg" else 1.0
        out = []
        for k, t in enumerate(tables):
            name = t.get("name") if isinstance(t, dict) else None
            try:
                region = box_of(_in_rad(t, ang), f"region '{name}'" if name else f"region #{k + 1}")
                box = region_in_scanner(region, alignment)
                out.append({"name": name, "count": self.scan.cloud.count(box), "error": None})
            except GagekitError as exc:
                out.append({"name": name, "count": None, "error": str(exc)})
        return {"regions": out, "alignment": _alignment_dict(alignment), "alignment_error": error,
                "validation": specdoc.validate(doc, self.source).to_dict()}

    def _feature_regions(self, doc: dict) -> dict:
        tables = doc.get("feature", [])
        if not isinstance(tables, list):
            raise ConfigError(f"{self.source}: features must be given as [[feature]] tables")
        out = []
        for k, t in enumerate(tables):
            name = t.get("name") if isinstance(t, dict) else None
            if isinstance(t, dict) and "faces" in t and "region" not in t:  # located by CAD faces at Run
                out.append({"name": name, "count": None, "error": None, "faces": t["faces"]})
                continue
            try:
                region = t.get("region") if isinstance(t, dict) else None
                box = box_of(dict(region, frame="scanner") if isinstance(region, dict) else region,
                             f"feature '{name}'" if name else f"feature #{k + 1}").box
                out.append({"name": name, "count": self.scan.cloud.count(box), "error": None})
            except GagekitError as exc:
                out.append({"name": name, "count": None, "error": str(exc)})
        return {"regions": out, "alignment": None, "alignment_error": None,
                "validation": specdoc.validate(doc, self.source).to_dict()}

    def select(self, table: Any) -> dict:
        """Points inside one box (rotation in rad; a part-frame box is placed by the
        alignment last found by :meth:`regions`): the count over all points and which
        displayed points are inside, as whichever is smaller: ``indices`` (little-endian
        uint32 positions in the displayed points, ascending) or ``mask`` (one bit per
        displayed point, little-endian bit order). The client's work then grows with the
        box, not with the scan."""
        region = box_of(table)
        with self.lock:
            alignment = self.alignment
        box = region_in_scanner(region, alignment)
        scan = self.scan
        count = scan.cloud.count(box)
        lod_idx = scan.lod_cloud.select(box)
        out = {"count": int(count), "lod_count": int(len(lod_idx))}
        if 32 * len(lod_idx) < len(scan.lod):
            out["indices"] = _b64(lod_idx.astype("<u4"))
        else:
            mask = np.zeros(len(scan.lod), dtype=bool)
            mask[lod_idx] = True
            out["mask"] = _b64(np.packbits(mask, bitorder="little"))
        return out

    # ------------------------------------------------------------------ run

    def run(self, doc: Any, groups: bool = True) -> dict:
        """The gage check of ``doc`` on all points, and per displayed point the signed
        distance to the nearest-binding gage plane at T* (NaN outside every gage region)."""
        check = specdoc.validate(doc, self.source)
        if check.spec is None:
            raise SpecError(check)
        if specdoc.kind_of(doc) == "part":
            return self._inspect(check, doc)
        scan = self.scan
        t0 = time.perf_counter()
        result = check_gages(scan.points, check.spec, groups=groups)
        seconds = time.perf_counter() - t0
        values = np.full(len(scan.lod), np.nan)
        for idx, e in gage_distances(scan.lod_cloud.points, check.spec, result):
            if len(idx):
                cur = values[idx]
                values[idx] = np.where(np.isnan(cur), e, np.minimum(cur, e))
        H = np.eye(4) if result.alignment is None else result.alignment.H
        view = result.transform.as_array() @ H
        finite = values[np.isfinite(values)]
        return {"result": result.to_dict(), "seconds": round(seconds, 3),
                "validation": check.to_dict(),
                "view_matrix": view.tolist(), "align_matrix": H.tolist(),
                "values": _b64(values.astype("<f4")),
                "value_range": [float(finite.min()), float(finite.max())] if len(finite) else None, "cad": None}

    def _inspect(self, check: "specdoc.Validation", doc: dict) -> dict:
        """The inspection of the drawing (:func:`gagekit.inspect`) on all points, and per
        displayed point of a feature its signed deviation from the feature's least-squares
        fit (mm; NaN outside every feature)."""
        from .._util import check_finite_result, to_jsonable
        from ..inspect import inspect

        scan = self.scan
        spec = check.spec
        if spec.cad is not None:  # relative to the drawing's folder, inside the studio folder
            spec = dataclasses.replace(spec, cad=str(self.drawing_cad(doc)))
        result = inspect(scan.points, spec)
        check_finite_result(result)
        ctx = next((fd._cache["cad"] for fd in result.feature_data.values() if "cad" in fd._cache), None)
        if ctx is not None and self.cad is None:  # the drawing's model: shown once the inspection has read it
            with self.lock:
                self.cad = CadView(ctx.model, Path(spec.cad).relative_to(self.root).as_posix(), None,
                                   self.cad_max_triangles)
        cad = self._cad_colours(ctx)
        values = np.full(len(scan.lod), np.nan)
        for name, fd in result.feature_data.items():
            pos = np.searchsorted(scan.lod, fd.indices)
            pos = np.minimum(pos, len(scan.lod) - 1)
            shown = scan.lod[pos] == fd.indices
            if shown.any():
                values[pos[shown]] = fd.deviations()[shown]
        finite = values[np.isfinite(values)]
        return {"kind": "part", "result": to_jsonable(result), "seconds": round(result.seconds, 3),
                "validation": check.to_dict(), "view_matrix": np.eye(4).tolist(), "align_matrix": np.eye(4).tolist(),
                "values": _b64(values.astype("<f4")),
                "value_range": [float(finite.min()), float(finite.max())] if len(finite) else None, "cad": cad}


class OutsideError(ConfigError):
    """A file named by the drawing leads outside the studio folder (HTTP 403)."""


class SpecError(GagekitError):
    """The gage document has errors (carried located, for the client)."""

    def __init__(self, check: "specdoc.Validation") -> None:
        super().__init__(check.errors[0]["message"] if check.errors else "invalid gage document")
        self.check = check


def _in_rad(table: Any, factor: float) -> Any:
    if factor == 1.0 or not isinstance(table, dict) or "rotation" not in table:
        return table
    rot = table["rotation"]
    if not isinstance(rot, list):
        return table
    return dict(table, rotation=[v * factor if isinstance(v, (int, float)) else v for v in rot])


def _alignment_dict(alignment) -> Optional[dict]:
    if alignment is None:
        return None
    return {"H": np.asarray(alignment.H).tolist(), "C": np.asarray(alignment.frame).tolist()}


__all__ = ["Session", "Scan", "load_scan", "box_of", "SpecError", "OutsideError", "LOD_MAX"]
