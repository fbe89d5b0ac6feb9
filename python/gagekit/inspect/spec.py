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
from ..schema import validate_document
from ..schema.part import (  # the vocabulary of the drawing lives in its schema
    CHARACTERISTICS,
    FORM,
    MAX_SECTIONS,  # noqa: F401  (the bound of 'sections', read from here by callers)
    ORIENTATION,
    RANK_ORDER,
    RUNOUT,
    SHAPES,
    SIZE_MODIFIERS,
    SIZES,
    NominalTable,
)

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

#: Features of size (ISO 14405-1): a size callout applies to them; ``material`` needs one.
FEATURES_OF_SIZE = ("cylinder", "circle", "sphere", "cone", "slot", "tab")
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
MIN_POINTS = {"surface": 1, "plane": 3, "line": 2, "circle": 3, "sphere": 4, "cylinder": 5, "cone": 6, "slot": 6, "tab": 6}


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
# The schema (gagekit.schema.part, ``gagekit schema part``) checks every key's type, range
# and choice and refuses unknown keys; what follows are the rules between keys, in one place.


def _nonzero(v: Optional[list], where: str, key: str) -> Optional[tuple[float, float, float]]:
    if v is None:
        return None
    if math.hypot(*v) == 0.0:
        raise ConfigError(f"{where}: '{key}' has zero length; give a direction")
    return (float(v[0]), float(v[1]), float(v[2]))


def _region(v: Any, regions: Mapping[str, Box], where: str, name: str) -> Box:
    if isinstance(v, str):
        if v not in regions:
            raise ConfigError(f"{where}: 'region' = {v!r} names no [[region]] table")
        return regions[v]
    try:
        return Box(v.center, v.size, v.rotation, name=name if v.name is None else v.name)
    except ConfigError as exc:
        raise ConfigError(f"{where}: 'region': {exc}") from None


def part_spec_from_dict(doc: Mapping[str, Any], source: str = "part") -> PartSpec:
    """Validate a parsed PART.toml document (see the module docstring)."""
    from ..cloud.regions import regions_from_tables

    f = validate_document("part", doc, source)
    part = f.part
    regions = {b.name: b for b in regions_from_tables(doc.get("region", []), source)}
    features: dict[str, Feature] = {}
    for k, ft in enumerate(f.feature):
        name, shape, given = ft.name, ft.shape, ft.model_fields_set
        where = f"{source}: [[feature]] #{k + 1} ('{name}')"
        if name in features:
            raise ConfigError(f"{where}: 'name' = '{name}' is used by another feature")
        faces: tuple = ()
        if ft.faces is not None:
            if part.cad is None:
                raise ConfigError(f"{where}: 'faces' needs the CAD model: [part] cad = \"MODEL.step\"")
            faces = tuple(ft.faces) if isinstance(ft.faces, list) else (ft.faces,)
        if ft.region is None and not faces:
            raise ConfigError(f"{where}: 'region' is missing" + (" (or 'faces' of the [part] cad model)" if part.cad else ""))
        if shape == "surface" and not faces:
            raise ConfigError(f"{where}: a surface feature needs 'faces' (STEP ids or names of the [part] cad model)")
        region = _region(ft.region, regions, where, name) if ft.region is not None else None
        if shape in ("slot", "tab") and ft.direction is None:
            raise ConfigError(f"{where}: 'direction' is missing; a {shape} needs the direction across its width "
                              "(roughly normal to its two faces)")
        if ft.outward is not None and shape not in ("plane", "line"):
            raise ConfigError(f"{where}: 'outward' applies to planes and lines, not to a {shape}")
        if ft.outward is None and shape == "plane":
            raise ConfigError(f"{where}: 'outward' is missing; a plane needs the direction from the material into the air")
        if ft.kind is not None and shape not in ("cylinder", "circle", "sphere", "cone"):
            raise ConfigError(f"{where}: 'kind' applies to cylinders, circles, spheres and cones, not to a {shape}")
        if ft.direction is not None and shape not in ("cylinder", "cone", "line", "circle", "slot", "tab"):
            raise ConfigError(f"{where}: 'direction' applies to cylinders, cones, circles, lines, slots and tabs, "
                              f"not to a {shape}")
        features[name] = Feature(name, shape, region, _nonzero(ft.outward, where, "outward"), ft.kind,
                                 _nonzero(ft.direction, where, "direction"), ft.axis or part.axis,
                                 ft.sections or part.sections, ft.datum_fit or part.datum_fit, str(ft.qif_id),
                                 faces=faces, band=ft.band if "band" in given else part.band)

    datums: dict[str, DatumRef] = {}
    used: dict[str, str] = {}
    for letter, v in f.datums.items():
        where = f"{source}: [datums] {letter}"
        if not letter or not letter.replace("-", "").isalnum():
            raise ConfigError(f"{where}: a datum letter must be letters or digits")
        fname, angle = (v, 90.0) if isinstance(v, str) else (v.feature, v.angle)
        if fname not in features:
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
        datums[letter] = DatumRef(letter, fname, angle)

    tols = [_callout(t, k, f"{source}: [[tolerance]] #{k + 1} ({t.characteristic} of '{t.feature}')", features, datums,
                     part.standard) for k, t in enumerate(f.tolerance)]
    cad = part.cad
    if cad is not None:
        from pathlib import Path

        base = Path(source).parent if source != "part" else Path(".")
        cad = str(base / cad)
    qif = None if f.qif is None else {k: str(getattr(f.qif, k)) for k in f.qif.model_fields_set}
    return PartSpec(part.name, features, datums, tuple(tols), source, qif, cad=cad, standard=part.standard)


def _callout(t: Any, k: int, where: str, features: Mapping[str, Feature], datums: Mapping[str, DatumRef],
             standard: str) -> Tolerance:
    """One [[tolerance]] table: the rules between its keys, the feature and the datums."""
    given, fname, char = t.model_fields_set, t.feature, t.characteristic
    if char not in SIZES and t.tolerance is None:
        raise ConfigError(f"{where}: 'tolerance' is missing")
    if fname not in features:
        raise ConfigError(f"{where}: 'feature' = {fname!r} is not a [[feature]]")
    shape = features[fname].shape
    if shape not in APPLIES_TO[char]:
        raise ConfigError(f"{where}: 'characteristic' = {char!r} does not apply to a {shape}; "
                          f"it applies to: {', '.join(APPLIES_TO[char])}")
    raw_d, dmat = _datum_modifiers([t.datums] if isinstance(t.datums, str) else t.datums, datums, features, where)
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
    ids = {"qif_id": str(t.qif_id), "qpid": str(t.qpid)}
    if char in SIZES:
        return replace(_size_callout(t, k, fname, char, features, tuple(raw_d), dmat, standard, where), **ids)
    if t.material is not None and (char not in ORIENTATION + ("position", "straightness") or shape not in FEATURES_OF_SIZE):
        raise ConfigError(f"{where}: 'material' applies to position, orientation and straightness callouts of a "
                          f"feature of size ({', '.join(FEATURES_OF_SIZE)}), not to {char} of a {shape}")
    for key in ("upper", "lower", "fit", "modifier", "angles", "envelope", "to"):
        if key in given:
            raise ConfigError(f"{where}: '{key}' applies to size, distance and angle callouts, not to {char}")
    if any(dmat) and char not in ORIENTATION + ("position",):
        raise ConfigError(f"{where}: 'datums': a datum at MMB / LMB applies to position and orientation callouts")
    tol = t.tolerance
    if tol < 0 or (tol == 0 and t.material is None):
        raise ConfigError(f"{where}: 'tolerance' must be positive (0 only with material = \"MMC\" / \"LMC\"), got {tol!r}")
    angle = None
    if char == "angularity":
        if t.angle is None:
            raise ConfigError(f"{where}: 'angle' (the basic angle in degrees) is missing")
        angle = t.angle
        if not 0.0 <= angle <= 90.0:
            raise ConfigError(f"{where}: 'angle' must be in [0, 90] degrees, got {angle}")
    elif t.angle is not None:
        raise ConfigError(f"{where}: 'angle' applies to angularity only" +
                          ("; a cone's basic half angle is 'half_angle'" if char == "conicity" else ""))
    if t.half_angle is not None:  # conicity: the zone's cones at the basic half angle (degrees)
        if char != "conicity":
            raise ConfigError(f"{where}: 'half_angle' applies to conicity only")
        angle = t.half_angle
    nom = t.nominal
    if nom is not None and not isinstance(nom, NominalTable):
        raise ConfigError(f"{where}: 'nominal' must be a table {{ point, direction }}")
    npoint = None if nom is None or nom.point is None else tuple(nom.point)
    ndir = None if nom is None else _nonzero(nom.direction, where, "nominal.direction")
    if t.offset is not None and not (char in ("profile", "profile-line") and shape == "surface"):
        raise ConfigError(f"{where}: 'offset' (ISO 1101 UZ) applies to the profile of a surface or a line only")
    line_dir, spacing = None, None
    if char == "profile-line":
        if t.direction is None:
            raise ConfigError(f"{where}: 'direction' is missing: the normal of the section planes (CAD axes)")
        line_dir = _nonzero(t.direction, where, "direction")
        if t.spacing is not None:
            if t.sections is not None:
                raise ConfigError(f"{where}: give 'sections' (a count) or 'spacing' (mm), not both")
            spacing = t.spacing
            if not spacing > 0:
                raise ConfigError(f"{where}: 'spacing' must be a positive number of mm, got {spacing}")
    else:
        for key in ("direction", "spacing"):
            if key in given:
                raise ConfigError(f"{where}: '{key}' applies to profile-line (the section planes) only")
    if shape == "surface":
        if npoint is not None or ndir is not None:
            raise ConfigError(f"{where}: a surface's nominal is its CAD faces; drop 'nominal'")
    elif char in ("position", "profile") and npoint is None:
        raise ConfigError(f"{where}: 'nominal' needs a 'point' (the basic location in the datum frame)")
    if char in ("position", "profile") and shape in ("plane", "cylinder", "cone") and ndir is None:
        raise ConfigError(f"{where}: 'nominal' needs a 'direction' (the basic {'normal' if shape == 'plane' else 'axis'} in the datum frame)")
    return Tolerance(fname, char, float(tol), tuple(raw_d), npoint, ndir, angle, t.name, t.sections, k, **ids,
                     offset=t.offset or 0.0, material=t.material, datum_material=dmat, **_form_filter(t, char, where),
                     direction=line_dir, spacing=spacing)


#: ISO 12181-1 reference circles of a filtered roundness callout
ROUNDNESS_REFERENCES = ("MZCI", "LSCI", "MCCI", "MICI")


def _form_filter(t: Any, char: str, where: str) -> dict:
    """``filter = { upr = 50 }`` (``type = "gaussian"`` implied; ``{ type = "none" }``
    unfiltered) and ``reference = "MZCI"`` of a roundness callout (ISO 12181-2 / ISO 16610-21)."""
    if t.filter is None and t.reference is None:
        return {}
    if char != "roundness":
        raise ConfigError(f"{where}: 'filter' and 'reference' apply to roundness callouts (ISO 12181), not to {char}")
    out: dict = {"form_filter": "none", "filter_upr": None, "reference": None}
    flt = t.filter
    if flt is not None:
        if flt.type == "gaussian":
            if flt.upr is None:
                raise ConfigError(f"{where}: 'filter' needs 'upr', the cut-off in undulations per revolution (15, 50, 150, 500, 1500)")
            out["filter_upr"] = flt.upr
        elif flt.upr is not None:
            raise ConfigError(f"{where}: 'filter.upr' with type = \"none\"")
        out["form_filter"] = flt.type
    if t.reference is not None:
        out["reference"] = _choice(t.reference.upper(), ROUNDNESS_REFERENCES, where, "reference")
    return out


def _choice(v: str, choices: tuple[str, ...], where: str, key: str) -> str:
    if v not in choices:
        raise ConfigError(f"{where}: '{key}' = {v!r} is unknown; choose one of {', '.join(choices)}")
    return v


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


def _size_callout(t: Any, k: int, fname: str, char: str, features: Mapping[str, Feature], datums: tuple,
                  dmat: tuple, standard: str, where: str) -> Tolerance:
    """A size (ISO 14405-1), distance or angle (ISO 14405-2, ASME Y14.5) callout."""
    from .iso286 import fit_deviations

    given = t.model_fields_set
    if datums:
        raise ConfigError(f"{where}: 'datums': a {char} takes no datums")
    for key in ("material", "angle", "offset"):
        if key in given:
            raise ConfigError(f"{where}: '{key}' does not apply to a {char} callout")
    if t.nominal is None:
        raise ConfigError(f"{where}: 'nominal' (the nominal {'angle in degrees' if char == 'angle' else 'size in mm'}) is missing")
    if not isinstance(t.nominal, float):
        raise ConfigError(f"{where}: 'nominal' must be a finite number, got {t.nominal.model_dump(exclude_unset=True)!r}")
    nominal = t.nominal
    if char == "size" and nominal <= 0:
        raise ConfigError(f"{where}: 'nominal' must be a positive size, got {nominal!r}")
    fit = None
    if t.fit is not None:
        if char != "size":
            raise ConfigError(f"{where}: 'fit' (ISO 286) applies to sizes only")
        if given & {"upper", "lower", "tolerance"}:
            raise ConfigError(f"{where}: give either 'fit' or 'upper' and 'lower', not both")
        fit = t.fit
        upper, lower = fit_deviations(fit, nominal, f"{where}: 'fit'")
    elif given & {"upper", "lower"}:
        if t.tolerance is not None:
            raise ConfigError(f"{where}: give either 'tolerance' (+-) or 'upper' and 'lower', not both")
        for key in ("upper", "lower"):
            if key not in given:
                raise ConfigError(f"{where}: '{key}' is missing (the {key} limit deviation)")
        upper, lower = t.upper, t.lower
    elif t.tolerance is not None:
        if t.tolerance <= 0:
            raise ConfigError(f"{where}: 'tolerance' must be positive, got {t.tolerance!r}")
        upper, lower = t.tolerance, -t.tolerance
    else:
        raise ConfigError(f"{where}: the limits are missing: give 'upper' and 'lower' (deviations), "
                          + ("'fit' (e.g. \"H7\") " if char == "size" else "") + "or 'tolerance' (+-)")
    if upper < lower:
        raise ConfigError(f"{where}: 'upper' ({upper:g}) is below 'lower' ({lower:g})")
    shape = features[fname].shape
    modifier = angles = envelope = to = None
    if char == "size":
        modifier = _choice((t.modifier or "LP").upper(), SIZE_MODIFIERS + RANK_ORDER, where, "modifier")
        angles = t.angles
        # ASME Y14.5 Rule #1: the envelope applies unless stated otherwise
        envelope = t.envelope if t.envelope is not None else standard == "asme"
        if envelope and shape in ("cylinder", "circle", "sphere", "cone") and features[fname].kind is None:
            raise ConfigError(f"{where}: the envelope requirement needs the feature's kind = \"hole\" or \"shaft\" "
                              f"(its MMC size is the upper or the lower limit); set it on '{fname}'")
    else:
        for key in ("modifier", "angles", "envelope"):
            if key in given:
                raise ConfigError(f"{where}: '{key}' applies to sizes, not to a {char}")
        to = t.to
        if to is None:
            raise ConfigError(f"{where}: 'to' (the second feature of the {char}) is missing")
        if to not in features:
            raise ConfigError(f"{where}: 'to' = {to!r} is not a [[feature]]")
        if to == fname:
            raise ConfigError(f"{where}: 'to' names the feature itself")
        other = features[to].shape
        if other not in APPLIES_TO[char]:
            raise ConfigError(f"{where}: 'to': a {char} to a {other} is not defined; it applies to: {', '.join(APPLIES_TO[char])}")
    return Tolerance(fname, char, upper - lower, (), None, None, None, t.name, t.sections, k,
                     size_nominal=nominal, upper=upper, lower=lower, fit=fit, modifier=modifier, angles=angles,
                     envelope=envelope, to=to, datum_material=dmat)


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


def load_part_spec(path: Any) -> PartSpec:
    """Read and validate a PART.toml file."""
    from .._util import load_toml

    try:
        return part_spec_from_dict(load_toml(path), str(path))
    except GagekitError:
        raise
    except (TypeError, ValueError) as exc:  # pragma: no cover - defensive
        raise ConfigError(f"{path}: {exc}") from None

