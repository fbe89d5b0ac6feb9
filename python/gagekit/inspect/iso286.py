"""ISO 286-1:2010 limits and fits: ``"20 H7"`` -> the limit deviations of a hole or shaft.

Holds the standard's Table 1 (standard tolerance grades IT1-IT18, nominal sizes up to
500 mm) and its fundamental deviations (Tables 2-3) for the shaft letters d, e, f, g, h,
js, k, m, n, p, r, s and the hole letters D, E, F, G, H, JS, K, M, N, P, R, S, with the
rules of ISO 286-1 Sec. 5.3 that derive the holes from the shafts:

- D ... H: EI = -es of the shaft of the same letter (Sec. 5.3.2.1, general rule);
- K, M, N up to IT8 and P ... S up to IT7: ES = -ei + Delta, Delta = IT_n - IT_(n-1)
  (the special rule, Sec. 5.3.2.2); above those grades ES = -ei (K and N: ES = 0);
- JS, js: +-IT/2.

The grade values are the standard's rounded table values; :func:`it_formula` gives the
unrounded formula they come from (standard tolerance factor i = 0.45 D^(1/3) + 0.001 D,
D the geometric mean of the range's limits, IT5 ... IT18 = 7 i ... 2500 i), which the
tests check the table against. Nominal sizes above 500 mm raise ConfigError.
"""

from __future__ import annotations

import math
import re

from ..errors import ConfigError

__all__ = ["fit_deviations", "it_value", "it_formula", "RANGES"]

#: Upper limits (mm) of the nominal size ranges of Table 1 (each range is (previous, upper]).
RANGES = (3, 6, 10, 18, 30, 50, 80, 120, 180, 250, 315, 400, 500)

# IT1 ... IT11 in micrometres, IT12 ... IT18 in millimetres (as the standard prints them)
_IT_UM = {
    1: (0.8, 1, 1, 1.2, 1.5, 1.5, 2, 2.5, 3.5, 4.5, 6, 7, 8),
    2: (1.2, 1.5, 1.5, 2, 2.5, 2.5, 3, 4, 5, 7, 8, 9, 10),
    3: (2, 2.5, 2.5, 3, 4, 4, 5, 6, 8, 10, 12, 13, 15),
    4: (3, 4, 4, 5, 6, 7, 8, 10, 12, 14, 16, 18, 20),
    5: (4, 5, 6, 8, 9, 11, 13, 15, 18, 20, 23, 25, 27),
    6: (6, 8, 9, 11, 13, 16, 19, 22, 25, 29, 32, 36, 40),
    7: (10, 12, 15, 18, 21, 25, 30, 35, 40, 46, 52, 57, 63),
    8: (14, 18, 22, 27, 33, 39, 46, 54, 63, 72, 81, 89, 97),
    9: (25, 30, 36, 43, 52, 62, 74, 87, 100, 115, 130, 140, 155),
    10: (40, 48, 58, 70, 84, 100, 120, 140, 160, 185, 210, 230, 250),
    11: (60, 75, 90, 110, 130, 160, 190, 220, 250, 290, 320, 360, 400),
}
_IT_MM = {
    12: (0.1, 0.12, 0.15, 0.18, 0.21, 0.25, 0.3, 0.35, 0.4, 0.46, 0.52, 0.57, 0.63),
    13: (0.14, 0.18, 0.22, 0.27, 0.33, 0.39, 0.46, 0.54, 0.63, 0.72, 0.81, 0.89, 0.97),
    14: (0.25, 0.3, 0.36, 0.43, 0.52, 0.62, 0.74, 0.87, 1.0, 1.15, 1.3, 1.4, 1.55),
    15: (0.4, 0.48, 0.58, 0.7, 0.84, 1.0, 1.2, 1.4, 1.6, 1.85, 2.1, 2.3, 2.5),
    16: (0.6, 0.75, 0.9, 1.1, 1.3, 1.6, 1.9, 2.2, 2.5, 2.9, 3.2, 3.6, 4.0),
    17: (1.0, 1.2, 1.5, 1.8, 2.1, 2.5, 3.0, 3.5, 4.0, 4.6, 5.2, 5.7, 6.3),
    18: (1.4, 1.8, 2.2, 2.7, 3.3, 3.9, 4.6, 5.4, 6.3, 7.2, 8.1, 8.9, 9.7),
}
_FACTOR = {5: 7, 6: 10, 7: 16, 8: 25, 9: 40, 10: 64, 11: 100, 12: 160, 13: 250, 14: 400, 15: 640, 16: 1000, 17: 1600,
           18: 2500}

# shaft upper deviations es (um), Table 3: d ... h
_ES = {
    "d": (-20, -30, -40, -50, -65, -80, -100, -120, -145, -170, -190, -210, -230),
    "e": (-14, -20, -25, -32, -40, -50, -60, -72, -85, -100, -110, -125, -135),
    "f": (-6, -10, -13, -16, -20, -25, -30, -36, -43, -50, -56, -62, -68),
    "g": (-2, -4, -5, -6, -7, -9, -10, -12, -14, -15, -17, -18, -20),
    "h": (0,) * 13,
}
# shaft lower deviations ei (um), Table 3: k (IT4 ... IT7), m, n, p
_EI = {
    "k": (0, 1, 1, 1, 2, 2, 2, 3, 3, 4, 4, 4, 5),
    "m": (2, 4, 6, 7, 8, 9, 11, 13, 15, 17, 20, 21, 23),
    "n": (4, 8, 10, 12, 15, 17, 20, 23, 27, 31, 34, 37, 40),
    "p": (6, 12, 15, 18, 22, 26, 32, 37, 43, 50, 56, 62, 68),
}
# r and s: subdivided ranges above 50 mm (upper limits, ei um)
_EI_SUB = {
    "r": ((3, 10), (6, 15), (10, 19), (18, 23), (30, 28), (50, 34), (65, 41), (80, 43), (100, 51), (120, 54), (140, 63),
          (160, 65), (180, 68), (200, 77), (225, 80), (250, 84), (280, 94), (315, 98), (355, 108), (400, 114), (450, 126),
          (500, 132)),
    "s": ((3, 14), (6, 19), (10, 23), (18, 28), (30, 35), (50, 43), (65, 53), (80, 59), (100, 71), (120, 79), (140, 92),
          (160, 100), (180, 108), (200, 122), (225, 130), (250, 140), (280, 158), (315, 170), (355, 190), (400, 208),
          (450, 232), (500, 252)),
}

_FIT = re.compile(r"^\s*([A-Za-z]{1,2})\s*(\d{1,2})\s*$")


def _range_index(nominal: float, where: str) -> int:
    if not (0.0 < nominal <= RANGES[-1]):
        raise ConfigError(f"{where}: the ISO 286 tables here cover nominal sizes in (0, 500] mm; got {nominal:g} "
                          "(give 'upper' and 'lower' instead)")
    for k, hi in enumerate(RANGES):
        if nominal <= hi:
            return k
    raise AssertionError  # pragma: no cover


def it_value(grade: int, nominal: float, where: str = "fit") -> float:
    """The standard tolerance IT``grade`` (mm) for a nominal size (mm), ISO 286-1 Table 1."""
    k = _range_index(nominal, where)
    if grade in _IT_UM:
        return _IT_UM[grade][k] / 1000.0
    if grade in _IT_MM:
        return _IT_MM[grade][k]
    raise ConfigError(f"{where}: tolerance grade IT{grade} is not tabulated here; use IT1 ... IT18")


def it_formula(grade: int, range_index: int) -> float:
    """The unrounded IT5 ... IT18 (um) of a range: the factor times i = 0.45 D^(1/3) +
    0.001 D, D the geometric mean of the range's limits (ISO 286-1 Sec. 5.1)."""
    lo = 1.0 if range_index == 0 else RANGES[range_index - 1]  # the first range's D uses 1 and 3
    D = math.sqrt(lo * RANGES[range_index])
    return _FACTOR[grade] * (0.45 * D ** (1.0 / 3.0) + 0.001 * D)


def _shaft_ei(letter: str, nominal: float, k: int) -> float:
    if letter in _EI:
        return _EI[letter][k]
    for hi, v in _EI_SUB[letter]:
        if nominal <= hi:
            return v
    raise AssertionError  # pragma: no cover


def fit_deviations(fit: str, nominal: float, where: str = "fit") -> tuple[float, float]:
    """(upper, lower) limit deviations (mm) of the tolerance class ``fit`` (``"H7"``: a
    hole, upper-case; ``"g6"``: a shaft) at the nominal size (mm).

    >>> fit_deviations("H7", 20.0)
    (0.021, 0.0)
    >>> fit_deviations("g6", 20.0)
    (-0.007, -0.02)
    """
    m = _FIT.match(str(fit))
    if not m:
        raise ConfigError(f"{where}: 'fit' = {fit!r} is not a tolerance class like \"H7\" or \"g6\"")
    letter, grade = m.group(1), int(m.group(2))
    k = _range_index(nominal, where)
    it_um = it_value(grade, nominal, where) * 1000.0
    hole = letter[0].isupper()
    low = letter.lower()
    if letter not in ("JS", "js") and (letter != letter.upper() and letter != letter.lower()):
        raise ConfigError(f"{where}: 'fit' = {fit!r} mixes cases; holes are upper-case (H7), shafts lower-case (g6)")
    known = set(_ES) | set(_EI) | set(_EI_SUB) | {"js"}
    if low not in known:
        raise ConfigError(f"{where}: 'fit' = {fit!r}: fundamental deviation {letter!r} is not tabulated here; "
                          f"use one of {', '.join(sorted(known))} (upper-case for holes)")
    if low == "js":
        up, lo = it_um / 2.0, -it_um / 2.0
    elif not hole:
        if low in _ES:
            up = float(_ES[low][k])
            lo = up - it_um
        else:
            if low == "k" and not (4 <= grade <= 7):
                ei = 0.0  # k up to IT3 and above IT7: ei = 0 (ISO 286-1 Table 3)
            else:
                ei = float(_shaft_ei(low, nominal, k))
            lo, up = ei, ei + it_um
    else:
        if low in _ES:
            lo = -float(_ES[low][k])
            up = lo + it_um
        else:
            ei = float(_shaft_ei(low, nominal, k)) if not (low == "k" and nominal <= 3) else 0.0
            special = grade <= 8 if low in ("k", "m", "n") else grade <= 7
            if special and grade >= 2:
                delta = it_value(grade, nominal, where) * 1000.0 - it_value(grade - 1, nominal, where) * 1000.0
                up = -ei + delta
            elif low in ("k", "n"):
                up = 0.0
            else:
                up = -ei
            lo = up - it_um
    return round(up / 1000.0, 7) + 0.0, round(lo / 1000.0, 7) + 0.0  # + 0.0: no -0.0
