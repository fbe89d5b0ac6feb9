"""PART.toml: the part's features, datums and tolerance callouts (the drawing).

All lengths are millimetres in the scan's frame, angles degrees. Layout::

    [part]                       # optional
    name = "bracket"
    datum_fit = "chebyshev"      # or "least-squares" (ISO 5459 default: chebyshev)
    axis = "least-squares"       # derived axes: or "median-line" (ISO 12180)
    sections = 10                # sections of a median line / circular run-out / roundness

    [[feature]]
    name = "A"
    shape = "plane"              # plane | cylinder | circle | sphere | line | cone
    region = { center = [50, 30, 0], size = [100, 60, 2], rotation = [0, 0, 0] }
    outward = [0, 0, -1]         # planes (and optionally lines): from the material into the air
    kind = "hole"                # cylinder / circle / sphere / cone: "hole" or "shaft"
    direction = [0, 0, 1]        # cylinder / cone / line / circle: roughly along the axis (its sign)

    [datums]
    A = "A"                      # letter -> feature name
    B = { feature = "side", angle = 90.0 }   # basic angle to the primary plane (secondary planes, axes)

    [[tolerance]]
    feature = "bore"
    characteristic = "position"
    tolerance = 0.1
    datums = ["A", "B", "C"]
    nominal = { point = [50, 30, 0], direction = [0, 0, 1] }   # in the datum frame
    angle = 45.0                 # angularity: basic angle between feature and datum
    half_angle = 30.0            # conicity: basic half apex angle of the cone (default: free)

    [[tolerance]]                # profile of a line (ISO 1101 Sec. 18.6) of a surface by CAD faces
    feature = "top"
    characteristic = "profile-line"
    tolerance = 0.05
    direction = [0, 1, 0]        # the normal of the parallel section planes
    sections = 5                 # or spacing = 6.4 (mm)

    [[tolerance]]                # a size (ISO 14405-1), :mod:`.sizes`
    feature = "bore"
    characteristic = "size"
    nominal = 20.0
    upper = 0.021                # limit deviations (mm), or fit = "H7" (ISO 286)
    lower = 0.0
    modifier = "LP"              # LP LS GG GX GN CC CA CV, or SX SN SA SM SD SR
    envelope = true              # ISO (E) / ASME Rule #1 ([part] standard = "asme")

    [[tolerance]]                # distance / angle between two features
    feature = "top"
    characteristic = "distance"
    to = "A"
    nominal = 40.0
    upper = 0.1
    lower = -0.1

    position, orientation and straightness callouts of a feature of size take
    ``material = "MMC" | "LMC"`` (ISO 2692, bonus) and datums at MMB / LMB as
    ``datums = ["A", "B(M)"]`` (datum shift).

Every mistake raises :class:`~gagekit.errors.ConfigError` naming the file, the table and
the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Mapping, Optional

import numpy as np

from .._rotation import rotation_from_vector, rotation_vector
from ..cloud.regions import Box
from ..errors import ConfigError, GagekitError

__all__ = [
    "SHAPES",
    "CHARACTERISTICS",
    "APPLIES_TO",
    "Feature",
    "DatumRef",
    "Tolerance",
    "PartSpec",
    "load_part_spec",
    "part_spec_from_dict",
]

SHAPES = ("plane", "cylinder", "circle", "sphere", "line", "cone", "surface", "slot", "tab")
FORM = ("flatness", "straightness", "roundness", "cylindricity", "sphericity", "conicity")
ORIENTATION = ("parallelism", "perpendicularity", "angularity")
LOCATION = ("position", "coaxiality", "profile", "profile-line")
RUNOUT = ("circular-runout", "total-runout")
SIZES = ("size", "distance", "angle")
CHARACTERISTICS = FORM + ORIENTATION + LOCATION + RUNOUT + SIZES
#: Features of size (ISO 14405-1): a size callout applies to them; ``material`` needs one.
FEATURES_OF_SIZE = ("cylinder", "circle", "sphere", "cone", "slot", "tab")
#: Size modifiers (ISO 14405-1 Table 1) and rank-order statistics (applied to the two-point sizes).
SIZE_MODIFIERS = ("LP", "LS", "GG", "GX", "GN", "CC", "CA", "CV")
RANK_ORDER = ("SX", "SN", "SA", "SM", "SD", "SR")
STANDARDS = ("iso", "asme")
MATERIAL = ("MMC", "LMC")

#: Which feature shapes each characteristic applies to.
APPLIES_TO: dict[str, tuple[str, ...]] = {
    "flatness": ("plane",),
    "straightness": ("line", "cylinder"),
    "roundness": ("circle", "cylinder", "cone"),
    "cylindricity": ("cylinder",),
    "sphericity": ("sphere",),
    "conicity": ("cone",),
    "parallelism": ("plane", "cylinder", "cone"),
    "perpendicularity": ("plane", "cylinder", "cone"),
    "angularity": ("plane", "cylinder", "cone"),
    "position": ("plane", "cylinder", "cone", "circle", "sphere"),
    "coaxiality": ("cylinder", "cone", "circle", "sphere"),
    "profile": ("plane", "surface"),
    "profile-line": ("surface",),
    "circular-runout": ("cylinder", "cone", "circle", "plane"),
    "total-runout": ("cylinder", "cone", "plane"),
    "size": FEATURES_OF_SIZE,
    "distance": ("plane", "cylinder", "cone", "circle", "sphere", "slot", "tab"),
    "angle": ("plane", "cylinder", "cone", "circle", "line", "slot", "tab"),
}

#: Shapes that can serve as a datum feature (plane -> a plane; the others -> an axis).
DATUM_SHAPES = ("plane", "cylinder", "cone", "circle", "sphere")
AXIAL = ("cylinder", "cone", "circle")
AXIS_METHODS = ("least-squares", "median-line")
DATUM_FITS = ("chebyshev", "least-squares")
MIN_POINTS = {"surface": 1, "plane": 3, "line": 2, "circle": 3, "sphere": 4, "cylinder": 5, "cone": 6, "slot": 6, "tab": 6}

_FEATURE_KEYS = {"name", "shape", "region", "outward", "kind", "direction", "axis", "sections", "datum_fit", "qif_id",
                 "faces", "band"}
_TOL_KEYS = {"feature", "characteristic", "tolerance", "datums", "nominal", "angle", "name", "sections", "qif_id", "qpid",
             "offset", "upper", "lower", "fit", "modifier", "angles", "envelope", "to", "material", "filter", "reference",
             "half_angle", "direction", "spacing"}
_PART_KEYS = {"name", "datum_fit", "axis", "sections", "cad", "band", "standard"}
_TOP_KEYS = {"part", "feature", "datums", "tolerance", "region", "qif"}
#: the [qif] table of a drawing imported from a QIF model (``gagekit qif import``)
_QIF_KEYS = {"model", "qpid", "units"}


@dataclass(frozen=True)
class Feature:
    """A toleranced or datum feature: the points of the scan inside ``region``, or (with
    ``[part] cad``) those nearest to the CAD ``faces`` (STEP ids or names) within ``band``
    mm of them (None: 3 RMS of their deviations, :mod:`gagekit.cad.features`)."""

    name: str
    shape: str
    region: Optional[Box]
    outward: Optional[tuple[float, float, float]] = None
    kind: Optional[str] = None
    direction: Optional[tuple[float, float, float]] = None
    axis: str = "least-squares"
    sections: int = 10
    datum_fit: str = "chebyshev"
    qif_id: str = ""  # the QIF feature nominal this feature came from (gagekit qif import)
    faces: tuple = ()
    band: Optional[float] = None

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name, "shape": self.shape}
        if self.region is not None:
            d["region"] = self.region.to_dict()
        if self.faces:
            d["faces"] = list(self.faces)
            if self.band is not None:
                d["band"] = self.band
        for key in ("outward", "kind", "direction"):
            v = getattr(self, key)
            if v is not None:
                d[key] = list(v) if isinstance(v, tuple) else v
        d.update(axis=self.axis, sections=self.sections, datum_fit=self.datum_fit)
        return d


@dataclass(frozen=True)
class DatumRef:
    """A datum letter: its feature and (for a secondary plane or axis) the basic angle to
    the primary plane (90: perpendicular)."""

    letter: str
    feature: str
    angle: float = 90.0


@dataclass(frozen=True)
class Tolerance:
    """One callout of the drawing's feature control frames."""

    feature: str
    characteristic: str
    tolerance: float
    datums: tuple[str, ...] = ()
    nominal_point: Optional[tuple[float, float, float]] = None
    nominal_direction: Optional[tuple[float, float, float]] = None
    angle: Optional[float] = None
    name: str = ""
    sections: Optional[int] = None
    index: int = 0
    qif_id: str = ""  # the QIF characteristic nominal this callout came from (gagekit qif import)
    qpid: str = ""  # the QPId of the QIF model document
    offset: float = 0.0
    # sizes, distances, angles (ISO 14405): nominal size and limit deviations (mm; degrees for angles)
    size_nominal: Optional[float] = None
    upper: Optional[float] = None
    lower: Optional[float] = None
    fit: Optional[str] = None
    modifier: Optional[str] = None
    angles: Optional[int] = None
    envelope: Optional[bool] = None
    to: Optional[str] = None
    # material conditions (ISO 2692): "MMC" / "LMC" of the toleranced feature; per datum "" / "M" / "L"
    material: Optional[str] = None
    datum_material: tuple[str, ...] = ()
    # filtered roundness (ISO 12181, ISO 16610-21): "gaussian" / "none" when asked, its UPR, the reference circle
    form_filter: Optional[str] = None
    filter_upr: Optional[float] = None
    reference: Optional[str] = None
    # line profile (ISO 1101 Sec. 18.6): the normal of its parallel section planes, their spacing (mm)
    direction: Optional[tuple[float, float, float]] = None
    spacing: Optional[float] = None

    @property
    def upper_limit(self) -> Optional[float]:
        return None if self.size_nominal is None or self.upper is None else self.size_nominal + self.upper

    @property
    def lower_limit(self) -> Optional[float]:
        return None if self.size_nominal is None or self.lower is None else self.size_nominal + self.lower

    @property
    def label(self) -> str:
        return self.name or f"{self.characteristic} of {self.feature}"


@dataclass(frozen=True)
class PartSpec:
    """A parsed PART.toml (see the module docstring)."""

    name: str
    features: dict[str, Feature]
    datums: dict[str, DatumRef]
    tolerances: tuple[Tolerance, ...]
    source: str = "part"
    qif: Optional[dict] = None  # [qif]: model, qpid, units of an imported QIF model
    cad: Optional[str] = None
    standard: str = "iso"  # [part] standard: "iso" or "asme" (ASME Rule #1 on sizes)

    def moved(self, rotation: Any, translation: Any) -> "PartSpec":
        """The same drawing for the part moved by the rigid motion p -> R p + t: regions,
        ``outward`` and ``direction`` move with it (nominals are in the datum frame and
        do not change)."""
        R = np.asarray(rotation, dtype=float).reshape(3, 3)
        t = np.asarray(translation, dtype=float).reshape(3)
        feats = {}
        for name, f in self.features.items():
            if f.region is None:  # located by CAD faces: the part and its model move together
                feats[name] = f
                continue
            box_R = rotation_from_vector(f.region.rotation)
            new_R = R @ box_R
            feats[name] = Feature(
                f.name, f.shape,
                Box(tuple(R @ np.array(f.region.center) + t), f.region.size, tuple(rotation_vector(new_R)), name=f.region.name),
                None if f.outward is None else tuple(R @ np.array(f.outward)),
                f.kind,
                None if f.direction is None else tuple(R @ np.array(f.direction)),
                f.axis, f.sections, f.datum_fit, f.qif_id,
            )
        return PartSpec(self.name, feats, self.datums, self.tolerances, self.source, self.qif, self.cad, self.standard)


# -- parsing ---------------------------------------------------------------------------


def _vec3(v: Any, where: str, key: str, nonzero: bool = False) -> tuple[float, float, float]:
    try:
        vals = tuple(float(x) for x in v)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: '{key}' must be three numbers, got {v!r}") from None
    if len(vals) != 3 or not all(math.isfinite(x) for x in vals):
        raise ConfigError(f"{where}: '{key}' must be three finite numbers, got {v!r}")
    if nonzero and math.hypot(*vals) == 0.0:
        raise ConfigError(f"{where}: '{key}' has zero length; give a direction")
    return vals  # type: ignore[return-value]


def _number(v: Any, where: str, key: str, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise ConfigError(f"{where}: '{key}' must be a finite number, got {v!r}")
    if positive and float(v) <= 0:
        raise ConfigError(f"{where}: '{key}' must be positive, got {v!r}")
    return float(v)


#: The most sections a median line, run-out or banded measurement may take: each section
#: needs points of its own, and a larger count only loops over empty slices.
MAX_SECTIONS = 10_000


def _sections(v: Any, where: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ConfigError(f"{where}: 'sections' must be a positive integer, got {v!r}")
    if v > MAX_SECTIONS:
        raise ConfigError(f"{where}: 'sections' = {v} is more than {MAX_SECTIONS} (each section needs points of its own)")
    return int(v)


def _choice(v: Any, choices: tuple[str, ...], where: str, key: str) -> str:
    if v not in choices:
        raise ConfigError(f"{where}: '{key}' = {v!r} is unknown; choose one of {', '.join(choices)}")
    return v


def _unknown(t: Mapping, allowed: set, where: str) -> None:
    extra = sorted(set(t) - allowed)
    if extra:
        raise ConfigError(f"{where}: unknown key(s) {', '.join(repr(k) for k in extra)}; allowed: {', '.join(sorted(allowed))}")


def _region(v: Any, regions: Mapping[str, Box], where: str, name: str) -> Box:
    if isinstance(v, str):
        if v not in regions:
            raise ConfigError(f"{where}: 'region' = {v!r} names no [[region]] table")
        return regions[v]
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}: 'region' must be a table {{ center, size, rotation }} or the name of a [[region]]")
    _unknown(v, {"center", "size", "rotation", "name"}, f"{where}, region")
    for key in ("center", "size"):
        if key not in v:
            raise ConfigError(f"{where}: 'region' has no '{key}'")
    try:
        return Box(v["center"], v["size"], v.get("rotation", (0.0, 0.0, 0.0)), name=str(v.get("name", name)))
    except ConfigError as exc:
        raise ConfigError(f"{where}: 'region': {exc}") from None


def part_spec_from_dict(doc: Mapping[str, Any], source: str = "part") -> PartSpec:
    """Validate a parsed PART.toml document (see the module docstring)."""
    from ..cloud.regions import regions_from_tables

    if not isinstance(doc, Mapping):
        raise ConfigError(f"{source}: expected a TOML document")
    _unknown(doc, _TOP_KEYS, source)
    part = doc.get("part", {})
    if not isinstance(part, Mapping):
        raise ConfigError(f"{source}: [part] must be a table")
    _unknown(part, _PART_KEYS, f"{source}: [part]")
    pname = str(part.get("name", "part"))
    dfit = _choice(part.get("datum_fit", "chebyshev"), DATUM_FITS, f"{source}: [part]", "datum_fit")
    daxis = _choice(part.get("axis", "least-squares"), AXIS_METHODS, f"{source}: [part]", "axis")
    dsec = _sections(part.get("sections", 10), f"{source}: [part]")
    standard = _choice(part.get("standard", "iso"), STANDARDS, f"{source}: [part]", "standard")
    regions = {b.name: b for b in regions_from_tables(doc.get("region", []), source)}

    raw_features = doc.get("feature", [])
    if not isinstance(raw_features, list) or not raw_features:
        raise ConfigError(f"{source}: no [[feature]] tables; describe at least one feature")
    features: dict[str, Feature] = {}
    for k, t in enumerate(raw_features):
        if not isinstance(t, Mapping):
            raise ConfigError(f"{source}: [[feature]] #{k + 1} must be a table")
        name = t.get("name")
        where = f"{source}: [[feature]] #{k + 1}" + (f" ('{name}')" if isinstance(name, str) and name else "")
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{where}: 'name' is missing or empty")
        if name in features:
            raise ConfigError(f"{where}: 'name' = '{name}' is used by another feature")
        _unknown(t, _FEATURE_KEYS, where)
        if "shape" not in t:
            raise ConfigError(f"{where}: 'shape' is missing; choose one of {', '.join(SHAPES)}")
        shape = _choice(t["shape"], SHAPES, where, "shape")
        faces: tuple = ()
        if "faces" in t:
            faces = _faces(t["faces"], where, part.get("cad"))
        if "region" not in t and not faces:
            raise ConfigError(f"{where}: 'region' is missing" + (" (or 'faces' of the [part] cad model)" if "cad" in part else ""))
        if shape == "surface" and not faces:
            raise ConfigError(f"{where}: a surface feature needs 'faces' (STEP ids or names of the [part] cad model)")
        region = _region(t["region"], regions, where, name) if "region" in t else None
        band = _number(t.get("band", part.get("band")), where, "band", positive=True) if ("band" in t or "band" in part) else None
        outward = None
        if shape in ("slot", "tab") and "direction" not in t:
            raise ConfigError(f"{where}: 'direction' is missing; a {shape} needs the direction across its width "
                              "(roughly normal to its two faces)")
        if "outward" in t:
            if shape not in ("plane", "line"):
                raise ConfigError(f"{where}: 'outward' applies to planes and lines, not to a {shape}")
            outward = _vec3(t["outward"], where, "outward", nonzero=True)
        elif shape == "plane":
            raise ConfigError(f"{where}: 'outward' is missing; a plane needs the direction from the material into the air")
        kind = t.get("kind")
        if kind is not None:
            if shape not in ("cylinder", "circle", "sphere", "cone"):
                raise ConfigError(f"{where}: 'kind' applies to cylinders, circles, spheres and cones, not to a {shape}")
            kind = _choice(kind, ("hole", "shaft"), where, "kind")
        direction = None
        if "direction" in t:
            if shape not in ("cylinder", "cone", "line", "circle", "slot", "tab"):
                raise ConfigError(f"{where}: 'direction' applies to cylinders, cones, circles, lines, slots and tabs, "
                                  f"not to a {shape}")
            direction = _vec3(t["direction"], where, "direction", nonzero=True)
        axis = _choice(t.get("axis", daxis), AXIS_METHODS, where, "axis")
        sections = _sections(t.get("sections", dsec), where)
        fit = _choice(t.get("datum_fit", dfit), DATUM_FITS, where, "datum_fit")
        features[name] = Feature(name, shape, region, outward, kind, direction, axis, sections, fit,
                                 _qif_ref(t.get("qif_id", ""), where, "qif_id"), faces=faces, band=band)

    raw_datums = doc.get("datums", {})
    if not isinstance(raw_datums, Mapping):
        raise ConfigError(f"{source}: [datums] must be a table of letter = feature name")
    datums: dict[str, DatumRef] = {}
    used: dict[str, str] = {}
    for letter, v in raw_datums.items():
        where = f"{source}: [datums] {letter}"
        if not letter or not str(letter).replace("-", "").isalnum():
            raise ConfigError(f"{where}: a datum letter must be letters or digits")
        angle = 90.0
        if isinstance(v, Mapping):
            _unknown(v, {"feature", "angle"}, where)
            if "feature" not in v:
                raise ConfigError(f"{where}: 'feature' is missing")
            fname = v["feature"]
            if "angle" in v:
                angle = _number(v["angle"], where, "angle")
                if not 0.0 < angle <= 90.0:
                    raise ConfigError(f"{where}: 'angle' must be in (0, 90] degrees, got {angle}")
        else:
            fname = v
        if not isinstance(fname, str) or fname not in features:
            raise ConfigError(f"{where}: names feature {fname!r}, which is not a [[feature]]")
        shape = features[fname].shape
        if shape not in DATUM_SHAPES:
            raise ConfigError(f"{where}: a {shape} cannot be a datum feature; use a plane, cylinder, cone, circle or sphere")
        if shape in ("cylinder", "circle", "cone", "sphere") and features[fname].kind is None:
            raise ConfigError(f"{where}: datum feature '{fname}' needs kind = \"hole\" or \"shaft\" (its datum is the "
                              "maximum inscribed or minimum circumscribed feature, ISO 5459)")
        if fname in used:
            raise ConfigError(f"{where}: feature '{fname}' is already datum {used[fname]}; a datum letter is used twice for one feature")
        used[fname] = letter
        datums[str(letter)] = DatumRef(str(letter), fname, angle)

    raw_tols = doc.get("tolerance", [])
    if not isinstance(raw_tols, list) or not raw_tols:
        raise ConfigError(f"{source}: no [[tolerance]] tables; list the drawing's callouts")
    tols: list[Tolerance] = []
    for k, t in enumerate(raw_tols):
        if not isinstance(t, Mapping):
            raise ConfigError(f"{source}: [[tolerance]] #{k + 1} must be a table")
        where = f"{source}: [[tolerance]] #{k + 1}"
        if isinstance(t.get("feature"), str):
            where += f" ({t.get('characteristic', '?')} of '{t['feature']}')"
        _unknown(t, _TOL_KEYS, where)
        for key in ("feature", "characteristic") + (() if t.get("characteristic") in SIZES else ("tolerance",)):
            if key not in t:
                raise ConfigError(f"{where}: '{key}' is missing")
        fname = t["feature"]
        if not isinstance(fname, str) or fname not in features:
            raise ConfigError(f"{where}: 'feature' = {fname!r} is not a [[feature]]")
        char = _choice(t["characteristic"], CHARACTERISTICS, where, "characteristic")
        shape = features[fname].shape
        if shape not in APPLIES_TO[char]:
            raise ConfigError(f"{where}: 'characteristic' = {char!r} does not apply to a {shape}; "
                              f"it applies to: {', '.join(APPLIES_TO[char])}")
        raw_d = t.get("datums", [])
        if isinstance(raw_d, str):
            raw_d = [raw_d]
        if not isinstance(raw_d, list) or not all(isinstance(x, str) for x in raw_d):
            raise ConfigError(f"{where}: 'datums' must be a list of datum letters")
        raw_d, dmat = _datum_modifiers(raw_d, datums, features, where)
        if len(raw_d) > 3:
            raise ConfigError(f"{where}: 'datums' lists {len(raw_d)} datums; at most three (primary, secondary, tertiary)")
        for j, letter in enumerate(raw_d):
            if letter not in datums:
                raise ConfigError(f"{where}: 'datums' names '{letter}', which is not in [datums]")
            if letter in raw_d[:j]:
                raise ConfigError(f"{where}: 'datums' uses datum '{letter}' twice")
            if datums[letter].feature == fname:
                raise ConfigError(f"{where}: 'datums' names '{letter}', the toleranced feature itself")
        _check_datums(char, raw_d, datums, features, where)
        if char in SIZES:
            ids = {key: _qif_ref(t.get(key, ""), where, key) for key in ("qif_id", "qpid")}
            tols.append(replace(_size_callout(t, k, fname, char, features, tuple(raw_d), dmat, standard, where), **ids))
            continue
        material = None
        if "material" in t:
            material = _choice(t["material"], MATERIAL, where, "material")
            if char not in ORIENTATION + ("position", "straightness") or shape not in FEATURES_OF_SIZE:
                raise ConfigError(f"{where}: 'material' applies to position, orientation and straightness callouts of a "
                                  f"feature of size ({', '.join(FEATURES_OF_SIZE)}), not to {char} of a {shape}")
        for key in ("upper", "lower", "fit", "modifier", "angles", "envelope", "to"):
            if key in t:
                raise ConfigError(f"{where}: '{key}' applies to size, distance and angle callouts, not to {char}")
        if any(dmat) and char not in ORIENTATION + ("position",):
            raise ConfigError(f"{where}: 'datums': a datum at MMB / LMB applies to position and orientation callouts")
        tol = _number(t["tolerance"], where, "tolerance")
        if tol < 0 or (tol == 0 and material is None):
            raise ConfigError(f"{where}: 'tolerance' must be positive (0 only with material = \"MMC\" / \"LMC\"), got {tol!r}")
        angle = None
        if char == "angularity":
            if "angle" not in t:
                raise ConfigError(f"{where}: 'angle' (the basic angle in degrees) is missing")
            angle = _number(t["angle"], where, "angle")
            if not 0.0 <= angle <= 90.0:
                raise ConfigError(f"{where}: 'angle' must be in [0, 90] degrees, got {angle}")
        elif "angle" in t:
            raise ConfigError(f"{where}: 'angle' applies to angularity only" +
                              ("; a cone's basic half angle is 'half_angle'" if char == "conicity" else ""))
        if "half_angle" in t:  # conicity: the zone's cones at the basic half angle (degrees)
            if char != "conicity":
                raise ConfigError(f"{where}: 'half_angle' applies to conicity only")
            angle = _number(t["half_angle"], where, "half_angle")
            if not 0.0 < angle < 90.0:
                raise ConfigError(f"{where}: 'half_angle' must lie strictly between 0 and 90 degrees, got {angle}")
        npoint = ndir = None
        if "nominal" in t:
            nom = t["nominal"]
            if not isinstance(nom, Mapping):
                raise ConfigError(f"{where}: 'nominal' must be a table {{ point, direction }}")
            _unknown(nom, {"point", "direction"}, f"{where}, nominal")
            if "point" in nom:
                npoint = _vec3(nom["point"], where, "nominal.point")
            if "direction" in nom:
                ndir = _vec3(nom["direction"], where, "nominal.direction", nonzero=True)
        offset = 0.0
        if "offset" in t:
            if not (char in ("profile", "profile-line") and shape == "surface"):
                raise ConfigError(f"{where}: 'offset' (ISO 1101 UZ) applies to the profile of a surface or a line only")
            offset = _number(t["offset"], where, "offset")
        line_dir, spacing = None, None
        if char == "profile-line":
            if "direction" not in t:
                raise ConfigError(f"{where}: 'direction' is missing: the normal of the section planes (CAD axes)")
            line_dir = _vec3(t["direction"], where, "direction", nonzero=True)
            if "spacing" in t:
                if "sections" in t:
                    raise ConfigError(f"{where}: give 'sections' (a count) or 'spacing' (mm), not both")
                spacing = _number(t["spacing"], where, "spacing")
                if not spacing > 0:
                    raise ConfigError(f"{where}: 'spacing' must be a positive number of mm, got {spacing}")
        else:
            for key in ("direction", "spacing"):
                if key in t:
                    raise ConfigError(f"{where}: '{key}' applies to profile-line (the section planes) only")
        if shape == "surface":
            if npoint is not None or ndir is not None:
                raise ConfigError(f"{where}: a surface's nominal is its CAD faces; drop 'nominal'")
        elif char in ("position", "profile") and npoint is None:
            raise ConfigError(f"{where}: 'nominal' needs a 'point' (the basic location in the datum frame)")
        if char in ("position", "profile") and shape in ("plane", "cylinder", "cone") and ndir is None:
            raise ConfigError(f"{where}: 'nominal' needs a 'direction' (the basic {'normal' if shape == 'plane' else 'axis'} in the datum frame)")
        sections = _sections(t["sections"], where) if "sections" in t else None
        ids = {key: _qif_ref(t.get(key, ""), where, key) for key in ("qif_id", "qpid")}
        tols.append(Tolerance(fname, char, tol, tuple(raw_d), npoint, ndir, angle, str(t.get("name", "")), sections, k, **ids,
                              offset=offset, material=material, datum_material=dmat, **_form_filter(t, char, where),
                              direction=line_dir, spacing=spacing))
    cad = part.get("cad")
    if cad is not None:
        if not isinstance(cad, str) or not cad:
            raise ConfigError(f"{source}: [part] 'cad' must be the path of the CAD model (relative to the drawing)")
        from pathlib import Path

        base = Path(source).parent if source != "part" else Path(".")
        cad = str(base / cad)
    return PartSpec(pname, features, datums, tuple(tols), source, _qif_table(doc.get("qif"), source), cad=cad,
                    standard=standard)


#: ISO 12181-1 reference circles of a filtered roundness callout
ROUNDNESS_REFERENCES = ("MZCI", "LSCI", "MCCI", "MICI")


def _form_filter(t: Mapping, char: str, where: str) -> dict:
    """``filter = { upr = 50 }`` (``type = "gaussian"`` implied; ``{ type = "none" }``
    unfiltered) and ``reference = "MZCI"`` of a roundness callout (ISO 12181-2 / ISO 16610-21)."""
    if "filter" not in t and "reference" not in t:
        return {}
    if char != "roundness":
        raise ConfigError(f"{where}: 'filter' and 'reference' apply to roundness callouts (ISO 12181), not to {char}")
    out: dict = {"form_filter": "none", "filter_upr": None, "reference": None}
    if "filter" in t:
        f = t["filter"]
        if not isinstance(f, Mapping):
            raise ConfigError(f"{where}: 'filter' must be a table {{ upr = 50 }} or {{ type = \"none\" }}")
        _unknown(f, {"type", "upr"}, f"{where}, filter")
        kind = _choice(f.get("type", "gaussian"), ("gaussian", "none"), where, "filter.type")
        if kind == "gaussian":
            if "upr" not in f:
                raise ConfigError(f"{where}: 'filter' needs 'upr', the cut-off in undulations per revolution (15, 50, 150, 500, 1500)")
            out["filter_upr"] = _number(f["upr"], where, "filter.upr", positive=True)
        elif "upr" in f:
            raise ConfigError(f"{where}: 'filter.upr' with type = \"none\"")
        out["form_filter"] = kind
    if "reference" in t:
        out["reference"] = _choice(str(t["reference"]).upper(), ROUNDNESS_REFERENCES, where, "reference")
    return out


def _datum_modifiers(raw: list, datums: Mapping[str, DatumRef], features: Mapping[str, Feature],
                     where: str) -> tuple[list, tuple[str, ...]]:
    """Split ``"B(M)"`` / ``"B(L)"`` into the letter and its material boundary (MMB / LMB,
    ISO 2692 / ASME Y14.5 Sec. 7); the datum feature must be a feature of size."""
    letters, mods = [], []
    for x in raw:
        x = x.strip()
        mod = ""
        if x.endswith(")") and "(" in x:
            x, m = x[:-1].split("(", 1)
            x, m = x.strip(), m.strip().upper()
            if m not in ("M", "L"):
                raise ConfigError(f"{where}: 'datums': '{x}({m})' -- a datum's material boundary is (M) or (L)")
            mod = m
            if x in datums and features[datums[x].feature].shape not in FEATURES_OF_SIZE:
                raise ConfigError(f"{where}: 'datums': datum '{x}' is a {features[datums[x].feature].shape}, not a feature "
                                  "of size; (M) / (L) apply to datum features of size")
        letters.append(x)
        mods.append(mod)
    return letters, tuple(mods)


def _size_callout(t: Mapping, k: int, fname: str, char: str, features: Mapping[str, Feature], datums: tuple,
                  dmat: tuple, standard: str, where: str) -> Tolerance:
    """A size (ISO 14405-1), distance or angle (ISO 14405-2, ASME Y14.5) callout."""
    from .iso286 import fit_deviations

    if datums:
        raise ConfigError(f"{where}: 'datums': a {char} takes no datums")
    for key in ("material", "angle", "offset"):
        if key in t:
            raise ConfigError(f"{where}: '{key}' does not apply to a {char} callout")
    if "nominal" not in t:
        raise ConfigError(f"{where}: 'nominal' (the nominal {'angle in degrees' if char == 'angle' else 'size in mm'}) is missing")
    nominal = _number(t["nominal"], where, "nominal")
    if char == "size" and nominal <= 0:
        raise ConfigError(f"{where}: 'nominal' must be a positive size, got {nominal!r}")
    fit = None
    if "fit" in t:
        if char != "size":
            raise ConfigError(f"{where}: 'fit' (ISO 286) applies to sizes only")
        if "upper" in t or "lower" in t or "tolerance" in t:
            raise ConfigError(f"{where}: give either 'fit' or 'upper' and 'lower', not both")
        fit = str(t["fit"])
        upper, lower = fit_deviations(fit, nominal, f"{where}: 'fit'")
    elif "upper" in t or "lower" in t:
        if "tolerance" in t:
            raise ConfigError(f"{where}: give either 'tolerance' (+-) or 'upper' and 'lower', not both")
        for key in ("upper", "lower"):
            if key not in t:
                raise ConfigError(f"{where}: '{key}' is missing (the {key} limit deviation)")
        upper, lower = _number(t["upper"], where, "upper"), _number(t["lower"], where, "lower")
    elif "tolerance" in t:
        half = _number(t["tolerance"], where, "tolerance", positive=True)
        upper, lower = half, -half
    else:
        raise ConfigError(f"{where}: the limits are missing: give 'upper' and 'lower' (deviations), "
                          + ("'fit' (e.g. \"H7\") " if char == "size" else "") + "or 'tolerance' (+-)")
    if upper < lower:
        raise ConfigError(f"{where}: 'upper' ({upper:g}) is below 'lower' ({lower:g})")
    shape = features[fname].shape
    modifier = angles = envelope = to = None
    if char == "size":
        modifier = str(t.get("modifier", "LP")).upper()
        _choice(modifier, SIZE_MODIFIERS + RANK_ORDER, where, "modifier")
        if "angles" in t:
            angles = t["angles"]
            if isinstance(angles, bool) or not isinstance(angles, int) or angles < 1:
                raise ConfigError(f"{where}: 'angles' must be a positive integer, got {angles!r}")
        if "envelope" in t:
            if not isinstance(t["envelope"], bool):
                raise ConfigError(f"{where}: 'envelope' must be true or false, got {t['envelope']!r}")
            envelope = bool(t["envelope"])
        else:
            envelope = standard == "asme"  # ASME Y14.5 Rule #1: the envelope applies unless stated otherwise
        if envelope and shape in ("cylinder", "circle", "sphere", "cone") and features[fname].kind is None:
            raise ConfigError(f"{where}: the envelope requirement needs the feature's kind = \"hole\" or \"shaft\" "
                              f"(its MMC size is the upper or the lower limit); set it on '{fname}'")
    else:
        for key in ("modifier", "angles", "envelope"):
            if key in t:
                raise ConfigError(f"{where}: '{key}' applies to sizes, not to a {char}")
        if "to" not in t:
            raise ConfigError(f"{where}: 'to' (the second feature of the {char}) is missing")
        to = t["to"]
        if not isinstance(to, str) or to not in features:
            raise ConfigError(f"{where}: 'to' = {to!r} is not a [[feature]]")
        if to == fname:
            raise ConfigError(f"{where}: 'to' names the feature itself")
        other = features[to].shape
        if other not in APPLIES_TO[char]:
            raise ConfigError(f"{where}: 'to': a {char} to a {other} is not defined; it applies to: {', '.join(APPLIES_TO[char])}")
    sections = _sections(t["sections"], where) if "sections" in t else None
    return Tolerance(fname, char, upper - lower, (), None, None, None, str(t.get("name", "")), sections, k,
                     size_nominal=nominal, upper=upper, lower=lower, fit=fit, modifier=modifier, angles=angles,
                     envelope=envelope, to=to, datum_material=dmat)


def _qif_ref(v: Any, where: str, key: str) -> str:
    if isinstance(v, bool) or not isinstance(v, (str, int)):
        raise ConfigError(f"{where}: '{key}' must be a string (a QIF id or QPId), got {v!r}")
    return str(v)


def _qif_table(t: Any, source: str) -> Optional[dict]:
    if t is None:
        return None
    if not isinstance(t, Mapping):
        raise ConfigError(f"{source}: [qif] must be a table {{ model, qpid, units }}")
    _unknown(t, _QIF_KEYS, f"{source}: [qif]")
    return {k: _qif_ref(v, f"{source}: [qif]", k) for k, v in t.items()}


def _check_datums(char: str, letters: list, datums: Mapping[str, DatumRef], features: Mapping[str, Feature], where: str) -> None:
    n = len(letters)
    if char in SIZES:
        return
    if char in FORM:
        if n:
            raise ConfigError(f"{where}: 'datums': {char} is a form tolerance and takes no datums")
        return
    if char in ORIENTATION + ("position",) and n == 0:
        raise ConfigError(f"{where}: 'datums' is missing; {char} needs at least a primary datum")
    if char in ORIENTATION and features[datums[letters[0]].feature].shape == "sphere":
        raise ConfigError(f"{where}: 'datums': {char} needs a primary datum plane or axis; datum '{letters[0]}' is a "
                          "sphere (a datum point fixes no orientation)")
    if char in ("coaxiality",) + RUNOUT:
        if n == 0:
            raise ConfigError(f"{where}: 'datums' is missing; {char} needs a datum axis")
        first = features[datums[letters[0]].feature].shape
        if first not in AXIAL:
            raise ConfigError(f"{where}: 'datums': {char} needs a datum axis (a cylinder, cone or circle); "
                              f"datum '{letters[0]}' is a {first}")
        if n > 1:
            raise ConfigError(f"{where}: 'datums': {char} takes one datum axis, got {n} datums")


def _faces(v: Any, where: str, cad: Any) -> tuple:
    """The ``faces`` of a feature: STEP ids (integers or "#12") or names, at least one."""
    if cad is None:
        raise ConfigError(f"{where}: 'faces' needs the CAD model: [part] cad = \"MODEL.step\"")
    if isinstance(v, (str, int)) and not isinstance(v, bool):
        v = [v]
    if not isinstance(v, list) or not v or not all(isinstance(x, (str, int)) and not isinstance(x, bool) for x in v):
        raise ConfigError(f"{where}: 'faces' must be a list of STEP face ids or names, got {v!r}")
    return tuple(v)


def load_part_spec(path: Any) -> PartSpec:
    """Read and validate a PART.toml file."""
    from .._util import load_toml

    try:
        return part_spec_from_dict(load_toml(path), str(path))
    except GagekitError:
        raise
    except (TypeError, ValueError) as exc:  # pragma: no cover - defensive
        raise ConfigError(f"{path}: {exc}") from None

