"""Read a QIF 3.0 model-based definition (ANSI/DMSC QIF 3.0, ISO 23952:2020): the file
units, the feature nominals with their definitions, the datum definitions, the datum
reference frames and the characteristics (definitions, nominals, items).

Every length comes out in millimetres and every angle in degrees, whatever the file's
``FileUnits`` (and each value's own ``linearUnit`` / ``angularUnit``) say. Bad input is
one :class:`~gagekit.errors.FileFormatError`: not XML, not a QIF 3 document, a unit
gagekit does not know, a reference to an id the file does not hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ..errors import FileFormatError
from . import _xml as X

__all__ = ["QifModel", "FeatureNominal", "DatumDef", "DatumRefFrame", "Characteristic", "read_model"]

#: millimetres per linear unit, by the names QIF files use (UnitName)
LINEAR_MM = {"mm": 1.0, "millimeter": 1.0, "millimetre": 1.0, "cm": 10.0, "m": 1000.0, "meter": 1000.0, "metre": 1000.0,
             "um": 1e-3, "micrometer": 1e-3, "micron": 1e-3, "in": 25.4, "inch": 25.4, "ft": 304.8, "foot": 304.8,
             "feet": 304.8, "mil": 0.0254, "uin": 2.54e-5, "km": 1e6}
#: degrees per angular unit
ANGULAR_DEG = {"degree": 1.0, "deg": 1.0, "degrees": 1.0, "radian": 180.0 / math.pi, "rad": 180.0 / math.pi,
               "radians": 180.0 / math.pi, "revolution": 360.0, "grad": 0.9, "gon": 0.9}


@dataclass
class Units:
    """The file's units: ``linear`` mm per primary linear unit, ``pmi_angle`` degrees per
    PMI angular unit (tolerances, basic angles), ``angle`` degrees per geometric angular
    unit; named other units for values carrying a ``linearUnit`` / ``angularUnit``."""

    linear: float
    linear_name: str
    pmi_angle: float
    angle: float
    named_linear: dict = field(default_factory=dict)
    named_angular: dict = field(default_factory=dict)
    pmi_linear: float = 0.0  # mm per PMI linear unit (tolerances, targets); 0: the linear unit

    def length(self, el: Any, where: str, pmi: bool = False) -> float:
        v = X.number(el, where)
        unit = el.get("linearUnit")
        if unit is None:
            return v * ((self.pmi_linear or self.linear) if pmi else self.linear)
        if unit not in self.named_linear:
            raise FileFormatError(f"{where}: unknown linear unit {unit!r} (not in FileUnits)")
        return v * self.named_linear[unit]

    def pmi_angle_of(self, el: Any, where: str) -> float:
        v = X.number(el, where)
        unit = el.get("angularUnit")
        if unit is None:
            return v * self.pmi_angle
        if unit not in self.named_angular:
            raise FileFormatError(f"{where}: unknown angular unit {unit!r} (not in FileUnits)")
        return v * self.named_angular[unit]


@dataclass
class FeatureNominal:
    """A feature nominal: ``kind`` is the QIF type without ``FeatureNominal`` (Plane,
    Cylinder, OppositeParallelPlanes...); ``geometry`` holds its nominal in mm (points,
    unit vectors, ``diameter``, ``length``, ``polyline`` as an (n, 3) array...);
    ``internal`` is True for a hole, False for a shaft, None when the type has no side."""

    id: str
    kind: str
    name: str
    geometry: dict
    internal: Optional[bool] = None
    definition_id: str = ""


@dataclass
class DatumDef:
    id: str
    label: str
    feature_ids: list


@dataclass
class DatumRefFrame:
    """``datums``: (label, material modifier) in precedence order; ``problem`` says why
    gagekit cannot use the frame (a compound datum, datum targets...), else ''."""

    id: str
    datums: list
    problem: str = ""


@dataclass
class Characteristic:
    """One characteristic nominal with its definition (and items, when the file has
    them). Lengths mm, angles degrees. ``kind``: the QIF type without
    ``CharacteristicNominal`` (Flatness, Position, Diameter...)."""

    id: str
    kind: str
    name: str
    definition_id: str
    feature_ids: list
    designator: str = ""
    tolerance: Optional[float] = None
    upper: Optional[float] = None
    lower: Optional[float] = None
    limits_absolute: bool = False
    target: Optional[float] = None
    drf_id: Optional[str] = None
    material: str = "NONE"
    zone: str = ""
    angle: Optional[float] = None
    item_ids: list = field(default_factory=list)
    extras: list = field(default_factory=list)
    angular: bool = False
    basic: bool = False


@dataclass
class QifModel:
    """A parsed QIF model-based definition."""

    path: str
    qpid: str
    version: str
    units: Units
    features: dict
    datums: dict
    drfs: dict
    characteristics: list
    id_max: int
    tree: Any = None

    @property
    def characteristic_count(self) -> int:
        return len(self.characteristics)


# -- units -----------------------------------------------------------------------------


def _unit_factor(u: Any, table: dict, si: str, scale: float, where: str) -> tuple[str, float]:
    name = (X.text(u, "UnitName") or "").strip()
    if name.lower() in table:
        return name, table[name.lower()]
    conv = X.child(u, "UnitConversion")
    si_name = (X.text(u, "SIUnitName") or "").lower()
    if conv is not None and X.child(conv, "Factor") is not None and si_name == si:
        factor = X.number(X.child(conv, "Factor"), f"{where} {name} UnitConversion/Factor")
        offset = X.text(conv, "Offset")
        if factor > 0 and not (offset and float(offset) != 0.0):
            return name, factor * scale
    raise FileFormatError(f"{where}: unknown unit {name!r} (SI unit {si_name or '?'}; no usable conversion factor)")


def _units(root: Any, path: str) -> Units:
    fu = X.child(root, "FileUnits")
    where = f"{path}: FileUnits"
    if fu is None:
        raise FileFormatError(f"{path}: the QIF file has no FileUnits: its length unit is unknown")
    prim = X.child(fu, "PrimaryUnits")
    lin = X.child(prim, "LinearUnit") if prim is not None else None
    if lin is None:
        raise FileFormatError(f"{where}: no PrimaryUnits/LinearUnit: the length unit is unknown")
    lname, lmm = _unit_factor(lin, LINEAR_MM, "meter", 1000.0, where)
    ang = X.child(prim, "AngularUnit")
    pmi = X.child(prim, "PMIAngularUnit")
    # QIF: geometric angles in radians unless PrimaryUnits gives an AngularUnit; PMI angles
    # (tolerances, basic angles) in the PMIAngularUnit, else the AngularUnit
    angle = _unit_factor(ang, ANGULAR_DEG, "radian", 180.0 / math.pi, where)[1] if ang is not None else 180.0 / math.pi
    pmi_angle = _unit_factor(pmi, ANGULAR_DEG, "radian", 180.0 / math.pi, where)[1] if pmi is not None else angle
    named_l = {lname: lmm}
    pmi_lin = X.child(prim, "PMILinearUnit")
    pmi_mm = 0.0
    if pmi_lin is not None:
        pname, pmi_mm = _unit_factor(pmi_lin, LINEAR_MM, "meter", 1000.0, where)
        named_l[pname] = pmi_mm
    named_a: dict = {}
    for u in ([ang] if ang is not None else []) + ([pmi] if pmi is not None else []):
        n, f = _unit_factor(u, ANGULAR_DEG, "radian", 180.0 / math.pi, where)
        named_a[n] = f
    other = X.child(fu, "OtherUnits")
    for u in (list(other) if other is not None else []):
        kind = X.local(u)
        try:
            if kind == "LinearUnit":
                n, f = _unit_factor(u, LINEAR_MM, "meter", 1000.0, where)
                named_l[n] = f
            elif kind in ("AngularUnit", "PMIAngularUnit"):
                n, f = _unit_factor(u, ANGULAR_DEG, "radian", 180.0 / math.pi, where)
                named_a[n] = f
        except FileFormatError:
            continue  # an exotic other unit only matters if a value names it (checked there)
    return Units(lmm, lname, pmi_angle, angle, named_l, named_a, pmi_mm)


# -- features --------------------------------------------------------------------------


def _vec(el: Any, name: str, where: str, scale: float = 1.0) -> Optional[np.ndarray]:
    s = X.text(el, name)
    if s is None:
        return None
    return np.array(X.floats(s, 3, f"{where}/{name}")) * scale


def _unit_vec(el: Any, name: str, where: str) -> Optional[np.ndarray]:
    v = _vec(el, name, where)
    if v is None:
        return None
    n = float(np.linalg.norm(v))
    if n == 0.0:
        raise FileFormatError(f"{where}/{name}: zero vector")
    return v / n


def _length(units: Units, el: Any, name: str, where: str) -> Optional[float]:
    c = X.child(el, name) if el is not None else None
    return None if c is None else units.length(c, f"{where}/{name}")


def _nominal(el: Any, what: str, defs: dict, path: str) -> tuple[str, str, str, str, Any]:
    """(kind, id, where, definition id, definition element) of a feature or characteristic
    nominal (``what``: "Feature" / "Characteristic"); a definition id the file does not
    hold is a FileFormatError."""
    kind = X.local(el)[: -len(f"{what}Nominal")]
    i = el.get("id")
    where = f"{path}: {X.local(el)} id={i}"
    def_id = X.text(el, f"{what}DefinitionId") or ""
    d = defs.get(def_id)
    if d is None:
        raise FileFormatError(f"{where}: {what}DefinitionId {def_id!r} names no {what.lower()} definition in the file")
    return kind, i, where, def_id, d


def _feature(el: Any, defs: dict, units: Units, path: str) -> FeatureNominal:
    kind, fid, where, def_id, d = _nominal(el, "Feature", defs, path)
    s = units.linear
    g: dict = {}
    internal = None
    side = X.text(d, "InternalExternal")
    if side is not None:
        internal = side.upper() == "INTERNAL"
    if kind == "Plane":
        g["location"] = _vec(el, "Location", where, s)
        g["normal"] = _unit_vec(el, "Normal", where)
        pl = X.child(el, "PolyLine")
        if pl is not None and pl.text:
            vals = pl.text.split()
            try:
                arr = np.array([float(v) for v in vals]).reshape(-1, 3) * s
            except ValueError:
                raise FileFormatError(f"{where}/PolyLine: expected triples of numbers") from None
            g["polyline"] = arr
    elif kind in ("Cylinder", "Cone", "CylindricalSegment"):
        ax = X.child(el, "Axis")
        if ax is None:
            raise FileFormatError(f"{where}: no Axis")
        g["point"] = _vec(ax, "AxisPoint", where, s)
        g["direction"] = _unit_vec(ax, "Direction", where)
        g["diameter"] = _length(units, d, "Diameter", where)
        g["length"] = _length(units, d, "Length", where)
        if kind == "Cone":
            ha = X.child(d, "HalfAngle")
            g["half_angle"] = X.number(ha, where) * units.angle if ha is not None else None
            g["large_end"] = _length(units, d, "LargeEndDistance", where)
            g["small_end"] = _length(units, d, "SmallEndDistance", where)
    elif kind in ("Circle", "CircularArc"):
        g["center"] = _vec(el, "Location", where, s)
        g["normal"] = _unit_vec(el, "Normal", where)
        g["diameter"] = _length(units, d, "Diameter", where) or (2 * (_length(units, d, "Radius", where) or 0.0)) or None
    elif kind in ("Sphere", "SphericalSegment"):
        g["center"] = _vec(el, "Location", where, s)
        g["diameter"] = _length(units, d, "Diameter", where)
    elif kind == "Line":
        g["location"] = _vec(el, "Location", where, s)
        g["direction"] = _unit_vec(el, "Direction", where)
        g["length"] = _length(units, el, "Length", where)
        g["normal"] = _unit_vec(el, "Normal", where)
    elif kind in ("OppositeParallelPlanes", "OppositeAngledPlanes"):
        cp = X.child(el, "CenterPlane")
        if cp is not None:
            g["point"] = _vec(cp, "Point", where, s)
            g["normal"] = _unit_vec(cp, "Normal", where)
        g["length_vector"] = _unit_vec(el, "LengthVector", where)
        g["width"] = _length(units, d, "Width", where)
        g["length"] = _length(units, d, "Length", where)
        g["depth"] = _length(units, d, "Depth", where)
    elif kind == "Point":
        g["location"] = _vec(el, "Location", where, s)
    return FeatureNominal(fid, kind, X.text(el, "Name") or "", g, internal, def_id)


# -- datums ----------------------------------------------------------------------------

_MODIFIER = {"NONE": "", "MAXIMUM": "M", "LEAST": "L", "MMB": "M", "LMB": "L", "MAXIMUM_MATERIAL_BOUNDARY": "M",
             "LEAST_MATERIAL_BOUNDARY": "L", "REGARDLESS": ""}


def _drf(el: Any, datums: dict, path: str) -> DatumRefFrame:
    fid = el.get("id")
    where = f"{path}: DatumReferenceFrame id={fid}"
    out: list = []
    problem = ""
    order = {"PRIMARY": 0, "SECONDARY": 1, "TERTIARY": 2}
    entries = []
    dlist = X.child(el, "Datums")
    for k, d in enumerate(X.children(dlist, "Datum") if dlist is not None else []):
        prec = X.text(X.child(d, "Precedence"), "PrecedenceEnum") if X.child(d, "Precedence") is not None else None
        simple = X.child(d, "SimpleDatum")
        if simple is None:
            kinds = [X.local(c) for c in d if X.local(c) != "Precedence"]
            problem = f"a {kinds[0] if kinds else 'compound'} (common datum or datum targets) in the datum reference frame"
            continue
        did = X.text(simple, "DatumDefinitionId")
        if did is None:
            problem = "a datum given by datum targets or another document (no DatumDefinitionId)"
            continue
        if did not in datums:
            raise FileFormatError(f"{where}: DatumDefinitionId {did} names no DatumDefinition in the file")
        mod = (X.text(simple, "MaterialModifier") or "NONE").upper()
        if X.child(simple, "DatumTranslation") is not None or X.child(simple, "PrecedenceWithDegreesOfFreedom") is not None:
            problem = "a datum with translation or customised degrees of freedom"
        entries.append((order.get(prec or "", k), datums[did].label, _MODIFIER.get(mod, mod)))
    for _, label, mod in sorted(entries, key=lambda e: e[0]):
        out.append((label, mod))
    return DatumRefFrame(fid, out, problem)


# -- characteristics -------------------------------------------------------------------

#: elements of a definition or nominal gagekit reads; any other child is recorded (a
#: modifier gagekit does not evaluate is never silently dropped)
_KNOWN = {"Attributes", "StatisticalCharacteristic", "ToleranceValue", "DatumReferenceFrameId", "MaterialCondition",
          "ZoneShape", "Tolerance", "Extent", "CharacteristicDefinitionId", "FeatureNominalIds", "Name",
          "CharacteristicDesignator", "TargetValue", "FeatureNominalPairs", "Angle", "Description", "FormalStandardId",
          "UUID", "SizeCharacteristicDefinitionId", "ReportPeriod", "DimensionCount", "EntityInternalIds", "DimensionType",
          "NonTolerance"}


def _char(nom: Any, defs: dict, units: Units, features: dict, drfs: dict, path: str) -> Characteristic:
    kind, cid, where, def_id, d = _nominal(nom, "Characteristic", defs, path)
    fids = X.ids(X.child(nom, "FeatureNominalIds"))
    for f in fids:
        if f not in features:
            raise FileFormatError(f"{where}: FeatureNominalIds names {f}, which is no feature nominal in the file")
    dz = X.child(nom, "CharacteristicDesignator")
    c = Characteristic(cid, kind, X.text(nom, "Name") or "", def_id, fids, X.text(dz, "Designator") or "" if dz is not None else "")
    angular = kind in ("Angle", "AngleBetween", "AngleFrom", "AngularCoordinate", "ConicalTaper")
    c.angular = angular

    def value(el: Any, w: str) -> float:
        return units.pmi_angle_of(el, w) if angular else units.length(el, w, pmi=True)

    tv = X.child(d, "ToleranceValue")
    if tv is not None:
        c.tolerance = value(tv, f"{where}: ToleranceValue")
    tol = X.child(d, "Tolerance")
    if tol is not None:
        mx, mn = X.child(tol, "MaxValue"), X.child(tol, "MinValue")
        c.upper = value(mx, f"{where}: Tolerance/MaxValue") if mx is not None else None
        c.lower = value(mn, f"{where}: Tolerance/MinValue") if mn is not None else None
        c.limits_absolute = (X.text(tol, "DefinedAsLimit") or "false").lower() == "true"
    tgt = X.child(nom, "TargetValue")
    if tgt is not None:
        c.target = value(tgt, f"{where}: TargetValue")
    ang = X.child(nom, "Angle")
    if ang is not None:
        c.angle = units.pmi_angle_of(ang, f"{where}: Angle")
    c.basic = (X.text(d, "DimensionType") or "").upper() == "BASIC_OR_TED" or X.child(d, "NonTolerance") is not None
    c.drf_id = X.text(d, "DatumReferenceFrameId")
    if c.drf_id is not None and c.drf_id not in drfs:
        raise FileFormatError(f"{where}: DatumReferenceFrameId {c.drf_id} names no DatumReferenceFrame in the file")
    c.material = (X.text(d, "MaterialCondition") or "NONE").upper()
    zs = X.child(d, "ZoneShape")
    if zs is not None and len(zs):
        c.zone = X.local(zs[0])
    ext = X.child(d, "Extent")
    extras = [X.local(e) for e in list(d) + list(nom) if X.local(e) not in _KNOWN]
    if ext is not None and (X.text(ext, "ExtentEnum") or "UNDEFINED") not in ("UNDEFINED",):
        extras.append(f"Extent {X.text(ext, 'ExtentEnum')}")
    c.extras = extras
    return c


# -- document --------------------------------------------------------------------------


def read_model(path: Any) -> QifModel:
    """Parse a QIF 3.0 document (``.qif``, or gzip-compressed) into a :class:`QifModel`."""
    tree = X.parse(path)
    root = tree.getroot()
    name = X.local(root)
    ns = root.tag[1:].split("}")[0] if root.tag.startswith("{") else ""
    if name != "QIFDocument":
        raise FileFormatError(f"{path}: not a QIF document (the root element is <{name}>, not <QIFDocument>)")
    version = root.get("versionQIF") or ""
    if ns == X.NS and not version:
        raise FileFormatError(f"{path}: the <QIFDocument> has no versionQIF attribute (QIF 3.0 requires it, "
                              f"e.g. versionQIF=\"3.0.0\")")
    if ns != X.NS or not version.startswith("3."):
        found = version or (ns.rsplit("/", 1)[-1] if ns else "no namespace")
        raise FileFormatError(f"{path}: QIF version {found} is not supported; gagekit reads QIF 3.0 "
                              f"(namespace {X.NS}, versionQIF 3.x)")
    units = _units(root, str(path))
    by_id: dict = {}
    for el in root.iter():
        i = el.get("id") if isinstance(el.tag, str) else None
        if i is not None:
            by_id.setdefault(i, el)
    feats_el = X.child(root, "Features")
    fdefs: dict = {}
    features: dict = {}
    if feats_el is not None:
        fd = X.child(feats_el, "FeatureDefinitions")
        for el in (list(fd) if fd is not None else []):
            fdefs[el.get("id")] = el
        fn = X.child(feats_el, "FeatureNominals")
        for el in (list(fn) if fn is not None else []):
            f = _feature(el, fdefs, units, str(path))
            features[f.id] = f
    datums: dict = {}
    dd = X.child(root, "DatumDefinitions")
    for el in (X.children(dd, "DatumDefinition") if dd is not None else []):
        label = X.text(el, "DatumLabel") or ""
        fids = X.ids(X.child(el, "FeatureNominalIds"))
        for f in fids:
            if f not in features:
                raise FileFormatError(f"{path}: DatumDefinition {label!r} id={el.get('id')} names feature nominal {f}, "
                                      "which is not in the file")
        datums[el.get("id")] = DatumDef(el.get("id"), label, fids)
    drfs: dict = {}
    dr = X.child(root, "DatumReferenceFrames")
    for el in (X.children(dr, "DatumReferenceFrame") if dr is not None else []):
        drfs[el.get("id")] = _drf(el, datums, str(path))
    chars: list = []
    ch = X.child(root, "Characteristics")
    if ch is not None:
        defs_el = X.child(ch, "CharacteristicDefinitions")
        cdefs = {el.get("id"): el for el in (list(defs_el) if defs_el is not None else [])}
        noms = X.child(ch, "CharacteristicNominals")
        for el in (list(noms) if noms is not None else []):
            chars.append(_char(el, cdefs, units, features, drfs, str(path)))
        items = X.child(ch, "CharacteristicItems")
        by_nom = {c.id: c for c in chars}
        for el in (list(items) if items is not None else []):
            nid = X.text(el, "CharacteristicNominalId")
            if nid not in by_nom:
                raise FileFormatError(f"{path}: {X.local(el)} id={el.get('id')}: CharacteristicNominalId {nid!r} names no "
                                      "characteristic nominal in the file")
            by_nom[nid].item_ids.append(el.get("id"))
    try:
        id_max = max([int(root.get("idMax") or 0)] + [int(i) for i in by_id if i.isdigit()])
    except ValueError:
        id_max = len(by_id)
    qpid = X.text(root, "QPId") or ""
    return QifModel(str(path), qpid, version, units, features, datums, drfs, chars, id_max, tree)
