"""Length units of point-cloud files. Inside gagekit every length is in millimetres.

=========  ==========================  ===========================================
name       unit                        millimetres per unit
=========  ==========================  ===========================================
``mm``     millimetre                  1
``cm``     centimetre                  10
``m``      metre                       1000
``um``     micrometre                  0.001
``in``     international inch          25.4 (exact, 1959 agreement)
``ft``     international foot          304.8 (exact)
``us-ft``  US survey foot              1200/3937 m = 304.80060960... (LAS CRS only)
=========  ==========================  ===========================================

What a file is read in, when no unit is given (``units=None``):

- E57: metres, by its standard (ASTM E2807: Cartesian and range coordinates in metres).
- LAS/LAZ: the linear unit of the header's coordinate reference system (OGC WKT
  ``UNIT[...]`` or GeoTIFF ``ProjLinearUnitsGeoKey`` / ``VerticalUnitsGeoKey``), metres
  when it has none (with a warning naming the assumed unit when a CRS is present but
  its unit is not recognised).
- PLY, XYZ/CSV/TXT/PTS, NIST ``.ds`` and ``.npy`` carry no unit: millimetres.
"""

from __future__ import annotations

from typing import Optional

from ..errors import InvalidInputError

MM_PER_UNIT = {
    "mm": 1.0,
    "cm": 10.0,
    "m": 1000.0,
    "um": 1e-3,
    "in": 25.4,
    "ft": 304.8,
    "us-ft": 1200.0 / 3937.0 * 1000.0,
}

#: the names ``--units`` and ``units=`` accept
UNIT_NAMES = ("mm", "cm", "m", "um", "in", "ft")

_ALIASES = {"µm": "um", "μm": "um", "micron": "um", "inch": "in", "foot": "ft", "feet": "ft", "metre": "m", "meter": "m"}


def scale_to_mm(unit: str) -> float:
    """Millimetres per ``unit`` (a name of :data:`MM_PER_UNIT`)."""
    return MM_PER_UNIT[unit]


def check_units(units: Optional[str]) -> Optional[str]:
    """Normalise a user-given unit name; ``None`` stays ``None`` (the file's own unit).

    Raises :class:`~gagekit.errors.InvalidInputError` for an unknown name.
    """
    if units is None:
        return None
    if not isinstance(units, str):
        raise InvalidInputError(f"units must be one of {', '.join(UNIT_NAMES)}, got {units!r}")
    name = units.strip()
    name = _ALIASES.get(name.lower(), name.lower())
    if name not in MM_PER_UNIT:
        raise InvalidInputError(f"unknown unit {units!r}; choose one of {', '.join(UNIT_NAMES)}")
    return name
