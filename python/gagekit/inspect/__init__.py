"""Inspect a scan against its drawing: GD&T callouts relative to datum reference frames
(ISO 1101:2017 geometrical tolerancing, ISO 5459:2011 datums).

``inspect(points, spec)`` cuts every feature's points out of the scan by its region box
(Sec. 5.4.1), simulates the datums in the order of each feature control frame
(:mod:`.datums`), builds the datum frame and evaluates every callout's tolerance zone
exactly (:mod:`.zones`; the zone kernels are the Rust crate ``gagekit-gdt`` and the form
kernels of :mod:`gagekit.form`). The spec is a PART.toml (:mod:`.spec`).

The module docstrings of :mod:`.spec`, :mod:`.datums`, :mod:`.features` and :mod:`.zones`
define every characteristic with its ISO reference, and say for each zone whether
``tolerance`` is a width or a diameter; ``docs/inspection.md`` gathers them.
"""

from __future__ import annotations

import time
from typing import Any, Union

import numpy as np

from .._util import as_points
from .datums import DatumFrame, DatumSystem, SimulatedDatum
from .features import FeatureData, extract
from .result import CalloutResult, InspectionResult
from .spec import APPLIES_TO, CHARACTERISTICS, SHAPES, PartSpec, load_part_spec, part_spec_from_dict
from .zones import evaluate

__all__ = [
    "inspect",
    "inspect_stream",
    "load_part_spec",
    "part_spec_from_dict",
    "PartSpec",
    "InspectionResult",
    "CalloutResult",
    "DatumFrame",
    "SimulatedDatum",
    "CHARACTERISTICS",
    "SHAPES",
    "APPLIES_TO",
]


def inspect(points: Any, spec: Union[PartSpec, str, Any]) -> InspectionResult:
    """Evaluate every callout of ``spec`` (a :class:`PartSpec`, or the path of a PART.toml)
    on the scan ``points`` ((n, 3), mm, in the frame the spec's regions are given in).

    Returns an :class:`InspectionResult`; nonconforming parts are a result, not an error.

    Raises
    ------
    ConfigError
        A mistake in the spec (naming the table and key), e.g. a secondary datum plane
        parallel to the primary.
    DegenerateGeometryError
        A region with too few points for its shape.
    InvalidInputError
        Points of the wrong shape or with NaN / inf.
    """
    t0 = time.perf_counter()
    if not isinstance(spec, PartSpec):
        spec = load_part_spec(spec)
    pts = as_points(points)  # the region kernel checks finiteness (naming the row)
    cad = None
    if spec.cad is not None:
        from ..cad.context import CadContext

        cad = CadContext.of_scan(spec.cad, pts)
    feats = extract(pts, spec.features, spec.source, cad)
    return _evaluate(spec, feats, int(len(pts)), t0)


def inspect_stream(stream: Any, spec: Union[PartSpec, str, Any]) -> InspectionResult:
    """:func:`inspect` of a streamed scan (:func:`gagekit.cloud.stream.open_cloud`, or any
    re-iterable of (m, 3) chunks in file order): one pass keeps the points inside the
    feature regions only (every one: the fits need them all), then the same evaluation."""
    from .features import extract_stream

    t0 = time.perf_counter()
    if not isinstance(spec, PartSpec):
        spec = load_part_spec(spec)
    if getattr(spec, "cad", None) is not None:
        from ..errors import InvalidInputError

        raise InvalidInputError(f"{spec.source}: a drawing with a [part] cad model is matched to the whole scan: "
                                "read it whole (inspect)")
    n, feats = extract_stream(stream, spec.features, spec.source)
    return _evaluate(spec, feats, n, t0)


def _evaluate(spec: PartSpec, feats: dict, n: int, t0: float) -> InspectionResult:
    system = DatumSystem(spec, feats)
    results = []
    for tol in spec.tolerances:
        fd = feats[tol.feature]
        m = evaluate(tol, fd, system)
        results.append(CalloutResult(tol.feature, tol.characteristic, tol.tolerance, float(m.value), m.zone, tol.datums,
                                     m.n_points, m.element, tol.name, tol.angle, m.details, m.margin, m.extra))
    refs = sorted({t.datums for t in spec.tolerances if t.datums and t.characteristic in ("position", "profile", "profile-line")} |
                  {t.datums for t in spec.tolerances if t.datums}, key=lambda d: (-len(d), d))
    frames = []
    for r in refs:
        if r not in [f.datums for f in frames]:
            frames.append(system.frame(r))
    main = frames[0] if frames else None
    used = {n: feats[n] for n in spec.features}
    return InspectionResult(spec.name, n, tuple(system.simulated()), main, tuple(frames), tuple(results), used,
                            time.perf_counter() - t0, feats)
