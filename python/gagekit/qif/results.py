"""Inspection results as a QIF 3.0 document (``MeasurementsResults``), the file CMM and
statistics software read.

One document holds one ``MeasurementResults`` per scan (``inspect`` writes one,
``inspect batch`` one per inspected scan): the actual of every callout
(``...CharacteristicMeasurement``: ``Value`` = gagekit's ``measured``, ``Status`` PASS /
FAIL), the measured features (the least-squares fit of each feature: location,
direction, diameter, form), the datum reference frames as ``ActualTransforms`` (each
callout's position / orientation measurement names its frame), the scan file as an
``ExternalFileReference`` and the instrument as a ``MeasurementDevice`` in
``MeasurementResources``, ``Version`` and ``Header`` naming gagekit.

Two layouts:

- **The part came from a QIF model** (``[qif] model`` in PART.toml, ``gagekit qif
  import``): the document is the model itself (its ids unchanged) with a new QPId, an
  ``ExternalQIFReferences`` entry naming the model's QPId, ``FeatureItems`` and
  ``CharacteristicItems`` pointing at the model's feature and characteristic nominals,
  and the results. Values are written in the model's units.
- **Otherwise** a self-contained Plan + Results: datum definitions, datum reference
  frames, characteristic definitions, nominals and items made from PART.toml, then the
  results, in mm and degrees.

The transforms map scan coordinates to datum-frame coordinates (QIF: ``Rotation`` rows
x/y/z directions as columns of the matrix, ``Origin`` the translation); a left-handed
datum frame (possible in gagekit, see docs/inspection.md) has no QIF transform and is
left out.
"""

from __future__ import annotations

import copy
import datetime as _dt
import hashlib
import json
import math
import uuid
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from .. import __version__
from ..errors import ConfigError
from . import _xml as X

__all__ = ["write_inspection_results", "inspection_results_document", "write_gage_results", "gage_results_document",
           "QIF_TYPE"]

#: gagekit characteristic -> QIF characteristic type (self-contained documents)
QIF_TYPE = {
    "flatness": "Flatness", "straightness": "Straightness", "roundness": "Circularity", "cylindricity": "Cylindricity",
    "sphericity": "Sphericity", "parallelism": "Parallelism", "perpendicularity": "Perpendicularity",
    "angularity": "Angularity", "position": "Position", "coaxiality": "Coaxiality", "profile": "SurfaceProfile",
    "circular-runout": "CircularRunout", "total-runout": "TotalRunout", "size": "Diameter", "distance": "DistanceBetween",
    "angle": "AngleBetween", "conicity": "Conicity", "profile-line": "LineProfile",
}
_FORM = ("Flatness", "Straightness", "Circularity", "Cylindricity", "Sphericity", "Conicity")
_SHAPE_TYPE = {"plane": "Plane", "cylinder": "Cylinder", "circle": "Circle", "sphere": "Sphere", "line": "Line", "cone": "Cone"}
#: the children of QIFDocument, in the schema's order
_DOC_ORDER = ["QPId", "Attributes", "VersionHistory", "Version", "Header", "ValidationCounts", "ProductDataQuality",
              "ExternalQIFReferences", "StandardsDefinitions", "SoftwareDefinitions", "AlgorithmDefinitions",
              "PreInspectionTraceability", "FileUnits", "DatumDefinitions", "DatumTargetDefinitions", "Transforms",
              "CoordinateSystems", "DatumReferenceFrames", "MeasurementResources", "ThreadSpecifications", "Product",
              "Features", "FeatureZones", "Characteristics", "Plan", "Results", "Statistics",
              "ManufacturingProcessTraceabilities", "Rules", "UserDataXML", "Signature"]


class _Ids:
    def __init__(self, start: int) -> None:
        self.last = start

    def __call__(self) -> str:
        self.last += 1
        return str(self.last)


def _place(root: Any, el: Any) -> Any:
    """Insert ``el`` as a child of QIFDocument at its place in the schema's sequence
    (replacing an element of the same name)."""
    name = X.local(el)
    old = X.child(root, name)
    if old is not None:
        root.replace(old, el)
        return el
    rank = _DOC_ORDER.index(name)
    for k, c in enumerate(root):
        if X.local(c) in _DOC_ORDER and _DOC_ORDER.index(X.local(c)) > rank:
            root.insert(k, el)
            return el
    root.append(el)
    return el


def _new(name: str, text: Optional[str] = None, **attrs: Any) -> Any:
    el = X.etree().Element(X.Q + name, {k: str(v) for k, v in attrs.items() if v is not None}, nsmap={None: X.NS})
    if text is not None:
        el.text = text
    return el


def _num(v: float) -> str:
    return X.dec(v)


def _id_list(parent: Any, name: str, values: Sequence[str]) -> Any:
    el = X.sub(parent, name, n=len(values))
    for v in values:
        X.sub(el, "Id", str(v))
    return el


def _units_block(root: Any) -> None:
    fu = _new("FileUnits")
    pu = X.sub(fu, "PrimaryUnits")
    au = X.sub(pu, "AngularUnit")
    X.sub(au, "SIUnitName", "radian")
    X.sub(au, "UnitName", "degree")
    X.sub(X.sub(au, "UnitConversion"), "Factor", "0.017453292519943295")
    lu = X.sub(pu, "LinearUnit")
    X.sub(lu, "SIUnitName", "meter")
    X.sub(lu, "UnitName", "mm")
    X.sub(X.sub(lu, "UnitConversion"), "Factor", "0.001")
    _place(root, fu)


def _header(root: Any) -> None:
    v = _new("Version")
    X.sub(v, "TimeCreated", _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).strftime("%Y-%m-%dT%H:%M:%SZ"))
    _place(root, v)
    h = _new("Header")
    app = X.sub(h, "Application")
    X.sub(app, "Name", "gagekit")
    X.sub(app, "Organization", "gagekit")
    X.sub(h, "Description", f"GD&T inspection results of point clouds (gagekit {__version__})")
    _place(root, h)


def _status(parent: Any, ok: bool, kind: str = "Characteristic", decision: Optional[str] = None) -> None:
    """PASS / FAIL; with an ISO 14253-1 ``decision`` (a result with its uncertainty):
    conforming PASS, nonconforming FAIL, not-proven INDETERMINATE."""
    s = X.sub(parent, "Status" if kind == "Characteristic" else "InspectionStatus")
    status = "PASS" if ok else "FAIL"
    if decision is not None:
        status = {"conforming": "PASS", "nonconforming": "FAIL"}.get(decision, "INDETERMINATE")
    X.sub(s, f"{kind}StatusEnum", status)


#: the order of ISO 14253-1 decisions, best first (a group takes its worst member's)
_DECISIONS = ("conforming", "not-proven", "nonconforming")


def _worst(decisions: Sequence[Optional[str]]) -> Optional[str]:
    known = [d for d in decisions if d in _DECISIONS]
    return max(known, key=_DECISIONS.index) if known and len(known) == len(decisions) else None


def _uncertainty_attributes(el: Any, unc: Optional[Mapping[str, Any]], rule: Optional[str], scale: float) -> None:
    """A measurement's uncertainty as QIF attributes (its first child, ``Attributes`` of
    CharacteristicBaseType): ``U`` (expanded, 95 %), ``k``, ``coverage``, the coverage
    interval's ends, the ``decision_rule`` (ISO 14253-1) and the method (JCGM 101). The
    combined standard uncertainty and the bias go on ``Value`` itself
    (``combinedUncertainty``, ``meanError``: QIF's MeasuredDecimalType)."""
    if not unc:
        return
    a = X.sub(el, "Attributes")

    def attribute(kind: str, key: str, value: str) -> None:  # QIF's attribute "name" (sub's own argument is name)
        X.etree().SubElement(a, X.Q + kind, {"name": key, "value": value})

    for key, v in (("U", unc["U"] / scale), ("k", unc["k"]), ("coverage", unc["coverage"]),
                   ("interval_low", unc["interval"][0] / scale), ("interval_high", unc["interval"][1] / scale)):
        attribute("AttributeD1", key, X.dec(v))
    if rule:
        attribute("AttributeStr", "decision_rule", rule)
    attribute("AttributeStr", "uncertainty_method", str(unc.get("method", "")))
    a.set("n", str(len(a)))


def _value(el: Any, value: float, unc: Optional[Mapping[str, Any]], scale: float) -> None:
    """``Value`` with, for a result with its uncertainty, ``combinedUncertainty`` = u and
    ``meanError`` = |bias| (the Monte Carlo's; QIF wants both or neither)."""
    if unc:
        X.sub(el, "Value", _num(value), combinedUncertainty=X.dec(unc["u"] / scale),
              meanError=X.dec(abs(unc["bias"]) / scale))
    else:
        X.sub(el, "Value", _num(value))


# -- the plan part: definitions, nominals, items ----------------------------------------


def _characteristics(root: Any, ids: _Ids, designator: str, year: str, title: str) -> Any:
    """A new Characteristics element with its FormalStandardId: the ISO standard the
    characteristics follow, in StandardsDefinitions."""
    sd = _new("StandardsDefinitions", n=1)
    std = X.sub(sd, "Standard", id=ids())
    X.sub(X.sub(std, "Organization"), "StandardsOrganizationEnum", "ISO")
    X.sub(std, "Designator", designator)
    X.sub(std, "Year", year)
    X.sub(std, "Title", title)
    _place(root, sd)
    ch = _new("Characteristics")
    X.sub(ch, "FormalStandardId", std.get("id"))
    return ch


class _Plan:
    """What the results point at: per callout its characteristic item id and QIF type,
    per feature its feature item id (or None), per datum tuple its DRF id."""

    def __init__(self) -> None:
        self.items: list = []        # per callout: (item id, QIF type)
        self.feature_items: dict = {}  # feature name -> item id
        self.drfs: dict = {}         # datums tuple -> DRF id
        self.device = ""
        self.scale = 1.0             # mm per file unit (geometry)
        self.pmi_scale = 1.0         # mm per file PMI linear unit (characteristic values)
        self.angle_scale = 1.0       # degrees per file PMI angle unit
        self.geom_angle_scale = 1.0  # degrees per file geometric angle unit


def _qif_type(t: Any, spec: Any) -> str:
    """The QIF characteristic type of a callout (a size by its feature: a slot or tab's is
    a Width, a sphere's a SphericalDiameter)."""
    if t.characteristic == "size":
        shape = spec.features[t.feature].shape
        return {"slot": "Width", "tab": "Width", "sphere": "SphericalDiameter"}.get(shape, "Diameter")
    if t.characteristic in ("distance", "angle"):  # QIF's DistanceBetween needs feature nominals: user-defined
        return "UserDefinedLinear" if t.characteristic == "distance" else "UserDefinedAngular"
    return QIF_TYPE[t.characteristic]


def _self_contained(root: Any, spec: Any, ids: _Ids, device: str, zones: dict) -> _Plan:
    """Definitions, nominals and items made from PART.toml; ``zones``: callout index ->
    gagekit's zone (width, diameter, spherical diameter), for each definition's ZoneShape."""
    plan = _Plan()
    plan.device = device
    _units_block(root)
    letters = sorted({d for t in spec.tolerances for d in t.datums})
    ddefs = {}
    if letters:
        dd = _new("DatumDefinitions", n=len(letters))
        for L in letters:
            i = ids()
            ddefs[L] = i
            X.sub(X.sub(dd, "DatumDefinition", id=i), "DatumLabel", L)
        _place(root, dd)
    frames = []
    for t in spec.tolerances:
        if t.datums and t.datums not in frames:
            frames.append(t.datums)
    if frames:
        dr = _new("DatumReferenceFrames", n=len(frames))
        for fr in frames:
            i = ids()
            plan.drfs[fr] = i
            el = X.sub(dr, "DatumReferenceFrame", id=i)
            ds = X.sub(el, "Datums", n=len(fr))
            for k, L in enumerate(fr):
                d = X.sub(ds, "Datum")
                sd = X.sub(d, "SimpleDatum")
                X.sub(sd, "DatumDefinitionId", ddefs[L])
                X.sub(sd, "MaterialModifier", "NONE")
                X.sub(sd, "ReferencedComponent", "NOMINAL")
                X.sub(X.sub(d, "Precedence"), "PrecedenceEnum", ("PRIMARY", "SECONDARY", "TERTIARY")[k])
        _place(root, dr)
    ch = _characteristics(root, ids, "1101", "2017", "Geometrical product specifications (GPS) -- Geometrical tolerancing")
    cdefs = X.sub(ch, "CharacteristicDefinitions", n=len(spec.tolerances))
    cnoms = X.sub(ch, "CharacteristicNominals", n=len(spec.tolerances))
    citems = X.sub(ch, "CharacteristicItems", n=len(spec.tolerances))
    for t in spec.tolerances:
        qt = _qif_type(t, spec)
        di, ni, ii = ids(), ids(), ids()
        d = X.sub(cdefs, f"{qt}CharacteristicDefinition", id=di)
        dimensional = getattr(t, "size_nominal", None) is not None  # sizes, distances, angles (issue 25)
        if dimensional:
            tol = X.sub(d, "Tolerance")
            X.sub(tol, "MaxValue", _num(t.upper))
            X.sub(tol, "MinValue", _num(t.lower))
            X.sub(tol, "DefinedAsLimit", "false")
            if qt.startswith("UserDefined"):
                X.sub(d, "WhatToMeasure", f"{t.characteristic} from {t.feature} to {getattr(t, 'to', None) or '?'} "
                                          "(ISO 14405-2 / ASME Y14.5, as gagekit inspect evaluates it)")
        else:
            X.sub(d, "ToleranceValue", _num(t.tolerance))
        if qt not in _FORM and t.datums and not dimensional:
            X.sub(d, "DatumReferenceFrameId", plan.drfs[t.datums])
        zone = zones.get(t.index, "width")
        if qt in ("Parallelism", "Perpendicularity", "Angularity", "Position", "Straightness", "Coaxiality"):
            if qt != "Coaxiality":
                X.sub(d, "MaterialCondition", {"MMC": "MAXIMUM", "LMC": "LEAST"}.get(getattr(t, "material", None) or "", "NONE"))
            flat = "PlanarZone" if qt in ("Parallelism", "Perpendicularity", "Angularity") else "NonDiametricalZone"
            X.sub(X.sub(d, "ZoneShape"), {"diameter": "DiametricalZone", "spherical diameter": "SphericalZone"}.get(zone, flat))
        n = X.sub(cnoms, f"{qt}CharacteristicNominal", id=ni)
        X.sub(n, "CharacteristicDefinitionId", di)
        X.sub(n, "Name", t.label)
        if qt == "Angularity" and t.angle is not None:
            X.sub(n, "Angle", _num(t.angle))
        if dimensional:
            X.sub(n, "TargetValue", _num(t.size_nominal))
        it = X.sub(citems, f"{qt}CharacteristicItem", id=ii)
        X.sub(it, "Name", t.label)
        _id_list(it, "MeasurementDeviceIds", [device])
        X.sub(it, "CharacteristicNominalId", ni)
        plan.items.append((ii, qt))
    _place(root, ch)
    return plan


def _from_model(root: Any, spec: Any, model: Any, ids: _Ids, device: str) -> _Plan:
    """Items of the model's nominals (the model's ids kept)."""
    plan = _Plan()
    plan.device = device
    plan.scale = model.units.linear
    plan.pmi_scale = model.units.pmi_linear or model.units.linear
    plan.angle_scale = model.units.pmi_angle
    plan.geom_angle_scale = model.units.angle
    by_id = {el.get("id"): el for el in root.iter() if isinstance(el.tag, str) and el.get("id") is not None}
    # the model's frames: the datums tuple of each DRF
    for did, fr in model.drfs.items():
        plan.drfs.setdefault(tuple(L for L, _ in fr.datums), did)
    feats = X.child(root, "Features")
    if feats is None:
        feats = _place(root, _new("Features"))
    fitems = X.child(feats, "FeatureItems")
    if fitems is None:
        fitems = _new("FeatureItems", n=0)
        after = X.child(feats, "FeatureNominals") or X.child(feats, "FeatureDefinitions")
        if after is not None:
            after.addnext(fitems)
        else:
            feats.insert(0, fitems)
    for name, f in spec.features.items():
        if not f.qif_id:
            continue
        nom = by_id.get(f.qif_id)
        if nom is None or not X.local(nom).endswith("FeatureNominal"):
            raise ConfigError(f"{spec.source}: [[feature]] '{name}': qif_id {f.qif_id} is no feature nominal of {model.path}")
        qt = X.local(nom)[: -len("FeatureNominal")]
        i = ids()
        it = X.sub(fitems, f"{qt}FeatureItem", id=i)
        X.sub(it, "FeatureNominalId", f.qif_id)
        X.sub(it, "FeatureName", name)
        X.sub(X.sub(X.sub(X.sub(it, "DeterminationMode"), "Checked"), "CheckDetails"), "Measured")
        plan.feature_items[name] = i
    fitems.set("n", str(len(fitems)))
    ch = X.child(root, "Characteristics")
    if ch is None:
        raise ConfigError(f"{model.path}: the model has no Characteristics for the callouts' qif_id to point at")
    citems = X.child(ch, "CharacteristicItems")
    if citems is None:
        citems = _new("CharacteristicItems", n=0)
        X.child(ch, "CharacteristicNominals").addnext(citems)
    existing = {X.text(el, "CharacteristicNominalId"): el.get("id") for el in citems}
    created: dict = {}
    for t in spec.tolerances:
        nom = by_id.get(t.qif_id) if t.qif_id else None
        if nom is None or not X.local(nom).endswith("CharacteristicNominal"):
            raise ConfigError(f"{spec.source}: [[tolerance]] #{t.index + 1} ({t.label}): qif_id {t.qif_id or '(none)'} is no "
                              f"characteristic nominal of {model.path}")
        qt = X.local(nom)[: -len("CharacteristicNominal")]
        fitem = plan.feature_items.get(t.feature)
        if t.qif_id in existing:
            plan.items.append((existing[t.qif_id], qt))
            fl = X.child(created[t.qif_id], "FeatureItemIds") if t.qif_id in created else None
            if fl is not None and fitem and fitem not in X.ids(fl):  # a pattern: every member's feature
                X.sub(fl, "Id", fitem)
                fl.set("n", str(len(fl)))
            continue
        i = ids()
        it = X.sub(citems, f"{qt}CharacteristicItem", id=i)
        created[t.qif_id] = it
        X.sub(it, "Name", t.label.rsplit(" (1/", 1)[0])
        if fitem:
            _id_list(it, "FeatureItemIds", [fitem])
        _id_list(it, "MeasurementDeviceIds", [device])
        X.sub(it, "CharacteristicNominalId", t.qif_id)
        existing[t.qif_id] = i
        plan.items.append((i, qt))
    citems.set("n", str(len(citems)))
    return plan


# -- the results ------------------------------------------------------------------------


def _scan_reference(mr: Any, scan: Any, description: str) -> None:
    """The scan file as the results' ExternalFileReference (a file URI when it exists)."""
    p = Path(str(scan))
    ref = X.sub(X.sub(mr, "ExternalFileReferences", n=1), "ExternalFileReference")
    X.sub(ref, "URI", p.resolve().as_uri() if p.exists() else str(scan))
    X.sub(X.sub(ref, "FileSpec"), "OtherFileSpec", (p.suffix.lstrip(".") or "points").upper())
    X.sub(ref, "Description", description)


def _device(root: Any, device: str, instrument: str, description: str) -> None:
    """The instrument as a MeasurementDevice of MeasurementResources (added to the model's)."""
    mres = X.child(root, "MeasurementResources")
    if mres is None:
        mres = _place(root, _new("MeasurementResources"))
    devs = X.child(mres, "MeasurementDevices")
    if devs is None:
        devs = _new("MeasurementDevices", n=0)
        later = [c for c in mres if X.local(c) in ("DetachableSensors", "Tools")]  # the schema's order
        if later:
            later[0].addprevious(devs)
        else:
            mres.append(devs)
    dev = X.sub(devs, "MeasurementDevice", id=device)
    X.sub(dev, "Name", instrument or "point-cloud scanner")
    X.sub(dev, "Description", description)
    devs.set("n", str(len(devs)))


def _measured_feature(parent: Any, name: str, fd: dict, plan: _Plan, ids: _Ids) -> Optional[str]:
    shape = fd.get("shape")
    ls = fd.get("least_squares") or {}
    qt = _SHAPE_TYPE.get(shape)
    if qt is None:
        return None
    s = 1.0 / plan.scale
    i = ids()
    el = X.sub(parent, f"{qt}FeatureMeasurement", id=i)
    if name in plan.feature_items:
        X.sub(el, "FeatureItemId", plan.feature_items[name])
    X.sub(el, "FeatureName", name)
    X.sub(el, "MeasurementDeviceIds", n=1).append(_new("Id", plan.device))

    def pt(key: str) -> Optional[str]:
        v = ls.get(key)
        return None if v is None else X.vec(np.asarray(v, dtype=float) * s)

    def dr(key: str) -> Optional[str]:
        v = ls.get(key)
        return None if v is None else X.vec(np.asarray(v, dtype=float) / np.linalg.norm(v))

    form = ls.get("form_error")
    if shape == "plane":
        X.sub(el, "Location", pt("point"))
        X.sub(el, "Normal", dr("normal"))
    elif shape in ("cylinder", "cone"):
        ax = X.sub(el, "Axis")
        X.sub(ax, "AxisPoint", pt("axis_point") or pt("point"))
        X.sub(ax, "Direction", dr("axis_direction") or dr("direction"))
        if shape == "cylinder" and ls.get("radius") is not None:
            X.sub(el, "Diameter", _num(2 * ls["radius"] * s))
        if shape == "cone":  # gagekit: full apex angle in rad; QIF: the file's angular unit,
            # HalfAngle or FullAngle (an xs:choice: one of them)
            full = math.degrees(float(ls.get("apex_angle", 0.0))) / plan.geom_angle_scale
            X.sub(el, "HalfAngle", _num(full / 2))
    elif shape == "circle":
        X.sub(el, "Location", pt("center"))
        if ls.get("normal") is not None:
            X.sub(el, "Normal", dr("normal"))
        if ls.get("radius") is not None:
            X.sub(el, "Diameter", _num(2 * ls["radius"] * s))
    elif shape == "sphere":
        X.sub(el, "Location", pt("center"))
        if ls.get("radius") is not None:
            X.sub(el, "Diameter", _num(2 * ls["radius"] * s))
    elif shape == "line":
        X.sub(el, "Location", pt("point"))
        X.sub(el, "Direction", dr("direction"))
    if form is not None:
        X.sub(el, "Form", _num(form * s))
    return i


def _transform(parent: Any, frame: dict, ids: _Ids, plan: _Plan) -> Optional[str]:
    if not frame.get("right_handed", True):
        return None
    A = np.array([frame["axes"][k] for k in "xyz"], dtype=float)
    o = np.asarray(frame["origin"], dtype=float)
    i = ids()
    tr = X.sub(parent, "Transform", id=i)
    rot = X.sub(tr, "Rotation")
    for k, n in enumerate(("XDirection", "YDirection", "ZDirection")):
        X.sub(rot, n, X.vec(A[:, k]))
    X.sub(tr, "Origin", X.vec(-(A @ o) / plan.scale))
    return i


def _results(results_el: Any, runs: Sequence[dict], spec: Any, plan: _Plan, ids: _Ids) -> None:
    mset = X.child(results_el, "MeasurementResultsSet")
    if mset is None:
        mset = X.sub(results_el, "MeasurementResultsSet", n=0)
    for run in runs:
        res = run["result"]
        tols = res.get("tolerances", [])
        if len(tols) != len(spec.tolerances):
            raise ConfigError(f"{run.get('scan')}: the result holds {len(tols)} callouts, the drawing {len(spec.tolerances)}")
        mr = X.sub(mset, "MeasurementResults", id=ids())
        key = json.dumps({"scan": run.get("sha256") or run.get("scan"), "tolerances": [t.get("measured") for t in tols]})
        X.sub(mr, "ThisResultsInstanceQPId", str(uuid.uuid5(uuid.NAMESPACE_URL, "gagekit-results:" + key)))
        scan = run.get("scan")
        if scan:
            desc = f"point cloud inspected: {res.get('n_points', 0)} points"
            if run.get("sha256"):
                desc += f", SHA-256 {run['sha256']}"
            _scan_reference(mr, scan, desc)
        feats = res.get("features", {})
        mf = X.sub(mr, "MeasuredFeatures", n=0)
        fmeas = {}
        for name in spec.features:
            if name in feats:
                i = _measured_feature(mf, name, feats[name], plan, ids)
                if i:
                    fmeas[name] = i
        mf.set("n", str(len(mf)))
        if len(mf) == 0:
            mr.remove(mf)
        # one measurement per characteristic item: the callouts of a pattern (one per member,
        # sharing a qif_id) give one actual, the largest, PASS when every member passes
        groups: dict = {}
        for t, r, (item, qt) in zip(spec.tolerances, tols, plan.items):
            groups.setdefault(item, (qt, []))[1].append((t, r))
        mc = X.sub(mr, "MeasuredCharacteristics")
        cm = X.sub(mc, "CharacteristicMeasurements", n=len(groups))
        at = _new("ActualTransforms", n=0)
        for fr in res.get("frames", []):
            _transform(at, fr, ids, plan)
        rule = (res.get("decision_rule") or {}).get("name") if isinstance(res.get("decision_rule"), Mapping) else None
        for item, (qt, members) in groups.items():
            el = X.sub(cm, f"{qt}CharacteristicMeasurement", id=ids())
            angular = members[0][0].characteristic == "angle"
            scale = plan.angle_scale if angular else plan.pmi_scale
            top = max((r for _, r in members), key=lambda r: float(r["measured"]))  # the value written
            unc = top.get("uncertainty") if isinstance(top.get("uncertainty"), Mapping) else None
            _uncertainty_attributes(el, unc, rule, scale)
            _status(el, all(bool(r["pass"]) for _, r in members),
                    decision=_worst([r.get("decision") for _, r in members]) if unc else None)
            X.sub(el, "CharacteristicItemId", item)
            fm = [fmeas[t.feature] for t, _ in members if t.feature in fmeas]
            if fm:
                _id_list(el, "FeatureMeasurementIds", fm)
            X.sub(el, "MeasurementDeviceIds", n=1).append(_new("Id", plan.device))
            _value(el, float(top["measured"]) / scale, unc, scale)
        if len(at):
            at.set("n", str(len(at)))
            mc.addnext(at)
        ok = all(bool(r["pass"]) for r in tols)
        _status(mr, ok, "Inspection")
    mset.set("n", str(len(mset)))


def inspection_results_document(runs: Sequence[dict], spec: Any, spec_path: Any = None, instrument: str = "") -> Any:
    """The QIF document (an lxml tree) of inspection results ``runs`` (each ``{"scan":
    PATH, "result": the inspect JSON dict, "sha256": optional}``) against ``spec``."""
    et = X.etree()
    model = None
    if spec.qif and spec.qif.get("model"):
        from .model import read_model

        mpath = Path(spec.qif["model"])
        if not mpath.is_absolute() and spec_path is not None:
            mpath = Path(spec_path).parent / mpath
        if not mpath.exists():
            raise ConfigError(f"{spec.source}: [qif] model = {spec.qif['model']!r}: the QIF model is not at {mpath}; "
                              "results against a QIF model are written into a copy of it")
        model = read_model(mpath)
        if spec.qif.get("qpid") and model.qpid and spec.qif["qpid"] != model.qpid:
            raise ConfigError(f"{spec.source}: [qif] qpid {spec.qif['qpid']} differs from the QPId of {mpath} "
                              f"({model.qpid}): the drawing was imported from another version of the model")
        root = copy.deepcopy(model.tree.getroot())
        ids = _Ids(model.id_max)
    else:
        root = et.Element(X.Q + "QIFDocument", nsmap={None: X.NS, "xsi": "http://www.w3.org/2001/XMLSchema-instance"})
        root.set("versionQIF", "3.0.0")
        ids = _Ids(0)
    digest = hashlib.sha256(json.dumps([r.get("sha256") or r.get("scan") for r in runs] +
                                       [[t.get("measured") for t in r["result"].get("tolerances", [])] for r in runs]).encode())
    qp = _new("QPId", str(uuid.uuid5(uuid.NAMESPACE_URL, "gagekit-document:" + digest.hexdigest())))
    _place(root, qp)
    _header(root)
    device = ids()
    if model is not None:
        ext = _new("ExternalQIFReferences", n=1)
        e = X.sub(ext, "ExternalQIFDocument", id=ids())
        X.sub(e, "QPId", model.qpid or str(uuid.uuid5(uuid.NAMESPACE_URL, str(model.path))))
        X.sub(e, "URI", X.path_name(model.path))
        X.sub(e, "Description", "the QIF model-based definition these results were measured against")
        _place(root, ext)
        plan = _from_model(root, spec, model, ids, device)
    else:
        first = runs[0]["result"].get("tolerances", []) if runs else []
        plan = _self_contained(root, spec, ids, device, {k: t.get("zone") for k, t in enumerate(first)})
    _device(root, device, instrument, "the instrument that acquired the inspected point clouds")
    res_el = X.child(root, "Results")
    if res_el is None:
        res_el = _place(root, _new("Results"))
    _results(res_el, runs, spec, plan, ids)
    root.set("idMax", str(ids.last))
    return root.getroottree()


def write_inspection_results(path: Any, runs: Sequence[dict], spec: Any, spec_path: Any = None, instrument: str = "") -> Path:
    """Write the QIF results document (atomically: temp file, then rename)."""
    from .._files import write_bytes

    tree = inspection_results_document(runs, spec, spec_path, instrument)
    data = X.etree().tostring(tree, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    return write_bytes(path, data)



# -- virtual gages (gage check) ---------------------------------------------------------


def gage_results_document(scan: Any, result: dict, instrument: str = "") -> Any:
    """A self-contained QIF document of a virtual-gage check (Ch. 5): each gage is a
    ``UserDefinedLinearCharacteristic`` whose value is its stock allowance at T*
    (``allowance_after``, mm; the smallest signed distance of its points from the gage
    plane, negative = short of material), with the lower limit 0 and status PASS when the
    gage is met (slack 0); T* is the results' ``ActualTransform`` (part frame, Eq. 5.11)."""
    et = X.etree()
    gages = result.get("gages", [])
    if not gages:
        raise ConfigError("the gage check has no gages to write")
    root = et.Element(X.Q + "QIFDocument", nsmap={None: X.NS, "xsi": "http://www.w3.org/2001/XMLSchema-instance"})
    root.set("versionQIF", "3.0.0")
    ids = _Ids(0)
    digest = hashlib.sha256(json.dumps([str(scan)] + [g.get("allowance_after") for g in gages]).encode()).hexdigest()
    _place(root, _new("QPId", str(uuid.uuid5(uuid.NAMESPACE_URL, "gagekit-gage:" + digest))))
    _header(root)
    _units_block(root)
    device = ids()
    _device(root, device, instrument, "the instrument that acquired the checked point cloud")
    # the gages are virtual gages for machining stock (dissertation Ch. 5) against the
    # datums of ISO 5459; that is the standard named
    ch = _characteristics(root, ids, "5459", "2011", "Geometrical product specifications (GPS) -- Datums and datum systems")
    cdefs = X.sub(ch, "CharacteristicDefinitions", n=len(gages))
    cnoms = X.sub(ch, "CharacteristicNominals", n=len(gages))
    citems = X.sub(ch, "CharacteristicItems", n=len(gages))
    items = []
    for g in gages:
        di, ni, ii = ids(), ids(), ids()
        d = X.sub(cdefs, "UserDefinedLinearCharacteristicDefinition", id=di)
        tol = X.sub(d, "Tolerance")
        X.sub(tol, "MinValue", "0")
        X.sub(tol, "DefinedAsLimit", "true")
        X.sub(d, "WhatToMeasure", f"stock allowance of virtual gage '{g['name']}' on region '{g['region']}' at the "
                                  "optimal correction T* (gagekit gage check, dissertation Eq. 5.4 and 5.11)")
        n = X.sub(cnoms, "UserDefinedLinearCharacteristicNominal", id=ni)
        X.sub(n, "CharacteristicDefinitionId", di)
        X.sub(n, "Name", str(g["name"]))
        it = X.sub(citems, "UserDefinedLinearCharacteristicItem", id=ii)
        X.sub(it, "Name", str(g["name"]))
        _id_list(it, "MeasurementDeviceIds", [device])
        X.sub(it, "CharacteristicNominalId", ni)
        items.append(ii)
    _place(root, ch)
    res_el = _place(root, _new("Results"))
    mset = X.sub(res_el, "MeasurementResultsSet", n=1)
    mr = X.sub(mset, "MeasurementResults", id=ids())
    X.sub(mr, "ThisResultsInstanceQPId", str(uuid.uuid5(uuid.NAMESPACE_URL, "gagekit-gage-results:" + digest)))
    _scan_reference(mr, scan, "point cloud checked with virtual gages")
    mc = X.sub(mr, "MeasuredCharacteristics")
    cm = X.sub(mc, "CharacteristicMeasurements", n=len(gages))
    rule = (result.get("decision_rule") or {}).get("name") if isinstance(result.get("decision_rule"), Mapping) else None
    for g, item in zip(gages, items):
        el = X.sub(cm, "UserDefinedLinearCharacteristicMeasurement", id=ids())
        unc = g.get("uncertainty") if isinstance(g.get("uncertainty"), Mapping) else None
        _uncertainty_attributes(el, unc, rule, 1.0)
        _status(el, float(g.get("slack", 0.0)) == 0.0, decision=g.get("decision") if unc else None)
        X.sub(el, "CharacteristicItemId", item)
        X.sub(el, "MeasurementDeviceIds", n=1).append(_new("Id", device))
        _value(el, g["allowance_after"], unc, 1.0)
    T = np.asarray(result.get("transform", {}).get("matrix", np.eye(4)), dtype=float)
    at = X.sub(mr, "ActualTransforms", n=1)
    tr = X.sub(at, "Transform", id=ids())
    rot = X.sub(tr, "Rotation")
    for k, nme in enumerate(("XDirection", "YDirection", "ZDirection")):
        X.sub(rot, nme, X.vec(T[:3, k]))
    X.sub(tr, "Origin", X.vec(T[:3, 3]))
    _status(mr, result.get("status") == "conforming", "Inspection")
    root.set("idMax", str(ids.last))
    return root.getroottree()


def write_gage_results(path: Any, scan: Any, result: dict, instrument: str = "") -> Path:
    """Write the virtual-gage QIF document (atomically)."""
    from .._files import write_bytes

    tree = gage_results_document(scan, result, instrument)
    return write_bytes(path, X.etree().tostring(tree, xml_declaration=True, encoding="UTF-8", pretty_print=True))
