"""The schema of PART.toml, the drawing (``gagekit inspect``): features, datums, callouts.

Lengths are millimetres in the scan's frame, angles degrees. The vocabulary (shapes,
characteristics, modifiers) lives here and :mod:`gagekit.inspect.spec` re-exports it; the rules
that tie keys together (a characteristic applies to the feature's shape, a datum letter names a
feature, 'fit' or 'upper'/'lower'...) are checked by that reader after this schema.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import Field

from ._engine import Style, Table
from ._types import Name, Positive, Vec3
from .gages import RegionTable
from .measurement import MeasurementTable

__all__ = ["PartFile", "PartStyle", "SHAPES", "CHARACTERISTICS", "MAX_SECTIONS"]

SHAPES = ("plane", "cylinder", "circle", "sphere", "line", "cone", "surface", "slot", "tab")
FORM = ("flatness", "straightness", "roundness", "cylindricity", "sphericity", "conicity")
ORIENTATION = ("parallelism", "perpendicularity", "angularity")
LOCATION = ("position", "coaxiality", "profile", "profile-line")
RUNOUT = ("circular-runout", "total-runout")
SIZES = ("size", "distance", "angle")
CHARACTERISTICS = FORM + ORIENTATION + LOCATION + RUNOUT + SIZES
#: Size modifiers (ISO 14405-1 Table 1) and rank-order statistics (applied to the two-point sizes).
SIZE_MODIFIERS = ("LP", "LS", "GG", "GX", "GN", "CC", "CA", "CV")
RANK_ORDER = ("SX", "SN", "SA", "SM", "SD", "SR")
STANDARDS = ("iso", "asme")
MATERIAL = ("MMC", "LMC")
AXIS_METHODS = ("least-squares", "median-line")
DATUM_FITS = ("chebyshev", "least-squares")
#: The most sections a median line, run-out or banded measurement may take: each section
#: needs points of its own, and a larger count only loops over empty slices.
MAX_SECTIONS = 10_000

Sections = Annotated[int, Field(ge=1, le=MAX_SECTIONS)]
Ref = Union[str, int]  # a QIF id or QPId (imported drawings)


class PartTable(Table):
    """``[part]``: the drawing's name and its defaults."""

    name: str = "part"
    """The part's name (reports)."""
    datum_fit: Literal[DATUM_FITS] = "chebyshev"  # type: ignore[valid-type]
    """How datum features are fitted (ISO 5459 default: chebyshev, the constrained minimax fit)."""
    axis: Literal[AXIS_METHODS] = "least-squares"  # type: ignore[valid-type]
    """Derived axes: the least-squares axis or the median line (ISO 12180)."""
    sections: Sections = 10
    """Sections of a median line, a circular run-out or a roundness (1 to 10000)."""
    cad: Optional[Name] = None
    """The CAD model (STEP), relative to the drawing: features may then be located by 'faces'."""
    band: Optional[Positive] = None
    """Default distance (mm) from the CAD faces within which a face feature takes its points."""
    standard: Literal[STANDARDS] = "iso"  # type: ignore[valid-type]
    """The rules of sizes: "iso" (ISO 14405-1) or "asme" (Y14.5 Rule #1: the envelope by default)."""


class InlineRegion(Table):
    """A feature's region: an oriented box in the scan's frame."""

    center: Vec3
    """Centre of the box (mm)."""
    size: Vec3
    """Full edge lengths along the box's own axes (mm, positive)."""
    rotation: Vec3 = [0.0, 0.0, 0.0]
    """Rotation vector (axis times angle, rad) turning the scan's axes onto the box axes."""
    name: Optional[str] = None
    """A name for the region (default: the feature's)."""


class FeatureTable(Table):
    """``[[feature]]``: a toleranced or datum feature, the points of the scan in its region (or near its CAD faces)."""

    name: Name
    """The feature's name: callouts and datums refer to it."""
    shape: Literal[SHAPES]  # type: ignore[valid-type]
    """What is fitted to its points."""
    region: Union[str, InlineRegion, None] = None
    """A box { center, size, rotation } or the name of a [[region]]: the feature's points."""
    outward: Optional[Vec3] = None
    """Planes (and optionally lines): the direction from the material into the air."""
    kind: Optional[Literal["hole", "shaft"]] = None
    """Cylinders, circles, spheres, cones: an internal (hole) or external (shaft) feature."""
    direction: Optional[Vec3] = None
    """Cylinders, cones, lines, circles: roughly along the axis; slots and tabs: across the width."""
    axis: Optional[Literal[AXIS_METHODS]] = None  # type: ignore[valid-type]
    """The derived axis (default: [part] axis)."""
    sections: Optional[Sections] = None
    """Sections of a median line, run-out or roundness (default: [part] sections)."""
    datum_fit: Optional[Literal[DATUM_FITS]] = None  # type: ignore[valid-type]
    """How the feature is fitted as a datum (default: [part] datum_fit)."""
    qif_id: Ref = ""
    """The QIF feature nominal this feature came from (gagekit qif import)."""
    faces: Union[Ref, Annotated[list[Ref], Field(min_length=1)], None] = None
    """STEP face ids (12 or "#12") or names of the [part] cad model."""
    band: Optional[Positive] = None
    """Distance (mm) from the faces within which the feature takes its points (default: [part] band, else 3 RMS)."""


class DatumTable(Table):
    """A datum letter's feature and its basic angle to the primary plane."""

    feature: str
    """The [[feature]] the letter names."""
    angle: Annotated[float, Field(gt=0.0, le=90.0)] = 90.0
    """Basic angle to the primary plane (degrees, (0, 90]; secondary planes and axes)."""


class NominalTable(Table):
    """The basic location in the datum frame."""

    point: Optional[Vec3] = None
    """A point of the feature or its axis (mm, datum frame)."""
    direction: Optional[Vec3] = None
    """The basic normal (planes) or axis (mm, datum frame)."""


class FilterTable(Table):
    """The profile filter of a roundness callout (ISO 16610-21)."""

    type: Literal["gaussian", "none"] = "gaussian"
    """A Gaussian filter, or none."""
    upr: Optional[Positive] = None
    """The cut-off in undulations per revolution (15, 50, 150, 500, 1500)."""


class ToleranceTable(Table):
    """``[[tolerance]]``: one callout of the drawing's feature control frames, or a size, distance or angle."""

    feature: str
    """The toleranced [[feature]]."""
    characteristic: Literal[CHARACTERISTICS]  # type: ignore[valid-type]
    """The characteristic (ISO 1101; size ISO 14405-1; distance and angle ISO 14405-2)."""
    tolerance: Optional[float] = None
    """The tolerance value (mm; 0 only with material); for a size, distance or angle +- this."""
    datums: Union[str, list[str]] = []
    """Datum letters, primary first; "B(M)" / "B(L)" at MMB / LMB."""
    nominal: Union[float, NominalTable, None] = None
    """Geometric callouts: { point, direction } in the datum frame; sizes: the nominal size (mm, degrees for angles)."""
    angle: Optional[float] = None
    """Angularity: the basic angle between feature and datum (degrees, [0, 90])."""
    half_angle: Optional[Annotated[float, Field(gt=0.0, lt=90.0)]] = None
    """Conicity: the basic half apex angle of the cone (degrees; default: free)."""
    name: str = ""
    """A label for reports."""
    sections: Optional[Sections] = None
    """Sections of this callout (default: the feature's)."""
    qif_id: Ref = ""
    """The QIF characteristic nominal this callout came from."""
    qpid: Ref = ""
    """The QPId of the QIF model document."""
    offset: Optional[float] = None
    """Profile of a surface: the zone's offset (ISO 1101 UZ, mm)."""
    upper: Optional[float] = None
    """Size, distance, angle: the upper limit deviation (mm or degrees)."""
    lower: Optional[float] = None
    """Size, distance, angle: the lower limit deviation (mm or degrees)."""
    fit: Optional[str] = None
    """Size: an ISO 286 tolerance class ("H7", "f7") instead of upper and lower."""
    modifier: Optional[str] = None
    """Size: LP LS GG GX GN CC CA CV, or a rank-order statistic SX SN SA SM SD SR (ISO 14405-1; default LP)."""
    angles: Optional[Annotated[int, Field(ge=1)]] = None
    """Size: the directions of the two-point sizes per section."""
    envelope: Optional[bool] = None
    """Size: the envelope requirement (E) (default: true under [part] standard = "asme")."""
    to: Optional[str] = None
    """Distance, angle: the second [[feature]]."""
    material: Optional[Literal[MATERIAL]] = None  # type: ignore[valid-type]
    """Position, orientation, straightness of a feature of size: MMC / LMC (ISO 2692, bonus)."""
    filter: Optional[FilterTable] = None
    """Roundness: the profile filter (ISO 12181-2)."""
    reference: Optional[str] = None
    """Roundness: the reference circle MZCI, LSCI, MCCI or MICI (ISO 12181-1)."""
    direction: Optional[Vec3] = None
    """Profile of a line (ISO 1101 Sec. 18.6): the normal of the parallel section planes (CAD axes)."""
    spacing: Optional[float] = None
    """Profile of a line: the distance between the section planes (mm, > 0; instead of sections)."""


class QifTable(Table):
    """``[qif]``: the QIF model a drawing was imported from (gagekit qif import)."""

    model: Optional[Ref] = None
    """The QIF model file."""
    qpid: Optional[Ref] = None
    """Its QPId."""
    units: Optional[Ref] = None
    """Its length unit."""


class PartFile(Table):
    """A drawing, PART.toml (``gagekit inspect``): the part's features, datums and tolerance callouts."""

    part: PartTable = PartTable()
    """The drawing's name and defaults."""
    region: list[RegionTable] = []
    """Named boxes features may refer to by name."""
    feature: Annotated[list[FeatureTable], Field(min_length=1)]
    """The features (at least one)."""
    datums: dict[str, Union[str, DatumTable]] = {}
    """Datum letter = feature name, or { feature, angle }."""
    tolerance: Annotated[list[ToleranceTable], Field(min_length=1)]
    """The callouts (at least one)."""
    qif: Optional[QifTable] = None
    """The QIF model of an imported drawing."""
    measurement: Optional[MeasurementTable] = None
    """The measurement model of the instrument (``--measurement PART.toml``)."""


class PartStyle(Style):
    """The wording of the drawing reader: ``PART.toml: [[feature]] #3 ('top'): 'shape' = 'torus'
    is unknown; choose one of ...``."""

    tables = ((), ("part",), ("region", int), ("feature", int), ("datums",), ("datums", str), ("tolerance", int),
              ("qif",), ("measurement",))
    phrases = {"outward": "three finite numbers", "direction": "three finite numbers", "point": "three finite numbers",
               "center": "three finite numbers", "size": "three finite numbers", "rotation": "three finite numbers",
               "sections": "a positive integer", "angles": "a positive integer",
               "faces": "a list of STEP face ids or names", "envelope": "true or false",
               "datums": "a list of datum letters", "qif_id": "a string (a QIF id or QPId)",
               "qpid": "a string (a QIF id or QPId)", "model": "a string (a QIF id or QPId)",
               "units": "a string (a QIF id or QPId)",
               "region": "a table { center, size, rotation } or the name of a [[region]]",
               "nominal": "a table { point, direction } (a size's nominal: a number)",
               "filter": "a table { upr = 50 } or { type = \"none\" }"}

    def label(self, table: tuple) -> str:
        if not table:
            return self.source
        if table[0] in ("feature", "tolerance", "region") and len(table) == 2:
            t = self.doc[table[0]][table[1]]
            t = t if isinstance(t, dict) else {}
            if table[0] == "region":
                name = t.get("name")
                return f"{self.source}: region '{name}'" if isinstance(name, str) else f"{self.source}: region #{table[1] + 1}"
            where = f"{self.source}: [[{table[0]}]] #{table[1] + 1}"
            if table[0] == "feature" and isinstance(t.get("name"), str) and t["name"]:
                return where + f" ('{t['name']}')"
            if table[0] == "tolerance" and isinstance(t.get("feature"), str):
                return where + f" ({t.get('characteristic', '?')} of '{t['feature']}')"
            return where
        return f"{self.source}: [{table[0]}]" + "".join(f" {k}" for k in table[1:])

    def subject(self, table: tuple, key: tuple) -> str:
        names = [str(k) for k in key if not isinstance(k, int)]
        return f"{self.label(table)}: '{'.'.join(names)}'"

    def missing(self, table: tuple, key: tuple) -> str:
        k = key[-1]
        if not table and k == "feature":
            return f"{self.source}: no [[feature]] tables; describe at least one feature"
        if not table and k == "tolerance":
            return f"{self.source}: no [[tolerance]] tables; list the drawing's callouts"
        if len(key) > 1:
            return f"{self.label(table)}: '{key[0]}' has no '{k}'"
        if table[:1] == ("feature",) and k == "name":
            return f"{self.label(table)}: 'name' is missing or empty"
        if table[:1] == ("feature",) and k == "shape":
            return f"{self.label(table)}: 'shape' is missing; choose one of {', '.join(SHAPES)}"
        return f"{self.label(table)}: '{k}' is missing"

    def generic(self, kind: str) -> str:
        return "a finite number" if kind in ("float_type", "finite_number") else super().generic(kind)

    def bound(self, subject: str, name: str, kind: str, limit: Any, value: Any) -> str:
        if name == "sections" and kind == "less_than_equal":
            return f"{subject} = {value} is more than {limit} (each section needs points of its own)"
        if name in self.phrases:
            return self.must(subject, self.phrases[name], value)
        return super().bound(subject, name, kind, limit, value)

    def not_table(self, path: tuple, value: Any) -> str:
        if path in (("feature",), ("tolerance",)):
            return self.missing((), path)
        if path == ("datums",):
            return f"{self.source}: [datums] must be a table of letter = feature name"
        if len(path) == 2 and path[0] == "datums":
            return f"{self.label(path)}: must name a [[feature]] or be a table {{ feature, angle }}, got {value!r}"
        if path == ("qif",):
            return f"{self.source}: [qif] must be a table {{ model, qpid, units }}"
        table, key = self.split(path)
        if not key:
            return f"{self.label(table)} must be a table"
        return self.must(self.subject(table, key), self.phrases.get(str(key[-1]), "a table"), value)
