"""Material conditions (ISO 2692:2021, ASME Y14.5-2018 Sec. 7): bonus and datum shift.

**Bonus.** A position, orientation or straightness callout of a feature of size with
``material = "MMC"`` gets the departure of the feature's actual mating size from its
maximum material size as extra tolerance: a hole's (slot's) mating size is its maximum
inscribed size GX, its MMC size the lower limit; a shaft's (tab's) mating size is GN,
its MMC size the upper limit; ``bonus = max(0, GX - lower limit)`` or
``max(0, upper limit - GN)``. With ``material = "LMC"`` the actual minimum material size
(a hole's GN, a shaft's GX) against the LMC size (a hole's upper, a shaft's lower
limit). The limits are those of the feature's first ``size`` callout (required). The
mating sizes are the unrelated ones (free orientation, ASME's unrelated actual mating
envelope); ``tolerance = 0`` with MMC is the "zero at MMC" callout: the whole zone is
bonus. ``zone`` (the JSON's ``tolerance_zone``) = ``tolerance + bonus``; ``margin =
tolerance_zone - measured``.

**Datum shift.** A datum feature of size referenced at MMB / LMB (``datums = ["A",
"B(M)"]``) is simulated by a gauge of its MMB (its MMC size; LMB: its LMC size); the part
may shift on that gauge by as much as the feature departs from it. gagekit takes the
shift region as the disk of radius ``(mating size - MMB size) / 2`` (a hole's GX, a
shaft's GN; LMB: the minimum material size) about the simulated datum axis, normal to
it: the largest disk about the mating axis that keeps the gauge inside the feature, a
conservative inner part of the exact (non-convex) shift region. The position's zone
then may move by any shift s in that disk, and ``measured`` is the exact optimum of the
small problem min over |s| <= rho of max_i |w_i - s| (w_i: the toleranced axis's points
relative to the nominal axis, normal to it): the minimum enclosing circle of the w_i
(Welzl) when its centre lies within the disk, otherwise a point of the disk's rim, the
minimum of the upper envelope of the sinusoids |w_i|^2 + rho^2 - 2 rho w_i . e(phi)
(exact: a sinusoid's minimum or a crossing of two). Supported for the position of axes
and circle centres parallel to one shifted datum axis (a cylinder or circle datum).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .. import _core
from ..errors import ConfigError
from .features import FeatureData, _unit
from .sizes import mating_size
from .spec import Tolerance
from .zone_tools import Measurement, _element

__all__ = ["apply_material", "shift_radius", "min_in_disk"]


def _size_limits(system: Any, feature: str, where: str, why: str) -> tuple[float, float]:
    for t in system.spec.tolerances:
        if t.feature == feature and t.characteristic == "size":
            return float(t.lower_limit), float(t.upper_limit)
    raise ConfigError(f"{where}: {why} needs the size limits of '{feature}': add a [[tolerance]] characteristic = \"size\" "
                      "for it")


def _internal(fd: FeatureData) -> bool:
    return fd.shape == "slot" or fd.spec.kind == "hole"


def _departure(fd: FeatureData, condition: str, lo: float, hi: float, where: str) -> tuple[float, float, str]:
    """(departure >= 0, actual size, which) of the feature from its MMC / LMC size."""
    if fd.shape not in ("slot", "tab") and fd.spec.kind is None:
        raise ConfigError(f"{where}: feature '{fd.name}' needs kind = \"hole\" or \"shaft\" for a material condition")
    internal = _internal(fd)
    if condition in ("MMC", "M"):
        which = "GX" if internal else "GN"
        size = mating_size(fd, which)
        dep = (size - lo) if internal else (hi - size)
    else:
        which = "GN" if internal else "GX"
        size = mating_size(fd, which)
        dep = (hi - size) if internal else (size - lo)
    return max(0.0, dep), size, which


def shift_radius(system: Any, letter: str, mod: str, where: str) -> float:
    """The radius of the datum shift disk of datum ``letter`` at MMB (``"M"``) or LMB (``"L"``)."""
    fd = system.feats[system.spec.datums[letter].feature]
    if fd.shape not in ("cylinder", "circle"):
        raise ConfigError(f"{where}: datum {letter}({mod}): a datum shift is supported for cylinder and circle datum "
                          f"features, not for a {fd.shape}")
    lo, hi = _size_limits(system, fd.name, where, f"datum {letter}({mod})")
    dep, _, _ = _departure(fd, mod, lo, hi, where)
    return 0.5 * dep


def min_in_disk(w: np.ndarray, rho: float) -> tuple[float, np.ndarray]:
    """Exact min over |s| <= rho of max_i |w_i - s| for 2-D points ``w`` (see the module
    docstring; ``gagekit_gdt::turn::min_in_disk``): (value, s)."""
    v, s = _core.gdt_min_in_disk(np.ascontiguousarray(w, dtype=float), float(rho))
    return v, np.array(s)


def _position_with_shift(tol: Tolerance, fd: FeatureData, system: Any, letter: str, rho: float, where: str) -> tuple[float, float]:
    """(measured diameter, shift used) of a position callout whose datum ``letter`` may shift by ``rho``."""

    datum = system.datum(tol.datums[: tol.datums.index(letter) + 1])
    if datum.type != "axis":
        raise ConfigError(f"{where}: datum {letter} at MMB / LMB must be a datum axis for its shift")
    a = _unit(datum.vector)
    frame = system.frame(tol.datums)
    if len(frame.free_translations):
        raise ConfigError(f"{where}: a datum shift with translations the datums leave free is not supported")
    P0 = frame.point_to_scan(tol.nominal_point)
    if fd.shape == "circle":
        D0 = frame.direction_to_scan(tol.nominal_direction) if tol.nominal_direction is not None else _unit(fd.lsq().normal)
        pts = np.array(fd.lsq().center)[None, :]
    elif fd.shape in ("cylinder", "cone"):
        D0 = frame.direction_to_scan(tol.nominal_direction)
        pts, _ = _element(fd)
    else:
        raise ConfigError(f"{where}: a datum shift is supported for the position of axes and circle centres, not of a {fd.shape}")
    if abs(abs(float(D0 @ a)) - 1.0) > 1e-6:
        raise ConfigError(f"{where}: a datum shift is supported when the nominal axis is parallel to the shifted datum axis {letter}")
    u = _unit(np.cross(a, [1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.cross(a, [0.0, 1.0, 0.0]))
    v = np.cross(a, u)

    # the turn about z, when the datums leave it free, searched in the same kernel call
    r, used, _ = _core.gdt_position_with_shift(np.ascontiguousarray(pts), frame.kernel_args(), tuple(P0), tuple(u), tuple(v), rho)
    return 2.0 * r, used


def apply_material(tol: Tolerance, fd: FeatureData, system: Any, m: Measurement) -> Measurement:
    """The measurement with its bonus and datum shift (module docstring); unchanged
    without material conditions."""
    shifted = [(letter, mod) for letter, mod in zip(tol.datums, tol.datum_material) if mod]
    if tol.material is None and not shifted:
        return m
    where = f"{system.spec.source}: [[tolerance]] #{tol.index + 1} ({tol.characteristic} of '{fd.name}')"
    extra = dict(m.extra)
    details = dict(m.details)
    value = m.value
    bonus = 0.0
    if tol.material is not None:
        lo, hi = _size_limits(system, fd.name, where, f"material = \"{tol.material}\"")
        bonus, size, which = _departure(fd, tol.material, lo, hi, where)
        details.update(actual_size=size, actual_size_modifier=which,
                       material_size=(lo if _internal(fd) else hi) if tol.material == "MMC" else (hi if _internal(fd) else lo))
        extra["material"] = tol.material
    shift_used = 0.0
    if shifted:
        if len(shifted) > 1:
            raise ConfigError(f"{where}: 'datums': one datum at MMB / LMB per callout is supported")
        letter, mod = shifted[0]
        if tol.characteristic != "position":
            raise ConfigError(f"{where}: a datum shift applies to position callouts here (orientation zones do not move)")
        rho = shift_radius(system, letter, mod, where)
        value, shift_used = _position_with_shift(tol, fd, system, letter, rho, where)
        details.update(datum_shift_allowed=rho, datum=letter + f"({mod})", measured_without_shift=m.value)
    zone = tol.tolerance + bonus
    extra.update(bonus=bonus, datum_shift=shift_used, tolerance_zone=zone)
    return replace(m, value=value, margin=zone - value, extra=extra, details=details)
