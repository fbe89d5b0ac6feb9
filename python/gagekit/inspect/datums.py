"""Datum simulation and the datum reference frame (ISO 5459:2011).

**Datum features.** Each datum letter is simulated in the order of the feature control
frame, every datum constrained by those before it (ISO 5459 Sec. 6.3, the dissertation's
Eqs. 5.13-5.15):

- a **plane** datum is the tangent plane on the air side that minimises the largest
  distance to the feature's points (constrained Chebyshev, the ISO 5459 default):
  primary -- free (the outer plane of the minimum zone); secondary -- perpendicular to the
  primary plane (or at the basic angle given as ``B = { feature = ..., angle = 60 }``),
  or perpendicular to a primary datum axis; tertiary -- perpendicular to both (only its
  offset is fitted) or, after a plane and an axis, perpendicular to the primary (it fixes
  the rotation about the axis);
- an **axis** datum (cylinder, cone, circle) is the axis of the maximum inscribed
  cylinder of a hole and of the minimum circumscribed cylinder of a shaft (ISO 5459
  Sec. B.3); as primary its direction is free (for a circle: its least-squares normal;
  a cone's datum axis is its least-squares axis), after a datum plane it is perpendicular
  to that plane (the 2-D maximum inscribed / minimum circumscribed circle of the points
  projected along the plane's normal, exact) or, given as ``D = { feature = ..., angle =
  60 }``, at that basic angle to the plane, free to turn about its normal (the best
  cylinder over the turn, searched in one kernel call, ``gagekit_gdt::turn::axis_on_cone``:
  a grid of the turn within 10 degrees of the least-squares axis's, golden-section
  refinement to machine precision of the turn; each value the exact fixed-direction
  cylinder; the axis's lean then fixes the frame's x);
- ``datum_fit = "least-squares"`` replaces each criterion by least squares.

**Datum frame.** z: the primary plane's normal into the material, or the primary axis
(then, if a later plane datum is perpendicular to the axis, that plane's normal into the
material). The next plane datum not parallel to z gives y when it is the secondary
behind a primary plane (the dissertation's 3-2-1 convention, Sec. 5.4.1: primary = XY,
secondary = XZ, tertiary = YZ), x otherwise; a tertiary axis after a plane and an axis
gives x from the secondary axis to the tertiary one. Every plane datum's axis points
into the material, so a frame can be left-handed (``right_handed`` says so); a missing
axis is completed by the right-hand rule. The origin satisfies every datum's location
constraint (Eq. 5.16); what the datums leave free -- translations and the rotation about
z -- is reported as ``free`` and each location tolerance optimises over it (ISO 1101
Sec. 7: the degrees of freedom a datum system does not lock are free). When the rotation
about z is free, x is the primary feature's region box x axis projected normal to z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import ConfigError
from ..form import fit_sphere
from .features import FeatureData, _unit
from .spec import DatumRef, PartSpec

__all__ = ["SimulatedDatum", "DatumFrame", "DatumSystem"]

#: A secondary / tertiary datum more than this far (degrees) from its constrained
#: orientation is a mistake in the drawing (e.g. a secondary plane parallel to the primary).
MAX_MISALIGN_DEG = 30.0


@dataclass(frozen=True)
class SimulatedDatum:
    """A simulated datum: a plane (``point``, ``vector`` = normal out of the material), an
    axis (``point``, ``vector`` = direction) or a point (a sphere's centre; ``vector`` 0). ``precedence``: the datums it was
    constrained by. ``radius``: the fitted cylinder's radius (axes); ``deviation``: the
    largest distance of the feature's points from a datum plane."""

    letter: str
    feature: str
    type: str
    method: str
    point: np.ndarray
    vector: np.ndarray
    precedence: tuple[str, ...]
    radius: Optional[float] = None
    deviation: Optional[float] = None

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"letter": self.letter, "feature": self.feature, "type": self.type, "method": self.method,
                             "constrained_by": list(self.precedence), "point": self.point.tolist()}
        if self.type != "point":
            d["normal" if self.type == "plane" else "direction"] = self.vector.tolist()
        if self.radius is not None:
            d["radius"] = self.radius
        if self.deviation is not None:
            d["deviation"] = self.deviation
        return d


@dataclass(frozen=True)
class DatumFrame:
    """The datum reference frame: ``origin`` and ``axes`` (rows x, y, z; unit, orthogonal),
    in the scan's frame; ``free_translations`` (orthonormal rows) and ``free_rotation``
    (about z) are the motions the datums leave free."""

    datums: tuple[str, ...]
    origin: np.ndarray
    axes: np.ndarray
    free_translations: np.ndarray
    free_rotation: bool

    @property
    def right_handed(self) -> bool:
        return bool(np.linalg.det(self.axes) > 0)

    def point_to_scan(self, p: Any) -> np.ndarray:
        return self.origin + np.asarray(p, dtype=float) @ self.axes

    def direction_to_scan(self, d: Any) -> np.ndarray:
        return _unit(np.asarray(d, dtype=float) @ self.axes)

    def to_frame(self, p: Any) -> np.ndarray:
        """Scan coordinates -> datum-frame coordinates."""
        return (np.asarray(p, dtype=float) - self.origin) @ self.axes.T

    def kernel_args(self) -> tuple:
        """The frame as the turn-search kernels take it: (origin, (x, y, z), free
        translations, free rotation)."""
        return (tuple(self.origin), tuple(tuple(a) for a in self.axes), [tuple(t) for t in self.free_translations],
                self.free_rotation)

    def to_dict(self) -> dict[str, Any]:
        return {"datums": list(self.datums), "origin": self.origin.tolist(), "axes": {k: self.axes[i].tolist() for i, k in enumerate("xyz")},
                "right_handed": self.right_handed,
                "free": {"translations": self.free_translations.tolist(), "rotation_about_z": self.free_rotation}}


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(min(1.0, abs(float(a @ b)))))


class DatumSystem:
    """Simulates datums on demand and caches them by precedence (a datum constrained by
    A differs from the same feature constrained by D)."""

    def __init__(self, spec: PartSpec, feats: dict[str, FeatureData]) -> None:
        self.spec = spec
        self.feats = feats
        self._sims: dict[tuple[str, ...], SimulatedDatum] = {}
        self._frames: dict[tuple[str, ...], DatumFrame] = {}

    def simulated(self) -> list[SimulatedDatum]:
        return list(self._sims.values())

    def datum(self, letters: tuple[str, ...]) -> SimulatedDatum:
        """The last datum of ``letters``, constrained by the ones before it."""
        if letters not in self._sims:
            prior = [self.datum(letters[:k]) for k in range(1, len(letters))]
            self._sims[letters] = self._simulate(self.spec.datums[letters[-1]], prior, letters[:-1])
        return self._sims[letters]

    def chain(self, letters: tuple[str, ...]) -> list[SimulatedDatum]:
        return [self.datum(letters[: k + 1]) for k in range(len(letters))]

    # -- simulation ----------------------------------------------------------------------
    def _simulate(self, ref: DatumRef, prior: list[SimulatedDatum], before: tuple[str, ...]) -> SimulatedDatum:
        fd = self.feats[ref.feature]
        where = f"{self.spec.source}: datum {ref.letter} (feature '{fd.name}')"
        if fd.shape == "plane":
            return self._plane(ref, fd, prior, before, where)
        if fd.shape == "sphere":
            return self._point(ref, fd, before)
        return self._axis(ref, fd, prior, before, where)

    def _point(self, ref, fd: FeatureData, before) -> SimulatedDatum:
        """A datum point: the centre of the maximum inscribed sphere of a spherical hole, of
        the minimum circumscribed sphere of a ball (ISO 5459 Sec. B.3: the associated
        sphere), or of the least-squares sphere; both Chebyshev spheres are exact / certified
        global (:func:`gagekit.form.fit_sphere`). A datum point is not constrained by
        the datums before it (a sphere has no orientation)."""
        if fd.spec.datum_fit == "least-squares":
            crit, name = "least-squares", "least-squares sphere"
        elif fd.spec.kind == "hole":
            crit, name = "max-inscribed", "maximum inscribed sphere"
        else:
            crit, name = "min-circumscribed", "minimum circumscribed sphere"
        s = fd.lsq() if crit == "least-squares" else fit_sphere(fd.points, crit)
        return SimulatedDatum(ref.letter, fd.name, "point", f"centre of the {name}", np.array(s.center), np.zeros(3), before,
                              radius=float(s.radius))

    def _plane(self, ref, fd: FeatureData, prior, before, where) -> SimulatedDatum:
        out = np.asarray(fd.spec.outward, dtype=float)
        out = out / np.linalg.norm(out)
        n_ls = fd.plane_normal_out()
        if _angle_deg(n_ls, out) > 60.0:
            raise ConfigError(f"{where}: its 'outward' is {_angle_deg(n_ls, out):.0f} degrees from the face's normal; "
                              "give the direction from the material into the air")
        mode, axis, angle = "free", (0.0, 0.0, 1.0), 0.0
        if len(prior) == 1 and prior[0].type == "plane":
            a = prior[0].vector
            got = math.degrees(math.acos(min(1.0, abs(float(n_ls @ a)))))
            want = ref.angle
            if got < 5.0:
                raise ConfigError(f"{where}: the secondary datum plane is parallel to the primary datum "
                                  f"{prior[0].letter} ({got:.1f} degrees apart); a secondary plane must be at an angle to it")
            if abs(got - want) > MAX_MISALIGN_DEG:
                raise ConfigError(f"{where}: the plane is {got:.0f} degrees from the primary datum {prior[0].letter}, "
                                  f"but its basic angle is {want:g} degrees (set it as {ref.letter} = {{ feature = \"{fd.name}\", angle = ... }})")
            if want == 90.0:
                mode, axis = "perpendicular", tuple(a)
            else:
                s = 1.0 if float(n_ls @ a) >= 0 else -1.0
                mode, axis, angle = "angle", tuple(s * a), math.radians(want)
        elif len(prior) == 1 and prior[0].type == "axis":
            a = prior[0].vector
            if _angle_deg(n_ls, a) > MAX_MISALIGN_DEG:
                raise ConfigError(f"{where}: a plane datum behind the datum axis {prior[0].letter} must be perpendicular "
                                  f"to it; this one's normal is {_angle_deg(n_ls, a):.0f} degrees from the axis")
            mode, axis = "fixed", tuple(a)
        elif len(prior) == 2:
            t = (prior[0].type, prior[1].type)
            if t == ("plane", "plane"):
                n = np.cross(prior[0].vector, prior[1].vector)
                n = n / np.linalg.norm(n)
                if _angle_deg(n_ls, n) > MAX_MISALIGN_DEG:
                    raise ConfigError(f"{where}: the tertiary datum plane must be perpendicular to datums "
                                      f"{prior[0].letter} and {prior[1].letter}; it is {_angle_deg(n_ls, n):.0f} degrees off")
                mode, axis = "fixed", tuple(n)
            elif t == ("plane", "axis"):
                mode, axis = "perpendicular", tuple(prior[0].vector)
            elif t == ("axis", "plane"):
                mode, axis = "perpendicular", tuple(prior[0].vector)
            else:
                raise ConfigError(f"{where}: a tertiary plane after two datum axes is not supported")
        pts = fd.points
        fit = fd.spec.datum_fit
        label = mode
        if mode == "free" and fit == "chebyshev":
            # the free Chebyshev tangent plane has the minimum-zone normal (shared with flatness)
            mode, axis = "fixed", tuple(fd.min_zone()[1])
        point, normal, _, dev = _core.gdt_datum_plane(pts, tuple(out), mode, axis, angle, fit)
        mode = label
        method = ("chebyshev tangent plane" if fit == "chebyshev" else "least-squares plane") + ("" if mode == "free" else f", {mode}")
        return SimulatedDatum(ref.letter, fd.name, "plane", method, np.array(point), np.array(normal), before, deviation=float(dev))

    def _axis(self, ref, fd: FeatureData, prior, before, where) -> SimulatedDatum:
        kind = fd.spec.kind
        fit = "least-squares" if fd.spec.datum_fit == "least-squares" else ("inscribed" if kind == "hole" else "circumscribed")
        p_ls, d_ls = fd.axis_line()
        planes = [p for p in prior if p.type == "plane"]
        if prior and prior[0].type == "axis":
            raise ConfigError(f"{where}: a datum axis behind the datum axis {prior[0].letter} is not supported; "
                              "use a plane perpendicular to it as the secondary datum")
        if planes:
            a = planes[0].vector
            tilt = 90.0 - ref.angle  # basic angle between the axis and the plane's normal
            got = _angle_deg(d_ls, a)
            if abs(got - tilt) > MAX_MISALIGN_DEG:
                how = "perpendicular to it" if ref.angle == 90.0 else f"at its basic angle of {ref.angle:g} degrees to it"
                raise ConfigError(f"{where}: a datum axis behind the datum plane {planes[0].letter} is taken "
                                  f"{how}; this axis is {90.0 - got:.0f} degrees from the plane "
                                  f"(set it as {ref.letter} = {{ feature = \"{fd.name}\", angle = ... }})")
            d0 = a if float(a @ d_ls) >= 0 else -a
            kind_name = {"inscribed": "maximum inscribed", "circumscribed": "minimum circumscribed"}.get(fit, "least-squares")
            kind_name += f" {'cylinder' if fd.shape != 'circle' else 'circle'}"
            if ref.angle == 90.0:
                point, direction, radius, _, _ = _core.gdt_axis_along(fd.points, tuple(d0), fit)
                method = f"{kind_name}, perpendicular to {planes[0].letter}"
            else:
                # free to turn about the plane's normal: the best cylinder over the turn (one kernel search)
                point, direction, radius, _, _ = _core.gdt_axis_on_cone(fd.points, tuple(d0), math.radians(tilt), tuple(d_ls), fit)
                method = f"{kind_name}, at {ref.angle:g} degrees to {planes[0].letter}"
            return SimulatedDatum(ref.letter, fd.name, "axis", method, np.array(point), np.array(direction), before, radius=float(radius))
        if fd.shape == "cone" or (fd.shape == "cylinder" and fit == "least-squares"):
            r = fd.lsq()
            radius = getattr(r, "radius", None)
            return SimulatedDatum(ref.letter, fd.name, "axis", f"least-squares {fd.shape} axis", p_ls, d_ls, before,
                                  radius=None if radius is None else float(radius))
        if fd.shape == "circle":
            point, direction, radius, _, _ = _core.gdt_axis_along(fd.points, tuple(d_ls), fit)
            method = {"inscribed": "maximum inscribed", "circumscribed": "minimum circumscribed"}.get(fit, "least-squares")
            return SimulatedDatum(ref.letter, fd.name, "axis", f"{method} circle", np.array(point), np.array(direction), before,
                                  radius=float(radius))
        crit = "max-inscribed" if fit == "inscribed" else "min-circumscribed"
        cyl = fd.chebyshev_cylinder(crit)
        d = _unit(cyl.direction)
        d = d if float(d @ d_ls) >= 0 else -d
        name = "maximum inscribed cylinder" if fit == "inscribed" else "minimum circumscribed cylinder"
        return SimulatedDatum(ref.letter, fd.name, "axis", name, np.array(cyl.point), d, before, radius=float(cyl.radius))

    # -- frame ---------------------------------------------------------------------------
    def frame(self, letters: tuple[str, ...]) -> DatumFrame:
        if letters not in self._frames:
            self._frames[letters] = self._build_frame(letters)
        return self._frames[letters]

    def _build_frame(self, letters: tuple[str, ...]) -> DatumFrame:
        sims = self.chain(letters)
        first = sims[0]
        rows: list[np.ndarray] = []
        vals: list[float] = []

        def constrain(n: np.ndarray, point: np.ndarray) -> None:
            # add n.o = n.point unless n is (nearly) in the span of the rows already there
            if rows:
                Q, _ = np.linalg.qr(np.array(rows).T)
                r = n - Q @ (Q.T @ n)
                if np.linalg.norm(r) < 1e-6:
                    return
            rows.append(n)
            vals.append(float(n @ point))

        def axis_rows(d: np.ndarray) -> list[np.ndarray]:
            from .features import _basis

            u, v = _basis(d)
            return [u, v]

        z = -first.vector if first.type == "plane" else (first.vector if first.type == "axis" else None)
        x = y = None
        if first.type == "plane":
            constrain(first.vector, first.point)
        elif first.type == "axis":
            for n in axis_rows(first.vector):
                constrain(n, first.point)
        else:
            for n in np.eye(3):
                constrain(n, first.point)
        axis_seen = first if first.type == "axis" else None
        point_seen = first if first.type == "point" else None
        for k, s in enumerate(sims[1:], start=1):
            if s.type == "point":
                # a datum point: locks the translations; after an axis, fixes the turn about it
                if axis_seen is not None and z is not None and x is None and y is None:
                    w = s.point - axis_seen.point
                    w = w - (w @ z) * z
                    if np.linalg.norm(w) > 1e-9:
                        x = _unit(w)
                for n in np.eye(3):
                    constrain(n, s.point)
                point_seen = point_seen or s
                continue
            if z is None:
                # behind a primary datum point: the first plane or axis gives z
                z = -s.vector if s.type == "plane" else s.vector
                if s.type == "plane":
                    constrain(s.vector, s.point)
                else:
                    if point_seen is not None:
                        w = point_seen.point - s.point
                        w = w - (w @ z) * z
                        if np.linalg.norm(w) > 1e-9:
                            x = _unit(w)
                    for n in axis_rows(s.vector):
                        constrain(n, s.point)
                    axis_seen = axis_seen or s
                continue
            if s.type == "plane":
                inward = -s.vector
                if abs(float(inward @ z)) > 0.999:
                    z = inward  # a plane perpendicular to the primary axis: its normal into the material
                else:
                    w = inward - (inward @ z) * z
                    w = w / np.linalg.norm(w)
                    if k == 1 and first.type == "plane" and y is None:
                        y = w
                    elif x is None:
                        x = w if y is None else _unit(w - (w @ y) * y)
                constrain(s.vector, s.point)
            else:
                if axis_seen is not None and x is None and y is None:
                    w = s.point - axis_seen.point
                    w = w - (w @ z) * z
                    if np.linalg.norm(w) > 1e-9:
                        x = _unit(w)
                elif x is None and y is None and abs(float(s.vector @ z)) < 0.999:
                    # an axis at a basic angle to the primary plane: its lean fixes x
                    x = _unit(s.vector - (s.vector @ z) * z)
                for n in axis_rows(s.vector):
                    constrain(n, s.point)
                axis_seen = axis_seen or s
        if z is None:
            # a datum point alone: every rotation is free; z and x from its region box
            z = self.feats[first.feature].box_axes()[2]
        free_rotation = x is None and y is None
        if free_rotation:
            box = self.feats[first.feature].box_axes()
            for cand in (box[0], box[1], box[2]):
                w = cand - (cand @ z) * z
                if np.linalg.norm(w) > 1e-6:
                    x = _unit(w)
                    break
        if x is None:
            x = np.cross(y, z)
        if y is None:
            y = np.cross(z, x)
        axes = np.array([x, y, z])
        A = np.array(rows)
        b = np.array(vals)
        ref = first.point
        o = ref + np.linalg.pinv(A) @ (b - A @ ref)
        _, s_, vt = np.linalg.svd(A)
        rank = int((s_ > 1e-9).sum())
        free_t = vt[rank:]
        return DatumFrame(letters, o, axes, free_t, bool(free_rotation))
