"""The reader of gage files (TOML; format in :mod:`gagekit.gage.spec`): every mistake raises
:class:`~gagekit.errors.ConfigError` whose message starts with the file name and names the
table and key."""

from __future__ import annotations

import math
import warnings
from typing import Any, Mapping, Optional

from .._util import named_tables
from ..cloud.regions import regions_from_tables
from ..errors import ConfigError
from .spec import DEFAULT_MAX_ANGLE, DEFAULT_MAX_SHIFT, MOTIONS, AlignmentSpec, Gage, GageFileWarning, GageSpec, MotionSet, Region

__all__ = ["parse_gage_spec"]

_TOP_KEYS = {"length_unit", "angle_unit", "motion", "alignment", "region", "gage", "description"}
_MOTION_KEYS = {"free", "max_angle", "max_shift"}
_ALIGN_KEYS = {"primary", "secondary", "tertiary"}
_REGION_KEYS = {"name", "frame", "center", "size", "rotation"}
_GAGE_KEYS = {"name", "region", "plane", "weight", "slack_weight"}



def _scaled_rotation(raw: Any, ang: float) -> Any:
    """A region's rotation in degrees, to radians (left as given when malformed: the box
    check then names the region and the key)."""
    if isinstance(raw, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in raw):
        return [float(v) * ang for v in raw]
    return raw

def _unknown(keys, allowed, where: str, source: str) -> None:
    extra = sorted(set(keys) - allowed)
    if extra:
        raise ConfigError(f"{source}: {where}: unknown key(s) {', '.join(map(repr, extra))}; "
                          f"allowed: {', '.join(sorted(allowed))}")


def _number(v: Any, where: str, source: str, minimum: Optional[float] = None, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{source}: {where} must be a number, got {v!r}")
    x = float(v)
    if not math.isfinite(x):
        raise ConfigError(f"{source}: {where} must be finite, got {v!r}")
    if positive and x <= 0:
        raise ConfigError(f"{source}: {where} must be positive, got {v!r}")
    if minimum is not None and x < minimum:
        raise ConfigError(f"{source}: {where} must be at least {minimum}, got {v!r}")
    return x


def _names(v: Any, where: str, source: str) -> tuple[str, ...]:
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not v or not all(isinstance(s, str) and s for s in v):
        raise ConfigError(f"{source}: {where} must be a non-empty list of names, got {v!r}")
    if len(set(v)) != len(v):
        raise ConfigError(f"{source}: {where} lists a name twice: {v!r}")
    return tuple(v)


def parse_gage_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """Validate a parsed gage file ``doc`` (see :mod:`gagekit.gage.spec` for the format)."""
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a table at the top level")
    _unknown(doc.keys(), _TOP_KEYS, "top level", source)
    ang = _angle_factor(doc, source)
    motion = _parse_motion(doc, source, ang)
    regions = _parse_regions(doc, source, ang)
    gages = _parse_gages(doc, source, {r.name for r in regions})
    alignment = _parse_alignment(doc, source, regions)
    return GageSpec(regions, tuple(gages), motion, alignment, source)


def parse_region_spec(doc: Mapping[str, Any], source: str) -> GageSpec:
    """The ``[[region]]`` tables and the ``[alignment]`` of a gage or regions file, without
    gages or motions (``cloud regions``): the regions placed as ``gage check`` places them."""
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a table at the top level")
    _unknown(doc.keys(), _TOP_KEYS, "top level", source)
    regions = _parse_regions(doc, source, _angle_factor(doc, source))
    return GageSpec(regions, (), alignment=_parse_alignment(doc, source, regions), source=source)


def _angle_factor(doc: Mapping[str, Any], source: str) -> float:
    """Radians per angle unit of the file (``length_unit`` must be mm)."""
    unit = doc.get("length_unit", "mm")
    if unit != "mm":
        raise ConfigError(f"{source}: length_unit must be \"mm\" (gage files are in millimetres), got {unit!r}")
    angle_unit = doc.get("angle_unit", "rad")
    if angle_unit not in ("rad", "deg"):
        raise ConfigError(f"{source}: angle_unit must be \"rad\" or \"deg\", got {angle_unit!r}")
    return math.pi / 180.0 if angle_unit == "deg" else 1.0


def _parse_motion(doc: Mapping[str, Any], source: str, ang: float) -> MotionSet:
    """[motion]: the free motions and their bounds (the set Omega of Eq. 5.2)."""
    mt = doc.get("motion", {})
    if not isinstance(mt, Mapping):
        raise ConfigError(f"{source}: [motion] must be a table")
    _unknown(mt.keys(), _MOTION_KEYS, "[motion]", source)
    raw_free = mt.get("free", list(MOTIONS))
    free = () if raw_free == [] else _names(raw_free, "[motion] free", source)  # [] = check as placed
    bad = [m for m in free if m not in MOTIONS]
    if bad:
        raise ConfigError(f"{source}: [motion] free: unknown motion(s) {', '.join(map(repr, bad))}; "
                          f"choose from {', '.join(MOTIONS)} (alpha about z, beta about y, gamma about x)")
    free = tuple(m for m in MOTIONS if m in free)
    max_angle = _number(mt.get("max_angle", DEFAULT_MAX_ANGLE / ang), "[motion] max_angle", source, minimum=0.0) * ang
    max_shift = _number(mt.get("max_shift", DEFAULT_MAX_SHIFT), "[motion] max_shift", source, minimum=0.0)
    if max_angle > 0.5:
        raise ConfigError(f"{source}: [motion] max_angle = {max_angle:.4g} rad is too large for a set-up "
                          "correction (at most 0.5 rad)")
    return MotionSet(free, max_angle, max_shift)


def _parse_regions(doc: Mapping[str, Any], source: str, ang: float) -> tuple[Region, ...]:
    """[[region]]: the sampling volumes (Sec. 5.4.1) and their frames."""
    tables = doc.get("region", [])
    if not isinstance(tables, list):
        raise ConfigError(f"{source}: regions must be given as [[region]] tables")
    frames = []
    for k, t in enumerate(tables):
        if not isinstance(t, Mapping):
            raise ConfigError(f"{source}: region #{k + 1} must be a table")
        label = f"region '{t.get('name')}'" if isinstance(t.get("name"), str) else f"region #{k + 1}"
        _unknown(t.keys(), _REGION_KEYS, label, source)
        frame = t.get("frame", "part")
        if frame not in ("part", "scanner"):
            raise ConfigError(f"{source}: {label}: frame must be \"part\" or \"scanner\", got {frame!r}")
        frames.append(frame)
    if ang != 1.0:
        tables = [dict(t, rotation=_scaled_rotation(t["rotation"], ang)) if "rotation" in t else t for t in tables]
    try:
        boxes = regions_from_tables(tables, source)
    except ConfigError as exc:
        msg = str(exc)
        raise ConfigError(msg if msg.startswith(source) else f"{source}: {msg}") from None
    return tuple(Region(b, f) for b, f in zip(boxes, frames))


def _parse_gages(doc: Mapping[str, Any], source: str, names: set) -> list[Gage]:
    """[[gage]]: the gage planes (Table 5.1), normalized, on regions of ``names``."""
    gtables = doc.get("gage", [])
    if not isinstance(gtables, list) or not gtables:
        raise ConfigError(f"{source}: no gages: add at least one [[gage]] table")
    gages: list[Gage] = []
    for name, t in named_tables(gtables, "gage", source):
        label = f"gage '{name}'"
        _unknown(t.keys(), _GAGE_KEYS, label, source)
        region = t.get("region")
        if region is None:
            raise ConfigError(f"{source}: {label} has no region (add region = \"<name of a [[region]]>\")")
        if not isinstance(region, str) or region not in names:
            raise ConfigError(f"{source}: {label}: unknown region {region!r}; defined regions: "
                              f"{', '.join(sorted(names)) or '(none)'}")
        plane = t.get("plane")
        if not isinstance(plane, list) or len(plane) != 4:
            raise ConfigError(f"{source}: {label}: plane must be four numbers [a, b, c, d], got {plane!r}")
        a, b, c, d = (_number(v, f"{label}: plane", source) for v in plane)
        nn = math.sqrt(a * a + b * b + c * c)
        if nn < 1e-12:
            raise ConfigError(f"{source}: {label}: plane normal (a, b, c) is zero")
        if abs(nn - 1.0) > 1e-6:
            warnings.warn(f"{source}: {label}: plane normal had length {nn:.6g}; normalized "
                          "(d scaled by the same factor)", GageFileWarning, stacklevel=4)
        weight = _number(t.get("weight", 1.0), f"{label}: weight", source, minimum=0.0)
        slack_weight = _number(t.get("slack_weight", 10.0), f"{label}: slack_weight", source, minimum=0.0)
        gages.append(Gage(name, region, (a / nn, b / nn, c / nn, d / nn), weight, slack_weight))
    return gages


def _parse_alignment(doc: Mapping[str, Any], source: str, regions: tuple[Region, ...]) -> Optional[AlignmentSpec]:
    """[alignment]: the 3-2-1 datums (Eqs. 5.13-5.19), regions in the scanner frame."""
    names = {r.name for r in regions}
    al = doc.get("alignment")
    if al is not None:
        if not isinstance(al, Mapping):
            raise ConfigError(f"{source}: [alignment] must be a table")
        _unknown(al.keys(), _ALIGN_KEYS, "[alignment]", source)
        for key in ("primary", "secondary", "tertiary"):
            if key not in al:
                raise ConfigError(f"{source}: [alignment] needs '{key}' (a list of region names); "
                                  "a 3-2-1 frame takes primary, secondary and tertiary datums")
        lists = []
        for key in ("primary", "secondary", "tertiary"):
            lst = _names(al[key], f"[alignment] {key}", source)
            for n in lst:
                if n not in names:
                    raise ConfigError(f"{source}: [alignment] {key}: unknown region {n!r}")
                frame = next(r.frame for r in regions if r.name == n)
                if frame != "scanner":
                    raise ConfigError(f"{source}: [alignment] {key}: region {n!r} must have frame = \"scanner\" "
                                      "(datums are found before the part frame exists)")
            lists.append(lst)
        return AlignmentSpec(*lists)
    return None
