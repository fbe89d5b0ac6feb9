"""An inspection compiled once for its Monte Carlo trials: each trial is then one step of
one kernel call (``gagekit._core.gdt.InspectionPlan``, ``gagekit_gdt::plan``), and a block
of trials runs in parallel in Rust without the interpreter.

:func:`compile_plan` turns the drawing and its measured evaluation into the plan: per
feature its rows in the active points (the union of the feature regions), its shape and
the starts the measured evaluation found (the least-squares cylinder or sphere, the
minimax cylinders' axes, the flatness zone's normal, the minimum-zone sphere's centre);
per datum (each prefix of a feature control frame's letters, ISO 5459) its feature, the
datums before it and its basic angle; the datum frames the location callouts need; per
callout its characteristic, feature, tolerance, datums, sections and nominal. The kernel
evaluates what :func:`gagekit.inspect.zones.evaluate` does, with the same kernels and the
same starts, except the least-squares cylinders and sphere: Gauss-Newton from the measured
fit to a step of 1e-12 mm (``gagekit_form::lsq::warm``), the stationary point the complete
fits converge to (``tests/uncertainty/test_plan.py`` holds the values equal to 1e-9 mm on
perturbed scans).

A drawing the plan does not cover -- a cone, slot, tab or CAD surface in a callout, a
median-line axis, least-squares datums, a datum point, sizes, distances and angles,
material conditions, filtered roundness, a fixed orientation (``nominal.direction`` of an
orientation callout), a profile offset -- returns ``None`` with the reason, and the trials
run the Python evaluation instead.
"""

from __future__ import annotations

from typing import Any, Mapping, Optional

import numpy as np

from .. import _core

__all__ = ["compile_plan", "SUPPORTED"]

#: The characteristics the plan evaluates.
SUPPORTED = ("flatness", "straightness", "roundness", "cylindricity", "sphericity", "parallelism", "perpendicularity",
             "angularity", "position", "coaxiality", "profile", "circular-runout", "total-runout")
_SHAPES = ("plane", "line", "circle", "sphere", "cylinder")
_CRITERIA = ("minimum-zone", "min-circumscribed", "max-inscribed")


class _Unsupported(Exception):
    pass


def _vec(v: Any) -> Optional[tuple[float, float, float]]:
    if v is None:
        return None
    a = np.asarray(v, dtype=float).reshape(3)
    return (float(a[0]), float(a[1]), float(a[2]))


def _axis(w: Any) -> Optional[tuple[Any, Any]]:
    return None if w is None else (_vec(w[0]), _vec(w[1]))


def _lsq_start(fd: Any) -> Optional[tuple]:
    """The measured least-squares cylinder (point, direction, radius) or sphere (centre,
    None, radius) a trial's fit starts from (Gauss-Newton, ``gagekit_form::lsq::warm``)."""
    fit = fd._cache.get("lsq")
    if fd.shape == "cylinder" and fit is not None:
        return (_vec(fit.point), _vec(fit.direction), float(fit.radius))
    if fd.shape == "sphere" and fit is not None:
        return (_vec(fit.center), None, float(fit.radius))
    return None


def compile_plan(spec: Any, feats: Mapping[str, Any], rows: Mapping[str, np.ndarray], warm: Mapping[str, dict],
                 near: Mapping[str, dict]) -> tuple[Optional[Any], str]:
    """(the plan, "") or (None, why not) for the drawing ``spec`` with its measured
    features ``feats``, their ``rows`` in the active points, the measured fits' starts
    ``warm`` ({feature: {criterion: (point, direction), "slab": normal, "least-squares":
    (point, direction)}}) and the measured sphericity zones ``near`` ({feature: details})."""
    try:
        return _compile(spec, feats, rows, warm, near), ""
    except _Unsupported as exc:
        return None, str(exc)


def _compile(spec, feats, rows, warm, near):
    if getattr(spec, "cad", None) is not None:
        raise _Unsupported("a drawing with a CAD model")
    index: dict[str, int] = {}
    features: list[tuple] = []

    def feature(name: str) -> int:
        if name in index:
            return index[name]
        fd = feats[name]
        if fd.shape not in _SHAPES:
            raise _Unsupported(f"feature '{name}' is a {fd.shape}")
        if fd.shape == "cylinder" and fd.spec.axis != "least-squares":
            raise _Unsupported(f"feature '{name}' has a median-line axis")
        w = warm.get(name, {})
        box = fd.box_axes()
        features.append((fd.shape, np.ascontiguousarray(rows[name], dtype=np.int64), _vec(fd.spec.outward),
                         _vec(fd.sign_hint()), tuple(_vec(r) for r in box), fd.spec.kind == "hole",
                         (_lsq_start(fd), *(_axis(w.get(c)) for c in _CRITERIA),
                          _vec(w.get("slab")), _vec(near[name]["center"]) if name in near else None)))
        index[name] = len(features) - 1
        return index[name]

    entries: dict[tuple[str, ...], int] = {}
    datums: list[tuple] = []

    def datum(letters: tuple[str, ...]) -> int:
        if letters in entries:
            return entries[letters]
        prior = [datum(letters[:k]) for k in range(1, len(letters))]
        ref = spec.datums[letters[-1]]
        fd = feats[ref.feature]
        if fd.spec.datum_fit != "chebyshev":
            raise _Unsupported(f"datum {ref.letter} is fitted by {fd.spec.datum_fit}")
        if fd.shape not in ("plane", "cylinder", "circle"):
            raise _Unsupported(f"datum {ref.letter} is a {fd.shape}")
        types = ["plane" if feats[spec.datums[letters[k - 1]].feature].shape == "plane" else "axis" for k in range(1, len(letters))]
        if fd.shape != "plane" and types and types[0] == "axis":
            raise _Unsupported(f"datum axis {ref.letter} behind a datum axis")
        if fd.shape == "plane" and types == ["axis", "axis"]:
            raise _Unsupported(f"datum plane {ref.letter} behind two datum axes")
        datums.append((feature(ref.feature), prior, float(ref.angle)))
        entries[letters] = len(datums) - 1
        return entries[letters]

    frames: list[list[int]] = []

    def frame(letters: tuple[str, ...]) -> int:
        chain = [datum(letters[:k + 1]) for k in range(len(letters))]
        if chain not in frames:
            frames.append(chain)
        return frames.index(chain)

    callouts = []
    for tol in spec.tolerances:
        char, fd = tol.characteristic, feats[tol.feature]
        where = f"callout #{tol.index + 1} ({char} of '{tol.feature}')"
        if char not in SUPPORTED:
            raise _Unsupported(f"{where}: {char}")
        if tol.material is not None or any(tol.datum_material) or tol.form_filter is not None or tol.offset:
            raise _Unsupported(f"{where}: a material condition, filter or offset")
        shape = fd.shape
        ok = {"flatness": ("plane",), "straightness": ("line",), "roundness": ("cylinder", "circle"),
              "cylindricity": ("cylinder",), "sphericity": ("sphere",), "profile": ("plane",),
              "coaxiality": ("cylinder", "circle", "sphere"), "circular-runout": ("cylinder", "circle", "plane"),
              "total-runout": ("cylinder", "circle", "plane"), "position": ("plane", "sphere", "circle", "cylinder"),
              }.get(char, ("plane", "cylinder"))
        if shape not in ok or (char == "straightness" and fd.spec.outward is None):
            raise _Unsupported(f"{where}: of a {shape}")
        if char in ("parallelism", "perpendicularity", "angularity") and tol.nominal_direction is not None:
            raise _Unsupported(f"{where}: a fixed orientation")
        f = feature(tol.feature)
        letters = tuple(tol.datums)
        chain = [datum(letters[:k + 1]) for k in range(len(letters))]
        fr = None
        if char == "position" or (char == "profile" and letters):
            if len(letters) == 0:
                raise _Unsupported(f"{where}: without datums")
            fr = frame(letters)
            if tol.nominal_point is None or (shape in ("plane", "cylinder") and tol.nominal_direction is None):
                raise _Unsupported(f"{where}: without its nominal")
        if char in ("coaxiality", "circular-runout", "total-runout"):
            chain = chain[:1]
            if not chain:
                raise _Unsupported(f"{where}: without a datum")
        callouts.append((char, f, float(tol.tolerance), chain, fr, float(tol.angle or 0.0), int(tol.sections or fd.spec.sections),
                         _vec(tol.nominal_point), _vec(tol.nominal_direction)))
    return _core.gdt.InspectionPlan(features, datums, frames, callouts)

