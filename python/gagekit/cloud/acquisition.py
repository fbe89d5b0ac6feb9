"""When a scan was taken, from its file's own header (not the file system's times).

* E57 (ASTM E2807, Secs. 8.4.10, 8.4.12 and 9.2): the earliest ``acquisitionStart`` of the
  ``data3D`` scans, else the file's ``creationDateTime``; both are GPS time (seconds since
  1980-01-06 00:00:00), converted to UTC with the leap seconds since then. The XML section
  is read through the file's 1024-byte pages, each ending in a 4-byte checksum.
* LAS/LAZ (ASPRS LAS 1.0-1.4, public header block): the file creation day of year and
  year, a date (00:00 UTC of that day); 0/0 means not given.

Other formats carry no acquisition time. A header that does not say, or says something
impossible (before 1980, after tomorrow), gives ``None``: the time is optional, never a
reason to refuse a scan (the reader reports a damaged file itself).
"""

from __future__ import annotations

import struct
from datetime import date, datetime, timedelta, timezone
from pathlib import Path
from typing import Optional, Union

__all__ = ["acquisition_time", "gps_to_utc"]

_GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
#: UTC dates from which GPS time is ahead of UTC by one more second (IERS Bulletin C)
_LEAPS = [date(1981, 7, 1), date(1982, 7, 1), date(1983, 7, 1), date(1985, 7, 1), date(1988, 1, 1), date(1990, 1, 1),
          date(1991, 1, 1), date(1992, 7, 1), date(1993, 7, 1), date(1994, 7, 1), date(1996, 1, 1), date(1997, 7, 1),
          date(1999, 1, 1), date(2006, 1, 1), date(2009, 1, 1), date(2012, 7, 1), date(2015, 7, 1), date(2017, 1, 1)]
_PAGE = 1024
_MAX_XML = 64 << 20  # a scan's XML section is kilobytes; more is not a header worth reading


def gps_to_utc(seconds: float) -> datetime:
    """UTC of a GPS time (seconds since the GPS epoch, leap seconds not counted in UTC)."""
    t = _GPS_EPOCH + timedelta(seconds=seconds)
    return t - timedelta(seconds=sum(1 for d in _LEAPS if t.date() >= d))


def _plausible(t: Optional[datetime]) -> Optional[datetime]:
    if t is None or t < _GPS_EPOCH or t > datetime.now(timezone.utc) + timedelta(days=1):
        return None
    return t


def acquisition_time(path: Union[str, Path]) -> Optional[datetime]:
    """The time (UTC) the scan in ``path`` was taken, if its format records it."""
    p = Path(path)
    suffix = p.suffix.lower()
    try:
        if suffix == ".e57":
            return _plausible(_e57(p))
        if suffix in (".las", ".laz"):
            return _plausible(_las(p))
    except (OSError, ValueError, OverflowError, struct.error, SyntaxError):  # ET.ParseError is a SyntaxError
        return None
    return None


def _e57_xml(p: Path) -> bytes:
    with open(p, "rb") as fh:
        head = fh.read(48)
        if len(head) < 48 or head[:8] != b"ASTM-E57":
            raise ValueError("not an E57 file")
        _major, _minor, _length, offset, xml_len, page = struct.unpack("<IIQQQQ", head[8:48])
        if page != _PAGE or xml_len > _MAX_XML or offset % _PAGE > _PAGE - 4:
            raise ValueError("unexpected E57 layout")
        out = bytearray()
        fh.seek(offset)
        skip = offset % _PAGE
        fh.seek(offset - skip)
        while len(out) < xml_len:
            block = fh.read(_PAGE)
            if len(block) < _PAGE:
                raise ValueError("truncated E57 XML section")
            out += block[skip:_PAGE - 4]
            skip = 0
        return bytes(out[:xml_len])


def _e57(p: Path) -> Optional[datetime]:
    import xml.etree.ElementTree as ET

    root = ET.fromstring(_e57_xml(p))

    def local(tag: str) -> str:
        return tag.rsplit("}", 1)[-1]

    def when(node) -> Optional[float]:
        for child in node:
            if local(child.tag) == "dateTimeValue" and child.text:
                v = float(child.text)
                return v if v > 0 else None
        return None

    starts = []
    for node in root.iter():
        if local(node.tag) == "data3D":
            for scan in node:
                for child in scan:
                    if local(child.tag) == "acquisitionStart":
                        v = when(child)
                        if v is not None:
                            starts.append(v)
    if not starts:
        for child in root:
            if local(child.tag) == "creationDateTime":
                v = when(child)
                if v is not None:
                    starts.append(v)
    return gps_to_utc(min(starts)) if starts else None


def _las(p: Path) -> Optional[datetime]:
    with open(p, "rb") as fh:
        head = fh.read(94)
    if len(head) < 94 or head[:4] != b"LASF":
        raise ValueError("not a LAS file")
    day, year = struct.unpack("<HH", head[90:94])
    if day == 0 or year == 0 or not 1 <= day <= 366:
        return None
    d = datetime(year, 1, 1, tzinfo=timezone.utc) + timedelta(days=day - 1)
    return d if d.year == year else None
