"""LAS and LAZ, read with ``laspy`` (LAZ through its ``lazrs`` backend: the ``las`` extra).

Unit: the linear unit of the header's coordinate reference system. The OGC WKT record
(LASF_Projection 2112) is used when present (``UNIT[...]`` of the projected CRS, and of a
vertical CRS for z); otherwise the GeoTIFF keys (LASF_Projection 34735:
``ProjLinearUnitsGeoKey`` 3076 and ``VerticalUnitsGeoKey`` 4099, EPSG unit codes 9001
metre, 9002 foot, 9003 US survey foot). Without a CRS unit, metres, and a warning naming
the assumed unit when a CRS is present but its unit is not recognised.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Optional

import numpy as np

from ...errors import FileFormatError
from ..units import MM_PER_UNIT
from . import Raw

_EPSG_UNITS = {9001: "m", 9002: "ft", 9003: "us-ft"}
_NAMES = {
    "metre": "m", "meter": "m", "metres": "m", "meters": "m", "m": "m",
    "foot": "ft", "feet": "ft", "ft": "ft", "foot_intl": "ft", "international foot": "ft", "intl foot": "ft",
    "us survey foot": "us-ft", "foot_us": "us-ft", "us_survey_foot": "us-ft", "ftus": "us-ft",
    "us survey feet": "us-ft", "foot (us survey)": "us-ft", "us foot": "us-ft",
}
_GEOGRAPHIC = 2  # GTModelTypeGeoKey value of a geographic (latitude/longitude) CRS


def read(p: Path, dim: int) -> Raw:
    try:
        import laspy
    except ImportError:
        raise FileFormatError(f"{p}: LAS/LAZ needs the optional extra: pip install 'gagekit[las]'") from None
    try:
        las = laspy.read(str(p))
    except Exception as exc:  # laspy raises LaspyException, ValueError, OSError... for bad files
        msg = str(exc)
        if "LazBackend" in msg:
            msg = "no LAZ decompressor; pip install 'gagekit[las]' (laspy with lazrs)"
        raise FileFormatError(f"{p}: not a readable LAS/LAZ file ({msg})") from None
    _check_scales(las.header, p)
    pts = np.empty((len(las.points), 3))
    pts[:, 0], pts[:, 1], pts[:, 2] = las.x, las.y, las.z
    raw = Raw(pts, "laz" if p.suffix.lower() == ".laz" else "las")
    vlrs = list(las.header.vlrs) + list(getattr(las, "evlrs", None) or [])
    _crs_unit(vlrs, raw, p)
    return raw


def _check_scales(header, p: Path) -> None:
    """A coordinate is offset + scale x the stored integer: a scale factor of 0 (or not a
    finite number) would read every point at the offset, so it is refused."""
    for axis, s in zip("xyz", np.asarray(header.scales, dtype=float)):
        if not (np.isfinite(s) and s != 0.0):
            raise FileFormatError(f"{p}: the LAS header's {axis} scale factor is {s:g}: every {axis} would read as "
                                  "the offset; the file is damaged")


def _crs_unit(vlrs: list, raw: Raw, p: Path) -> None:
    wkt = next((v.string for v in vlrs if hasattr(v, "string") and getattr(v, "record_id", None) == 2112), None)
    keys = next((v.geo_keys for v in vlrs if hasattr(v, "geo_keys")), None)
    if wkt:
        h, z, what = _wkt_units(wkt)
        basis = "the CRS of the LAS header (WKT)"
    elif keys:
        k = {g.id: g.value_offset for g in keys if g.tiff_tag_location == 0}
        if k.get(1024) == _GEOGRAPHIC and 3076 not in k:
            raw.unit = None
            raw.unit_basis = (f"{p}: geographic CRS (latitude/longitude in degrees): not lengths; "
                              "give the unit with --units if the coordinates are in fact lengths")
            return
        h = _EPSG_UNITS.get(k.get(3076, -1))
        z = _EPSG_UNITS.get(k.get(4099, -1))
        what = f"GeoTIFF ProjLinearUnitsGeoKey {k[3076]}" if 3076 in k else (
            f"GeoTIFF ProjectedCSTypeGeoKey {k[3072]} without ProjLinearUnitsGeoKey" if 3072 in k else "GeoTIFF keys without a linear unit")
        basis = "the CRS of the LAS header (GeoTIFF keys)"
    else:
        raw.unit, raw.unit_basis = "m", "no CRS in the LAS header: metres assumed"
        return
    if h is None and what == "geographic CRS (degrees)":
        raw.unit = None
        raw.unit_basis = (f"{p}: geographic CRS (latitude/longitude in degrees): not lengths; "
                          "give the unit with --units if the coordinates are in fact lengths")
        return
    if h is None:
        raw.unit, raw.unit_basis = "m", f"unknown CRS unit ({what}): metres assumed"
        raw.warnings.append(f"{p}: the CRS unit of this LAS file is not known ({what}); metres assumed "
                            "(give the unit with --units)")
        return
    raw.unit, raw.unit_basis = h, basis
    if z is not None and z != h:
        raw.z_unit = z
        raw.unit_basis = f"{basis}; z in {z} (vertical CRS)"


def _wkt_units(wkt: str) -> tuple[Optional[str], Optional[str], str]:
    """(horizontal unit, vertical unit, description) of an OGC WKT (1 or 2) string."""
    tree = _parse_wkt(wkt)
    if tree is None:
        return None, None, "unparsable WKT"
    root = tree
    horiz = vert = None
    hdesc = "no projected CRS in the WKT"

    def walk(node, inside):
        nonlocal horiz, vert, hdesc
        kw, args = node
        kwu = kw.upper()
        if kwu in ("PROJCS", "PROJCRS", "PROJECTEDCRS"):
            u = _direct_unit(node)
            if u is not None and horiz is None:
                horiz = u
                hdesc = f"UNIT {u[0]!r}"
        if kwu in ("VERT_CS", "VERTCS", "VERTCRS", "VERTICALCRS"):
            u = _direct_unit(node)
            if u is not None and vert is None:
                vert = u
        for a in args:
            if isinstance(a, tuple):
                walk(a, kwu)

    walk(root, "")
    if root[0].upper() in ("GEOGCS", "GEOGCRS", "GEOGRAPHICCRS") and horiz is None:
        hdesc = "geographic CRS (degrees)"
    return _unit_of(horiz), _unit_of(vert), hdesc


def _direct_unit(node):
    kw, args = node
    for a in args:
        if isinstance(a, tuple) and a[0].upper() in ("UNIT", "LENGTHUNIT"):
            name = a[1][0] if a[1] and isinstance(a[1][0], str) else ""
            factor = next((x for x in a[1][1:] if isinstance(x, float)), None)
            return (name, factor)
    # WKT2: the unit may sit inside CS[...]/AXIS[...]
    for a in args:
        if isinstance(a, tuple) and a[0].upper() == "AXIS":
            u = _direct_unit(a)
            if u is not None:
                return u
    return None


def _unit_of(u) -> Optional[str]:
    if u is None:
        return None
    name, factor = u
    key = _NAMES.get(name.strip().lower().replace("-", " "))
    if key is None:
        key = _NAMES.get(name.strip().lower())
    if key is not None:
        return key
    if factor is not None:
        for unit in ("m", "ft", "us-ft"):
            if abs(factor * 1000.0 - MM_PER_UNIT[unit]) <= 1e-9 * MM_PER_UNIT[unit]:
                return unit
    return None


_TOKEN = re.compile(r'\s*(?:"((?:[^"]|"")*)"|([A-Za-z_][A-Za-z0-9_]*)|([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)|([\[\]\(\),]))')


def _parse_wkt(text: str):
    """A WKT string as nested (KEYWORD, [args]) tuples; numbers as floats, strings as str.
    None if it does not parse."""
    toks = []
    pos = 0
    text = text.rstrip("\x00 \n\r\t")
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m:
            return None
        pos = m.end()
        s, word, num, punct = m.groups()
        if s is not None:
            toks.append(("s", s.replace('""', '"')))
        elif word is not None:
            toks.append(("w", word))
        elif num is not None:
            try:
                toks.append(("n", float(num)))
            except ValueError:
                return None
        else:
            toks.append(("p", punct))
    i = 0

    def node():
        nonlocal i
        kind, kw = toks[i]
        if kind != "w":
            raise ValueError
        i += 1
        args = []
        if i < len(toks) and toks[i] == ("p", "[") or i < len(toks) and toks[i] == ("p", "("):
            i += 1
            while True:
                kind, v = toks[i]
                if kind == "w":
                    if i + 1 < len(toks) and toks[i + 1][1] in ("[", "("):
                        args.append(node())
                    else:
                        args.append(v)  # a bare enum value (EAST, NORTH, UP)
                        i += 1
                elif kind in ("s", "n"):
                    args.append(v)
                    i += 1
                else:
                    raise ValueError
                kind, v = toks[i]
                i += 1
                if v in ("]", ")"):
                    break
                if v != ",":
                    raise ValueError
        return (kw, args)

    try:
        return node()
    except (ValueError, IndexError):
        return None
