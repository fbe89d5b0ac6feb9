"""Circular tests with a telescoping ballbar, ISO 230-4:2022.

The run file (CSV, UTF-8, ``#`` comment lines allowed) has the header
``angle_deg,deviation_um,direction``: one row per reading, ``angle_deg`` the commanded angle of
the ball on its circle, measured from the plane's first axis towards its second (XY: from +X
towards +Y; YZ: from +Y towards +Z; ZX: from +Z towards +X), ``deviation_um`` the measured
minus the nominal ballbar length (um), ``direction`` ``ccw`` (counter-clockwise: the angle
increases) or ``cw``. Both directions in one file, or one. Overrun arcs may stay in the file
(angles beyond 360 deg are taken modulo 360). No public, documented ballbar text export was
found to read besides this layout (vendor software stores its own formats); convert exports to
these three columns.

Results (the kernel: ``rust/kinematics/src/ballbar.rs``), all in um unless named otherwise:

- ``circular_deviation_um`` G (ISO 230-4:2022 3.2.2): radial width of the path about its
  least-squares centre: ``ccw``, ``cw`` and ``both`` (the path of both runs together).
- ``radial_deviation_um`` F (3.2.3): ``max`` and ``min`` of the deviations about the pivot.
- ``hysteresis_um`` H (3.2.4): the largest radial difference of the two runs at one angle.
- ``centre_offset_um``: the least-squares centre relative to the pivot, per run and both.
- ``squareness_um_per_m``: from the sin 2theta term common to both runs; positive when the
  included angle of the plane's +first and +second axes is below 90 deg (the second axis leans
  towards the first).
- ``scale_mismatch_um_per_m``: from the cos 2theta term, the first axis's scale minus the
  second's (positive: the first axis travels further).
- ``servo_mismatch_ms`` (with ``--feed``): from the sin 2theta term that changes sign with the
  direction; positive when the second axis trails the first. Without the feed, only
  ``servo_lag_um`` (how far it trails along the path).
- ``backlash_um``: lost motion per axis and run (an outward step of that size where the axis
  reverses).
- ``cyclic_error_um``: amplitude per axis of a cyclic error of ``pitch_mm`` (given, or the pitch
  that explains most).
- ``reversal_spikes_um``: per axis, at its positive and negative end, the largest residual
  near the reversal.

Each diagnostic carries ``fraction_of_G``: (G - G without that term) / G, both runs together
(negative when the term partly cancels others: removing it widens the path).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

import numpy as np

from .. import _core
from ..errors import FileFormatError, InvalidInputError

__all__ = ["BallbarRun", "BallbarResult", "read_ballbar", "analyse_ballbar", "PLANES", "group_sensitivities",
           "circle_commands", "radial_rows"]

#: The planes of ISO 230-4 and their (first, second) axes.
PLANES = {"XY": ("X", "Y"), "YZ": ("Y", "Z"), "ZX": ("Z", "X")}
_CCW = {"ccw", "counterclockwise", "counter-clockwise", "+"}
_CW = {"cw", "clockwise", "-"}


@dataclass(frozen=True)
class BallbarRun:
    """Readings of a ballbar test: angles (deg), deviations (um), directions (+1 ccw, -1 cw)."""

    angles_deg: np.ndarray
    deviations_um: np.ndarray
    directions: np.ndarray
    source: Optional[str] = None

    def __len__(self) -> int:
        return int(self.angles_deg.shape[0])


def read_ballbar(path: Union[str, Path]) -> BallbarRun:
    """Read a run CSV (``angle_deg,deviation_um,direction``); errors name the line."""
    from .._files import csv_rows, read_text

    p = Path(path)
    text = read_text(p, "ballbar run")
    header: Optional[list[str]] = None
    angles, devs, dirs = [], [], []
    for lineno, row in csv_rows(text, p):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in row]
        if header is None:
            header = [c.lower() for c in cells]
            missing = [c for c in ("angle_deg", "deviation_um", "direction") if c not in header]
            if missing:
                raise FileFormatError(
                    f"{p}, line {lineno}: missing column(s) {', '.join(missing)} (header must be angle_deg,deviation_um,direction)"
                )
            idx = [header.index(c) for c in ("angle_deg", "deviation_um", "direction")]
            continue
        if len(cells) != len(header):
            raise FileFormatError(f"{p}, line {lineno}: {len(cells)} values for {len(header)} columns")
        a, d, s = (cells[i] for i in idx)
        try:
            av, dv = float(a), float(d)
        except ValueError:
            raise FileFormatError(f"{p}, line {lineno}: angle_deg and deviation_um must be numbers, got {a!r}, {d!r}") from None
        if not (math.isfinite(av) and math.isfinite(dv)):
            raise InvalidInputError(f"{p}, line {lineno}: non-finite angle or deviation")
        if abs(av) > 1e6:
            raise InvalidInputError(f"{p}, line {lineno}: angle {av} deg is out of range")
        sl = s.lower()
        if sl in _CCW:
            dirs.append(1)
        elif sl in _CW:
            dirs.append(-1)
        else:
            raise FileFormatError(f"{p}, line {lineno}: direction must be cw or ccw, got {s!r}")
        angles.append(av)
        devs.append(dv)
    if header is None:
        raise FileFormatError(f"{p}: empty file (expected the header angle_deg,deviation_um,direction)")
    if not angles:
        raise FileFormatError(f"{p}: no readings after the header")
    return BallbarRun(np.array(angles), np.array(devs), np.array(dirs, dtype=np.int8), str(p))


@dataclass(frozen=True)
class BallbarResult:
    """The ISO 230-4 figures and diagnostics of one ballbar test (see the module's doc)."""

    plane: str
    radius_mm: float
    feed_mm_per_min: Optional[float]
    n_readings: dict
    raw: object  # gagekit._core.kinematics.BallbarAnalysis
    run: BallbarRun
    pitch_given: bool = False

    @property
    def axes(self) -> tuple[str, str]:
        return PLANES[self.plane]

    @property
    def circular_deviation_um(self) -> float:
        """G of both runs together, um."""
        return 1e3 * self.raw.both.g

    def residual_paths(self) -> dict:
        """{direction: (angles deg, radial deviation about the common LS centre, um)} for plots."""
        c = np.array(self.raw.both.centre)
        out = {}
        t = np.radians(self.run.angles_deg)
        u = np.stack([np.cos(t), np.sin(t)], axis=1)
        a = self.radius_mm + 1e-3 * self.run.deviations_um
        r = np.linalg.norm(a[:, None] * u - c, axis=1) - self.radius_mm
        for name, s in (("ccw", 1), ("cw", -1)):
            k = self.run.directions == s
            if k.any():
                out[name] = (self.run.angles_deg[k], 1e3 * r[k])
        return out

    def to_dict(self) -> dict:
        b = self.raw
        ax1, ax2 = self.axes
        g = b.both.g
        um = 1e3

        def circle(c) -> dict:
            return {"x": um * c.centre[0], "y": um * c.centre[1]}

        runs = {k: getattr(b, k) for k in ("ccw", "cw") if getattr(b, k) is not None}
        frac = lambda f: float(f)  # noqa: E731
        d = {
            "standard": "ISO 230-4:2022",
            "plane": self.plane,
            "axes": [ax1, ax2],
            "radius_mm": self.radius_mm,
            "n_readings": self.n_readings,
            "circular_deviation_um": {**{k: um * c.g for k, c in runs.items()}, "both": um * g},
            "radial_deviation_um": {"max": um * b.f_max, "min": um * b.f_min},
            "centre_offset_um": {**{k: circle(c) for k, c in runs.items()}, "both": circle(b.both),
                                 "fraction_of_G": frac(b.centre_fraction),
                                 "axes": "x along the first axis of the plane, y along the second"},
            "radius_deviation_um": um * b.both.radius_deviation,
            "squareness_um_per_m": {
                "value": 1e6 * b.squareness,
                "fraction_of_G": frac(b.squareness_fraction),
                "sign": f"positive: the angle between +{ax1} and +{ax2} is less than 90 deg ({ax2} leans towards +{ax1})",
            },
            "scale_mismatch_um_per_m": {
                "value": 1e6 * b.scale_mismatch,
                "fraction_of_G": frac(b.scale_fraction),
                "sign": f"{ax1} scale minus {ax2} scale (positive: {ax1} travels further)",
            },
            "backlash_um": {
                ax: {
                    **{run: um * v for run, v in zip(("ccw", "cw"), b.backlash[k]) if v is not None},
                    "fraction_of_G": frac(b.backlash_fraction[k]),
                }
                for k, ax in enumerate((ax1, ax2))
            },
            "reversal_spikes_um": {
                ax: {"positive_end": um * b.spikes[k][0], "negative_end": um * b.spikes[k][1]} for k, ax in enumerate((ax1, ax2))
            },
            "residual_rms_um": um * b.residual_rms,
        }
        if b.hysteresis is not None:
            d["hysteresis_um"] = um * b.hysteresis
        if b.cyclic is not None:
            d["cyclic_error_um"] = {
                "pitch_mm": float(b.pitch),
                "pitch_source": "given" if self.pitch_given else "searched (largest explained share)",
                **{ax: {"amplitude": um * b.cyclic[k], "fraction_of_G": frac(b.cyclic_fraction[k])} for k, ax in enumerate((ax1, ax2))},
            }
        if b.servo_lag is not None:
            d["servo_lag_um"] = {"value": um * b.servo_lag, "fraction_of_G": frac(b.servo_fraction),
                                 "sign": f"positive: {ax2} trails {ax1}"}
            if b.servo_mismatch is not None:
                d["servo_mismatch_ms"] = {
                    "value": 1e3 * b.servo_mismatch,
                    "feed_mm_per_min": self.feed_mm_per_min,
                    "fraction_of_G": frac(b.servo_fraction),
                    "sign": f"positive: {ax2} lags {ax1}",
                }
        return d


def analyse_ballbar(
    run: BallbarRun,
    plane: str,
    radius: float,
    feed: Optional[float] = None,
    pitch: Optional[float] = None,
) -> BallbarResult:
    """ISO 230-4 figures and diagnostics of a ballbar test (radius mm, feed mm/min, pitch mm)."""
    pl = plane.upper() if isinstance(plane, str) else plane
    if pl not in PLANES:
        raise InvalidInputError(f"plane must be XY, YZ or ZX, got {plane!r}")
    for name, v in (("radius", radius), ("feed", feed), ("pitch", pitch)):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise InvalidInputError(f"{name} must be a positive number, got {v}")
    raw = _core.kinematics.ballbar(
        float(radius),
        np.ascontiguousarray(np.radians(run.angles_deg)),
        np.ascontiguousarray(1e-3 * run.deviations_um),
        np.ascontiguousarray(run.directions, dtype=np.int8),
        pitch=pitch,
        feed=feed,
    )
    counts = {"ccw": int((run.directions == 1).sum()), "cw": int((run.directions == -1).sum())}
    return BallbarResult(pl, float(radius), feed, {k: v for k, v in counts.items() if v}, raw, run, pitch is not None)


def group_sensitivities(machine, plane: str, radius: float, at: dict, min_share: float = 0.01) -> dict:
    """Which identifiable groups (Eq. 3.14) a ballbar circle's squareness and scale mismatch
    stand for, at the centre commands ``at`` (every joint): for each group, the squareness
    (um/m) and scale mismatch (um/m) a unit value of it produces on this circle (first order:
    the radial effect u . (M_i - M_centre) g projected on sin 2theta and cos 2theta). Groups
    whose effect at Table 3.3's typical sizes is below ``min_share`` of the largest are left out. A ballbar test updates a
    calibration through these groups (or as an observation file of ``machine identify``)."""
    pl = plane.upper()
    if pl not in PLANES:
        raise InvalidInputError(f"plane must be XY, YZ or ZX, got {plane!r}")
    names = machine.joint_names
    centre = machine.position(at, "--at")
    for x in PLANES[pl]:
        if x not in names:
            raise InvalidInputError(f"machine '{machine.name}' has no joints {' and '.join(PLANES[pl])} for plane {pl}")
    st = machine.structure()
    t = np.radians(np.arange(0.0, 360.0, 5.0))
    cmds = circle_commands(machine, pl, radius, centre, t)
    rows, _ = radial_rows(machine, cmds, st.reduce(machine.design_matrix(cmds)))  # radial effect of each group
    sq = 2.0 / len(t) * np.sin(2 * t) @ rows * 2.0 / radius * 1e6  # um/m per unit group
    sc = 2.0 / len(t) * np.cos(2 * t) @ rows * 2.0 / radius * 1e6
    from .simulate import typical_magnitudes

    typical = typical_magnitudes(machine)[list(st.leaders)]  # Table 3.3 sizes: compare effects, not units
    out = {}
    for label, v in (("squareness_um_per_m", sq), ("scale_mismatch_um_per_m", sc)):
        size = np.abs(v) * typical
        big = size.max()
        out[label] = {g.name: float(x) for g, x, e in zip(st.groups, v, size) if big > 0 and e >= min_share * big}
    return out


def circle_commands(machine, plane: str, radius: float, centre: np.ndarray, angles_rad: np.ndarray) -> np.ndarray:
    """Commands of a ballbar circle: ``centre`` (every joint) with the plane's joints moved by
    radius (cos, sin) at each angle, and the centre itself as the last row."""
    names = machine.joint_names
    a, b = (names.index(x) for x in PLANES[plane])
    cmds = np.repeat(np.asarray(centre, dtype=np.float64)[None, :], len(angles_rad) + 1, axis=0)
    cmds[:-1, a] += radius * np.cos(angles_rad)
    cmds[:-1, b] += radius * np.sin(angles_rad)
    return cmds


def radial_rows(machine, commands: np.ndarray, design: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First-order change of the ballbar length for the circle ``commands`` (centre last):
    u_i . (M_i - M_centre) with u_i the nominal direction from the pivot, (n, k) for the columns
    of ``design`` (3(n+1), k); and the nominal lengths (n,)."""
    nom = machine.nominal(commands)
    m3 = np.asarray(design).reshape(len(commands), 3, -1)
    d = nom[:-1] - nom[-1]
    length = np.linalg.norm(d, axis=1)
    u = d / length[:, None]
    return np.einsum("ni,nik->nk", u, m3[:-1] - m3[-1][None]), length
