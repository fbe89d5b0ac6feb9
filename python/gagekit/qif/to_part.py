"""A QIF model-based definition -> a PART.toml that ``gagekit inspect`` runs.

Every characteristic nominal of the model is accounted for, in one of three lists:

- ``evaluated`` -- a ``[[tolerance]]`` table that this gagekit evaluates (flatness,
  straightness, circularity -> roundness, cylindricity, sphericity, parallelism,
  perpendicularity, angularity, position, coaxiality (ASME concentricity is evaluated as
  the coaxiality of the derived axis, ISO 1101 Sec. 18.13, and says so), surface profile of
  a plane, circular and total run-out);
- ``unsupported`` with ``"toml": "comment"`` -- sizes, distances, angles and material
  modifiers (issue 25's keys: ``characteristic = "size"``, ``nominal``/``upper``/``lower``,
  ``material = "MMC"``, ``datums = ["A", "B(M)"]``) when the installed gagekit does not
  evaluate them yet: written as a commented ``[[tolerance]]`` table, ready to run once
  it does (the importer checks what the spec accepts, so a newer gagekit writes them live);
- ``unsupported`` with ``"toml": "listed"`` -- anything else (a feature type gagekit has no
  shape for, a common datum, a profile of a free-form surface...), with the reason, and a
  comment line in the TOML.

Each callout keeps ``qif_id`` (the characteristic nominal's id) and ``qpid`` (the model
document's QPId): together they name the characteristic in the model, and ``gagekit
inspect --qif-results`` writes its results against them.

Basic locations (position, profile) are in the datum frame, as PART.toml wants them:
the importer samples the nominal surfaces (:mod:`.nominal`), simulates the datums on them
with the inspection's own :class:`~gagekit.inspect.datums.DatumSystem` and expresses
each nominal in the frame it builds (so the frame conventions are gagekit's by
construction).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..errors import ConfigError, GagekitError
from .model import Characteristic, QifModel
from .nominal import feature_region, problem, sample_feature, shape_of

__all__ = ["PartDraft", "part_from_model", "GAGEKIT_OF", "PENDING_OF"]

#: QIF characteristic type -> gagekit characteristic (evaluated by this version)
GAGEKIT_OF = {
    "Flatness": "flatness", "Straightness": "straightness", "Circularity": "roundness", "Cylindricity": "cylindricity",
    "Sphericity": "sphericity", "Parallelism": "parallelism", "Perpendicularity": "perpendicularity",
    "Angularity": "angularity", "Position": "position", "Coaxiality": "coaxiality", "Concentricity": "coaxiality",
    "SurfaceProfile": "profile", "CircularRunout": "circular-runout", "TotalRunout": "total-runout",
    "Conicity": "conicity",
}
#: QIF characteristic type -> issue 25's characteristic (sizes, distances, angles)
PENDING_OF = {"Diameter": "size", "SphericalDiameter": "size", "Width": "size", "DistanceBetween": "distance",
              "Angle": "angle", "AngleBetween": "angle"}
_MATERIAL = {"MAXIMUM": "MMC", "LEAST": "LMC"}
_NEEDS_DRF = ("parallelism", "perpendicularity", "angularity", "position", "coaxiality", "circular-runout", "total-runout")


@dataclass
class PartDraft:
    """The PART.toml text and the account of every characteristic."""

    toml: str
    doc: dict
    summary: dict = field(default_factory=dict)


def _spec_accepts() -> dict:
    """What the installed PART.toml reader evaluates beyond the geometric callouts."""
    from ..schema.part import CHARACTERISTICS, ToleranceTable

    keys = set(ToleranceTable.model_fields)  # the keys of a [[tolerance]] table (its schema)
    chars = set(CHARACTERISTICS)
    return {"size": "size" in chars, "distance": "distance" in chars, "angle": "angle" in chars,
            "material": "material" in keys, "datum_modifiers": "material" in keys}


def _fname(f) -> str:
    return f"{shape_of(f) or f.kind.lower()}-{f.id}"


def _angle_between(a_plane: bool, a: np.ndarray, b_plane: bool, b: np.ndarray) -> float:
    """Basic angle (deg, 0..90) between a feature and a datum, as gagekit reads ``angle``:
    between two planes or two lines the angle of their normals / directions, between a
    plane and a line 90 minus the angle of the normal and the line."""
    c = min(1.0, abs(float(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))))
    ang = math.degrees(math.acos(c))
    return 90.0 - ang if a_plane != b_plane else ang


class _Importer:
    def __init__(self, model: QifModel, band: float, inset: float) -> None:
        self.m = model
        self.band = band
        self.inset = inset
        self.accepts = _spec_accepts()
        self.features: dict = {}      # PART.toml feature name -> table
        self.feature_ids: dict = {}   # qif feature id -> name
        self.notes: dict = {}         # feature name -> region note
        self.datums: dict = {}        # letter -> feature name
        self.datum_problem: dict = {}  # letter -> why gagekit cannot simulate it
        self.live: list = []          # (characteristic, table)
        self.pending: list = []       # (characteristic, table, reason)
        self.listed: list = []        # (characteristic, reason)
        self.warnings: list = []

    # -- features and datums -----------------------------------------------------------
    def feature(self, fid: str) -> tuple[Optional[str], Optional[str]]:
        """The PART.toml feature of a QIF feature nominal (added on first use), or the reason
        it cannot be one."""
        f = self.m.features[fid]
        why = problem(f)
        if why:
            return None, why
        name = _fname(f)
        if name not in self.features:
            reg = feature_region(f, self.band, self.inset)
            t: dict = {"name": name, "shape": shape_of(f), "region": reg.to_dict(), "qif_id": f.id}
            g = f.geometry
            if f.kind == "OppositeParallelPlanes":  # slot / tab: the direction across the width
                t["direction"] = [float(x) for x in g["normal"]]
            if f.kind == "Plane":
                t["outward"] = [float(x) for x in g["normal"]]
            if f.kind in ("Cylinder", "Cone", "Circle", "Sphere") and f.internal is not None:
                t["kind"] = "hole" if f.internal else "shaft"
            if f.kind in ("Cylinder", "Cone", "Line"):
                t["direction"] = [float(x) for x in g["direction"]]
            if f.kind == "Circle":
                t["direction"] = [float(x) for x in g["normal"]]
            if f.kind == "Line" and g.get("normal") is not None:
                t["outward"] = [float(x) for x in g["normal"]]
            self.features[name] = t
            self.feature_ids[f.id] = name
            if reg.note:
                self.notes[name] = reg.note
                self.warnings.append(f"feature {name}: {reg.note}")
        return name, None

    def datum_letters(self) -> None:
        for d in self.m.datums.values():
            if not d.feature_ids:
                self.datum_problem[d.label] = f"datum {d.label} is established by datum targets, which gagekit does not simulate"
                continue
            if len(d.feature_ids) != 1:
                self.datum_problem[d.label] = f"datum {d.label} is defined on {len(d.feature_ids)} features (a common datum)"
                continue
            f = self.m.features[d.feature_ids[0]]
            if f.kind not in ("Plane", "Cylinder", "Cone", "Circle", "Sphere"):
                art = "an" if f.kind[0] in "AEIOU" else "a"
                self.datum_problem[d.label] = f"datum {d.label} is {art} {f.kind} feature, which gagekit cannot simulate as a datum"
                continue
            if f.kind != "Plane" and f.internal is None:
                self.datum_problem[d.label] = f"datum {d.label}: the model does not say whether feature {f.id} is internal or external"
                continue
            name, why = self.feature(f.id)
            if why:
                self.datum_problem[d.label] = f"datum {d.label}: {why}"
                continue
            self.datums[d.label] = name

    # -- characteristics ---------------------------------------------------------------
    def drf(self, c: Characteristic) -> tuple[list, Optional[str], bool]:
        """(datum labels with modifiers, problem, has modifiers)."""
        if c.drf_id is None:
            return [], None, False
        frame = self.m.drfs[c.drf_id]
        if frame.problem:
            return [], f"its datum reference frame {c.drf_id} has {frame.problem}", False
        out, mods = [], False
        for label, mod in frame.datums:
            if label in self.datum_problem:
                return [], self.datum_problem[label], False
            out.append(f"{label}({mod})" if mod else label)
            mods = mods or bool(mod)
        return out, None, mods

    def characteristic(self, c: Characteristic) -> None:
        kind = c.kind
        if kind in GAGEKIT_OF:
            self.geometric(c, GAGEKIT_OF[kind])
        elif kind in PENDING_OF:
            self.dimensional(c, PENDING_OF[kind])
        else:
            self.listed.append((c, f"gagekit does not evaluate a {kind} characteristic"))

    def _base(self, c: Characteristic, char: str, feature: str) -> dict:
        t: dict = {"feature": feature, "characteristic": char}
        label = c.name or f"{c.kind} {c.id}"
        if c.designator:
            label += f" [{c.designator}]"
        t["name"] = label
        t["qif_id"] = c.id
        if self.m.qpid:
            t["qpid"] = self.m.qpid
        return t

    def geometric(self, c: Characteristic, char: str) -> None:
        """One callout per feature of the characteristic (a pattern ``n x`` gives n callouts
        sharing the ``qif_id``; each member meets the tolerance on its own, ISO 1101 /
        ASME Y14.5 without a common-zone modifier)."""
        from ..inspect.spec import APPLIES_TO

        if not c.feature_ids:
            self.listed.append((c, "it names no feature"))
            return
        names = []
        for fid in c.feature_ids:
            name, why = self.feature(fid)
            if why:
                self.listed.append((c, f"its feature is {why}"))
                return
            shape = self.features[name]["shape"]
            if shape not in APPLIES_TO[char]:
                self.listed.append((c, f"{char} of a {shape} is not evaluated (it applies to: {', '.join(APPLIES_TO[char])})"))
                return
            names.append(name)
        if c.extras:
            self.listed.append((c, f"modifiers gagekit does not evaluate: {', '.join(c.extras)}"))
            return
        if c.tolerance is None or not c.tolerance > 0:
            self.listed.append((c, "the definition gives no positive ToleranceValue"))
            return
        kinds = {self.m.features[fid].kind for fid in c.feature_ids}
        axial = bool(kinds & {"Cylinder", "Cone", "Circle"})
        if c.zone in ("NonDiametricalZone", "PlanarZone") and axial and char == "position":
            self.listed.append((c, f"a {c.zone} (two parallel planes) about an axis; gagekit's position zone of an axis is a cylinder"))
            return
        if c.zone == "DiametricalZone" and "Plane" in kinds:
            self.listed.append((c, "a diametrical zone on a plane"))
            return
        letters, why, mods = self.drf(c)
        if why:
            self.listed.append((c, why))
            return
        if char in _NEEDS_DRF and not letters:
            self.listed.append((c, f"{char} without a datum reference frame"))
            return
        if char in ("flatness", "straightness", "roundness", "cylindricity", "sphericity", "conicity"):
            letters = []
        notes = []
        if c.kind == "Concentricity":
            notes.append("ASME concentricity evaluated as coaxiality of the derived axis (ISO 1101 18.13)")
        if len(names) > 1:
            notes.append(f"a pattern of {len(names)} features: one callout each")
        pending = []
        material = None
        if c.material in _MATERIAL:
            material = _MATERIAL[c.material]
            if not self.accepts["material"]:
                pending.append(f"material condition {material}")
        elif c.material not in ("NONE", "REGARDLESS", ""):
            self.listed.append((c, f"material condition {c.material}"))
            return
        if mods and not self.accepts["datum_modifiers"]:
            pending.append("datum material boundary modifiers " + ", ".join(x for x in letters if "(" in x))
        for k, name in enumerate(names):
            t = self._base(c, char, name)
            if len(names) > 1:
                t["name"] += f" ({k + 1}/{len(names)})"
            t["tolerance"] = c.tolerance
            if letters:
                t["datums"] = letters
            if char == "angularity":
                t["angle"] = c.angle if c.angle is not None and 0.0 <= c.angle <= 90.0 else None
            if material:
                t["material"] = material
            if pending:
                self.pending.append((c, t, "this gagekit does not evaluate " + " and ".join(pending) + " yet (issue 25)"))
            else:
                self.live.append((c, t, list(notes)))

    def dimensional(self, c: Characteristic, char: str) -> None:
        t = self._base(c, char, "")
        names = []
        for fid in c.feature_ids:
            name, why = self.feature(fid)
            names.append(name or _fname(self.m.features[fid]))
            if why and self.m.features[fid].kind == "OppositeParallelPlanes" and not shape_of(self.m.features[fid]):
                t.setdefault("_needs", f"feature {names[-1]} is an {self.m.features[fid].kind} (shape \"slot\" / \"tab\")")
            elif why:
                self.listed.append((c, f"its feature is {why}"))
                return
        if char == "size":
            t["feature"] = names[0]
        else:
            if len(names) != 2:
                self.listed.append((c, f"a {char} between {len(names)} features (gagekit: between two)"))
                return
            t["feature"], t["to"] = names
        if c.basic:
            self.listed.append((c, "a basic (theoretically exact) dimension: no tolerance to evaluate"))
            return
        if c.target is None or c.upper is None or c.lower is None:
            self.listed.append((c, "no TargetValue or no Tolerance limits"))
            return
        t["nominal"] = c.target
        if c.limits_absolute:
            t["upper"], t["lower"] = c.upper - c.target, c.lower - c.target
        else:
            t["upper"], t["lower"] = c.upper, c.lower
        if c.extras:
            self.listed.append((c, f"modifiers gagekit does not evaluate: {', '.join(c.extras)}"))
            return
        members = [t]
        if char == "size" and len(names) > 1:  # a pattern: the size of each member
            members = []
            for k, name in enumerate(names):
                m = dict(t, feature=name, name=f"{t['name']} ({k + 1}/{len(names)})")
                members.append(m)
        for m in members:
            if self.accepts.get(char) and "_needs" not in m:
                self.live.append((c, m, [f"a pattern of {len(names)} features: one callout each"] if len(members) > 1 else []))
            else:
                why = m.pop("_needs", None)
                self.pending.append((c, m, f"this gagekit does not evaluate {char} callouts yet (issue 25)" + (f"; {why}" if why else "")))

    # -- nominals in the datum frames --------------------------------------------------
    def nominal_frames(self) -> None:
        """Basic locations of position / profile callouts, and missing basic angles of
        angularity, from the nominal geometry in each callout's datum frame."""
        from ..inspect import part_spec_from_dict
        from ..inspect.datums import DatumSystem
        from ..inspect.features import FeatureData
        from ..errors import GagekitError as _GE

        need = [(c, t, n) for c, t, n in self.live if t["characteristic"] in ("position", "profile", "angularity")]
        if not need:
            return
        by_name = {_fname(f): f for f in self.m.features.values()}
        used = set(self.datums.values()) | {t["feature"] for _, t, _ in need}
        doc = self._doc([], only=used, datums_only=True)
        try:
            spec = part_spec_from_dict(doc, "nominal")
        except _GE:
            spec = None
        feats = {}
        if spec is not None:
            for name, feat in spec.features.items():
                pts = sample_feature(by_name[name])
                feats[name] = FeatureData(feat, np.arange(len(pts)), np.ascontiguousarray(pts))
            system = DatumSystem(spec, feats)
        for c, t, notes in need:
            f = by_name[t["feature"]]
            g = f.geometry
            letters = tuple(x.split("(")[0] for x in t.get("datums", []))
            if t["characteristic"] == "angularity":
                if t.get("angle") is None:
                    d = self.m.features[self.m.datums[[k for k, v in self.m.datums.items() if v.label == letters[0]][0]].feature_ids[0]]
                    a = g.get("normal") if f.kind == "Plane" else g.get("direction")
                    b = d.geometry.get("normal") if d.kind == "Plane" else d.geometry.get("direction")
                    if a is None or b is None:
                        t["_drop"] = "no basic angle in the model and none derivable from the nominals"
                        continue
                    t["angle"] = round(_angle_between(f.kind == "Plane", a, d.kind == "Plane", b), 9)
                    notes.append("basic angle from the nominal geometry")
                continue
            if not letters:  # a floating profile (= flatness): the nominal in the model's frame
                p, d = (g["location"], g["normal"]) if f.kind == "Plane" else (None, None)
                if p is None:
                    t["_drop"] = "a profile without datums of a feature that is not a plane"
                    continue
                t["nominal"] = {"point": [float(x) for x in p], "direction": [float(x) for x in d]}
                continue
            if spec is None:
                t["_drop"] = "the datum features cannot be simulated on the nominal geometry"
                continue
            try:
                frame = system.frame(letters)
            except _GE as exc:
                t["_drop"] = f"its datum frame cannot be built on the nominal geometry ({exc})"
                continue
            members = sum(1 for x in self.live if x[0].id == c.id)
            if members > 1 and (len(frame.free_translations) or frame.free_rotation):
                t["_drop"] = (f"a pattern of {members} features whose datum frame {'|'.join(letters)} leaves motion free: "
                              "the members share it (a simultaneous requirement); gagekit evaluates one feature per callout")
                continue
            if f.kind == "Plane":
                p, d = g["location"], g["normal"]
            elif f.kind in ("Cylinder", "Cone"):
                p, d = g["point"], g["direction"]
            elif f.kind == "Circle":
                p, d = g["center"], g["normal"]
            else:
                p, d = g.get("center", g.get("location")), None
            nom: dict = {"point": [round(float(x), 9) + 0.0 for x in frame.to_frame(p)]}
            if d is not None:
                dd = np.asarray(d, dtype=float) @ frame.axes.T
                nom["direction"] = [round(float(x), 12) + 0.0 for x in dd]
            t["nominal"] = nom
        dropped: dict = {}
        for c, t, notes in self.live:
            why = t.pop("_drop", None)
            if why and c.id not in dropped:
                dropped[c.id] = why
                self.listed.append((c, why))
        self.live = [x for x in self.live if x[0].id not in dropped]

    # -- output -------------------------------------------------------------------------
    def _doc(self, live: list, only: Optional[set] = None, datums_only: bool = False) -> dict:
        used = set(only) if only is not None else {t["feature"] for _, t, _ in live} | set(self.datums.values())
        feats = [dict(t) for n, t in self.features.items() if n in used]
        datums = {k: v for k, v in self.datums.items() if v in used}
        doc: dict = {"part": {"name": Path(self.m.path).name.split(".")[0]}, "feature": feats, "datums": datums,
                     "tolerance": [dict(t) for _, t, _ in live]}
        if datums_only:
            if not doc["tolerance"]:
                # a harmless callout so that the spec parses (the datums are what is needed)
                first = feats[0]
                doc["tolerance"] = [{"feature": first["name"], "characteristic": {"plane": "flatness", "cylinder": "cylindricity",
                                                                                     "circle": "roundness", "sphere": "sphericity",
                                                                                     "line": "straightness"}[first["shape"]],
                                     "tolerance": 1.0}]
        doc["qif"] = {"model": self.m.path, "qpid": self.m.qpid, "units": self.m.units.linear_name}
        return doc

    def validate(self) -> None:
        """Drop (to ``unsupported``) every live callout the spec reader refuses, with its
        message, until the document reads."""
        from ..inspect import part_spec_from_dict

        for _ in range(len(self.live) + 1):
            doc = self._doc(self.live)
            if not self.live:
                return
            try:
                part_spec_from_dict(doc, "import")
                return
            except GagekitError as exc:
                msg = str(exc)
                k = _tolerance_index(msg)
                if k is None:
                    raise ConfigError(f"{self.m.path}: the PART.toml made from the model does not read: {msg}") from None
                c = self.live[k][0]
                self.live = [x for x in self.live if x[0].id != c.id]  # a pattern goes whole
                self.listed.append((c, msg.split(": ", 2)[-1]))


def _tolerance_index(msg: str) -> Optional[int]:
    import re

    m = re.search(r"\[\[tolerance\]\] #(\d+)", msg)
    return int(m.group(1)) - 1 if m else None


def _crowded_regions(model: QifModel, features: list) -> dict:
    """Feature name -> the other features (of the whole model) whose nominal surface passes
    through its region: the regions are boxes, so a hole piercing a face, or a coaxial
    surface within the corners of a cylinder's box, lands in them."""
    from ..cloud.regions import Box, classify

    if not features:
        return {}
    boxes = [Box(t["region"]["center"], t["region"]["size"], t["region"]["rotation"], name=t["name"]) for t in features]
    out: dict = {}
    for f in model.features.values():
        if problem(f):
            continue
        pts = sample_feature(f, 1500)
        name = _fname(f)
        for t, ids in zip(features, classify(pts, boxes)):
            if t["name"] != name and len(ids) > 0:
                out.setdefault(t["name"], []).append(name)
    return out


# -- TOML text --------------------------------------------------------------------------


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        f = float(v)
        if not math.isfinite(f):
            raise ConfigError(f"a non-finite number {v!r} in the imported drawing")
        return repr(f) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def _table(header: str, t: dict, prefix: str = "") -> list:
    lines = [f"{prefix}{header}"]
    lines += [f"{prefix}{k} = {_toml_value(v)}" for k, v in t.items() if v is not None]
    return lines


def _one_line(s: str) -> str:
    return " ".join(str(s).split())


def part_from_model(model: QifModel, band: float = 0.5, inset: float = 1.0, model_ref: Optional[str] = None) -> PartDraft:
    """The PART.toml of a QIF model (module docstring); ``band`` (mm) is the half
    thickness of a surface's region, ``inset`` (mm) how far a region stays inside the
    boundary of its face; ``model_ref`` is the model's path as ``[qif] model`` records it
    (default: its file name: PART.toml beside the model)."""
    if not (band > 0 and inset >= 0):
        raise ConfigError(f"band must be positive and inset zero or positive, got band={band}, inset={inset}")
    imp = _Importer(model, band, inset)
    imp.datum_letters()
    for c in model.characteristics:
        imp.characteristic(c)
    imp.nominal_frames()
    imp.validate()
    live = imp.live
    doc = imp._doc(live)
    m = model
    crowded = _crowded_regions(m, doc["feature"])
    for name, others in crowded.items():
        imp.warnings.append(f"feature {name}: its region also holds the nominal surface of {', '.join(others)}; a scan of "
                            "the whole part puts those points into this feature (shrink or move its region)")
    lines = [
        f"# Imported by `gagekit qif import` from {Path(m.path).name} (QIF {m.version}, QPId {m.qpid or 'none'}).",
        f"# File units: {m.units.linear_name} (x {m.units.linear:g} -> mm). Lengths mm, angles degrees, in the model's",
        "# frame: align the scan to the model first. Regions derived from the nominal geometry:",
        f"# surfaces {2 * band:g} mm thick, kept {inset:g} mm inside each face's boundary.",
        f"# {len(m.characteristics)} characteristics: {len(live)} evaluated below, {len(imp.pending)} written as "
        f"comments (not evaluated by this gagekit yet), {len(imp.listed)} not evaluated (listed at the end).",
        "",
        "[part]",
        f"name = {_toml_value(doc['part']['name'])}",
        "",
        "[qif]",
        f"model = {_toml_value(model_ref or Path(m.path).name)}",
        f"qpid = {_toml_value(m.qpid)}",
        f"units = {_toml_value(m.units.linear_name)}",
        "",
    ]
    for t in doc["feature"]:
        f = m.features[t["qif_id"]]
        lines.append(f"# {f.kind} feature nominal {f.id}" + (f" ({_one_line(f.name)})" if f.name else ""))
        if t["name"] in imp.notes:
            lines.append(f"# region: {imp.notes[t['name']]}")
        if t["name"] in crowded:
            lines.append(f"# region: also holds the nominal surface of {', '.join(crowded[t['name']])} (shrink or move it)")
        lines += _table("[[feature]]", t)
        lines.append("")
    if doc["datums"]:
        lines.append("[datums]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in doc["datums"].items()]
        lines.append("")
    for c, t, notes in live:
        lines.append(f"# QIF {c.kind}CharacteristicNominal {c.id}" + (f": {'; '.join(notes)}" if notes else ""))
        lines += _table("[[tolerance]]", t)
        lines.append("")
    if imp.pending:
        lines.append("# --- written, not evaluated by this gagekit yet (uncomment when it does) ---")
        for c, t, why in imp.pending:
            lines.append(f"# QIF {c.kind}CharacteristicNominal {c.id}: {_one_line(why)}")
            lines += _table("[[tolerance]]", t, prefix="# ")
            lines.append("")
    if imp.listed:
        lines.append("# --- not evaluated by gagekit ---")
        for c, why in imp.listed:
            lines.append(f"# QIF {c.kind}CharacteristicNominal {c.id} ({_one_line(c.name) or 'unnamed'}): {_one_line(why)}")
        lines.append("")
    text = "\n".join(lines)

    def entry(c: Characteristic) -> dict:
        return {"qif_id": c.id, "type": c.kind, "name": c.name, "designator": c.designator,
                "features": [imp.feature_ids.get(f, _fname(m.features[f])) for f in c.feature_ids]}

    evaluated: list = []
    by_id: dict = {}
    for k, (c, t, notes) in enumerate(live):  # one entry per characteristic, its callouts listed
        crowd = [f"region of {t['feature']} also holds other nominal surfaces"] if t["feature"] in crowded else []
        if c.id in by_id:
            by_id[c.id]["callouts"].append(k)
            by_id[c.id]["notes"] += [n for n in crowd if n not in by_id[c.id]["notes"]]
            continue
        by_id[c.id] = dict(entry(c), characteristic=t["characteristic"], callouts=[k], notes=list(notes) + crowd)
        evaluated.append(by_id[c.id])
    seen: set = set()
    unsupported = []
    for c, t, why in imp.pending:
        if c.id not in seen:
            seen.add(c.id)
            unsupported.append(dict(entry(c), characteristic=t["characteristic"], reason=why, toml="comment"))
    unsupported += [dict(entry(c), reason=why, toml="listed") for c, why in imp.listed]
    summary = {
        "model": m.path, "qpid": m.qpid, "version": m.version,
        "units": {"file": m.units.linear_name, "mm_per_unit": m.units.linear},
        "characteristics": len(m.characteristics), "evaluated": evaluated, "unsupported": unsupported,
        "features": len(doc["feature"]), "datums": doc["datums"], "warnings": imp.warnings,
    }
    return PartDraft(text, doc, summary)
