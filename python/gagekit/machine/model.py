"""Machine files and the first-order volumetric error model (Sec. 3.1).

A machine file (TOML) lists the chain from the table to the spindle (Eq. 3.1): shape
transforms ``[shapes.T*]`` with a nominal ``offset`` and joints ``[joints.*]`` with ``type``
(``"prismatic"`` or ``"rotary"``), unit ``axis``, ``range`` and, for rotary joints,
``fourier_terms`` (Eq. 3.6, default 1). ``[tool] offset`` is the target r_t in the spindle
frame. Lengths are millimetres; ``angle_unit`` (``"deg"`` or ``"rad"``) is the unit of rotary
commands and ranges in the file and in command/observation CSVs. Inside, everything is mm
and rad.

Parameter names (Eq. 3.2, 3.3, 3.5): shape ``T.alpha T.beta T.gamma T.dx T.dy T.dz``;
prismatic joint ``J.dalpha J.dbeta J.dgamma J.delta``; rotary joint ``J.alpha.n J.beta.n
J.gamma.n J.dx.n J.dy.n J.dz.n`` for n = 1..fourier_terms. The kernels (exact chain, analytic
design matrix, identifiability) are in Rust (``gagekit-kinematics``).

Readings of the text: a rotary joint's error about its own axis adds to the joint angle; its
two tilts and its translations act in the joint's fixed frame (Eq. 3.5 as printed adds the
tilt to R(B) unrotated, which is rigid only at B = 0). The groups follow from the machine's
own offsets: with the example's T4 offset of -450 mm, T4.beta = T3.beta + 450 dx, so the
dx group of Eq. 3.14 also holds 450 T4.beta.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .. import _core
from .._util import parse_toml, read_text
from ..errors import ConfigError, InvalidInputError
from ..schema import validate_document

__all__ = [
    "Machine",
    "JointSpec",
    "ShapeSpec",
    "Group",
    "ModelStructure",
    "load_machine",
    "parse_machine",
    "halton",
    "example_machine_path",
]

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_RESERVED = {"x", "y", "z"}
_ANGLE_UNITS = {"deg": math.pi / 180.0, "rad": 1.0}
_UNIT_TOL = 1e-6


@dataclass(frozen=True)
class JointSpec:
    """A joint of the chain: ``kind`` "prismatic" or "rotary", unit ``axis``, ``range`` in file
    units (mm, or ``angle_unit`` for rotary), ``terms`` Fourier terms (rotary only)."""

    name: str
    kind: str
    axis: tuple[float, float, float]
    range: tuple[float, float]
    terms: int = 0

    def to_dict(self) -> dict:
        d = {"name": self.name, "type": self.kind, "axis": list(self.axis), "range": list(self.range)}
        if self.kind == "rotary":
            d["fourier_terms"] = self.terms
        return d


@dataclass(frozen=True)
class ShapeSpec:
    """A structural member of the chain with its nominal ``offset`` (mm, Eq. 3.2)."""

    name: str
    offset: tuple[float, float, float]

    def to_dict(self) -> dict:
        return {"name": self.name, "type": "shape", "offset": list(self.offset)}


@dataclass(frozen=True)
class Group:
    """An identifiable combination of parameters (Eq. 3.14): value = sum(coef * parameter).

    ``leader`` is the parameter whose design-matrix column represents the group (its
    coefficient is 1): the reduced design matrix is M[:, leaders].
    """

    name: str
    leader: str
    terms: dict

    def to_dict(self) -> dict:
        return {"name": self.name, "leader": self.leader, "terms": dict(self.terms)}


@dataclass(frozen=True)
class ModelStructure:
    """What the volumetric error can reveal (Sec. 3.1.5, Eq. 3.14).

    ``rank`` independent combinations (``groups``, spanning exactly the identifiable subspace);
    ``no_effect`` parameters that do not move the target at all; ``singular_values`` of the
    column-equilibrated design matrix over the analysis commands (the gap after ``rank`` shows
    how clear-cut the rank is).
    """

    parameters: tuple[str, ...]
    rank: int
    groups: tuple[Group, ...]
    no_effect: tuple[str, ...]
    singular_values: tuple[float, ...]
    coefficients: np.ndarray = field(repr=False, compare=False)
    leaders: tuple[int, ...] = field(repr=False)
    n_commands: int = 0

    @property
    def group_names(self) -> list[str]:
        return [g.name for g in self.groups]

    @property
    def rank_gap(self) -> float:
        """s_rank / s_(rank+1): how far the last identifiable direction is from the first null one."""
        s = self.singular_values
        if self.rank >= len(s):
            return math.inf
        return s[self.rank - 1] / max(s[self.rank], 1e-300)

    def reduce(self, design: np.ndarray) -> np.ndarray:
        """The reduced design matrix M[:, leaders] (Eq. 3.14): columns follow ``groups``."""
        return np.ascontiguousarray(np.asarray(design)[:, list(self.leaders)])

    def group_values(self, params: np.ndarray) -> np.ndarray:
        """Group values C p of a full parameter vector."""
        return self.coefficients @ np.asarray(params, dtype=np.float64)

    def params_from_groups(self, values: np.ndarray) -> np.ndarray:
        """The minimum-norm parameter vector with these group values; it has the same
        volumetric error everywhere as any other vector with these group values."""
        return np.linalg.pinv(self.coefficients) @ np.asarray(values, dtype=np.float64)

    def to_dict(self) -> dict:
        return {
            "n_parameters": len(self.parameters),
            "rank": self.rank,
            "no_effect": list(self.no_effect),
            "groups": [g.to_dict() for g in self.groups],
            "singular_values": list(self.singular_values),
            "rank_gap": self.rank_gap,
            "n_commands": self.n_commands,
        }


def warn_outside_ranges(what: str, detail: str, stacklevel: int = 2) -> None:
    """The one warning for commands outside the joint ranges of the machine file
    (``machine predict``, ``compensate``, ``compensate-nc``): ``detail`` says which joints,
    how many commands and (for a program) the first line."""
    warnings.warn(f"{what}: commands outside the machine's joint ranges ({detail})", UserWarning, stacklevel=stacklevel)


def example_machine_path() -> Path:
    """Path of the bundled copy of the dissertation's 5-axis machine file (Eq. 3.1, Table 3.1)."""
    return Path(__file__).resolve().parent / "examples" / "dissertation-5axis.toml"


def halton(n: int, dim: int, seed: Optional[int] = 0) -> np.ndarray:
    """``n`` points of the ``dim``-dimensional Halton sequence in [0, 1)^dim (from index 1),
    randomly shifted modulo 1 (Cranley-Patterson) by ``seed``; seed 0 or None: unshifted.
    Quasi-random commands as in Sec. 3.2.1; the same generator as the design candidates
    (``rust/design/src/qmc.rs``)."""

    if n < 0 or dim < 1 or (seed is not None and seed < 0):
        raise InvalidInputError(f"halton: need n >= 0, dim >= 1 and seed >= 0, got n={n}, dim={dim}, seed={seed}")
    return np.asarray(_core.design.halton(n, dim, seed or 0))


@dataclass(frozen=True)
class Machine:
    """A serial machine tool: the chain (Eq. 3.1), its target r_t and joint ranges."""

    name: str
    chain: tuple[str, ...]
    elements: tuple[Union[JointSpec, ShapeSpec], ...]
    tool: tuple[float, float, float]
    angle_unit: str = "deg"
    length_unit: str = "mm"
    source: Optional[str] = None

    # ----- structure -------------------------------------------------------------------
    @property
    def joints(self) -> tuple[JointSpec, ...]:
        return tuple(e for e in self.elements if isinstance(e, JointSpec))

    @property
    def joint_names(self) -> list[str]:
        """Joint names in chain order: the column order of command arrays."""
        return [j.name for j in self.joints]

    @property
    def ranges(self) -> np.ndarray:
        """(J, 2) joint ranges in file units."""
        return np.array([j.range for j in self.joints], dtype=np.float64)

    def __post_init__(self) -> None:
        # The Rust chain is built and validated once, here; every kinematic call reuses it.
        spec = [("shape", list(e.offset), 0) if isinstance(e, ShapeSpec) else (e.kind, list(e.axis), e.terms)
                for e in self.elements]
        chain = _core.kinematics.KinematicChain(spec, list(self.tool))
        object.__setattr__(self, "_chain", chain)
        object.__setattr__(self, "_labels", tuple(chain.parameter_labels))  # crosses the boundary once

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k not in ("_chain", "_labels")}

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)
        self.__post_init__()

    @property
    def parameter_names(self) -> list[str]:
        """The error parameters in design-matrix column order (52 for the example machine)."""
        return [f"{self.elements[k].name}.{n}" for k, n, _ in self._labels]

    @property
    def parameter_length_powers(self) -> list[int]:
        """Power of length by which each parameter's effect scales (0 mm, 1 rad, 2 rad/mm)."""
        return [p for _, _, p in self._labels]

    @property
    def n_parameters(self) -> int:
        return len(self._labels)

    def parameter_units(self) -> list[str]:
        """Unit of each parameter: mm, rad, rad/mm, or mm/mm (scale error)."""
        out = []
        for k, n, p in self._labels:
            if n == "delta":
                out.append("mm/mm")
            else:
                out.append({0: "mm", 1: "rad", 2: "rad/mm"}[p])
        return out

    # ----- commands ----------------------------------------------------------------------
    def _angle_factor(self) -> np.ndarray:
        f = _ANGLE_UNITS[self.angle_unit]
        return np.array([f if j.kind == "rotary" else 1.0 for j in self.joints])

    def commands_array(self, commands: Any, what: str = "commands") -> np.ndarray:
        """Commands as a float64 (n, J) array (file units), columns in ``joint_names`` order;
        NaN or inf is an error naming the row."""
        try:
            arr = np.asarray(commands, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"{what}: cannot be read as numbers ({exc})") from None
        nj = len(self.joints)
        if arr.ndim == 1 and arr.shape[0] == nj:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != nj:
            raise InvalidInputError(
                f"{what}: expected an (n, {nj}) array with columns {', '.join(self.joint_names)}, got shape {arr.shape}"
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise InvalidInputError(f"{what}: row {i} has a non-finite {self.joint_names[j]} command ({arr[i, j]})")
        return np.ascontiguousarray(arr)

    def _internal(self, commands: Any) -> np.ndarray:
        return np.ascontiguousarray(self.commands_array(commands) * self._angle_factor())

    def out_of_range(self, commands: Any) -> dict:
        """{joint: number of commands outside its range} for the joints with any."""
        c = self.commands_array(commands)
        r = self.ranges
        out = {}
        for j, name in enumerate(self.joint_names):
            k = int(((c[:, j] < r[j, 0]) | (c[:, j] > r[j, 1])).sum())
            if k:
                out[name] = k
        return out

    def warn_out_of_range(self, commands: Any, what: str = "commands") -> None:
        """Warn (UserWarning) when commands fall outside the joint ranges of the machine file."""
        bad = self.out_of_range(commands)
        if bad:
            warn_outside_ranges(what, ", ".join(f"{k}: {v}" for k, v in bad.items()), stacklevel=4)

    def check_joint_names(self, names: Any, what: str = "--at", error: type = InvalidInputError) -> None:
        """Every name in ``names`` is a joint of this machine (else ``error``, naming them all):
        options that fix some joints must not drop a misspelt one silently."""
        unknown = [k for k in names if k not in self.joint_names]
        if unknown:
            raise error(f"{what}: {', '.join(map(repr, unknown))} {'is not a joint' if len(unknown) == 1 else 'are not joints'} "
                        f"of machine '{self.name}' ({', '.join(self.joint_names)})")

    def position(self, at: Mapping[str, float], what: str = "--at", error: type = InvalidInputError) -> np.ndarray:
        """One command (J,) from ``{joint: value}`` naming every joint of the machine exactly
        once: a missing or unknown joint name, or a non-finite value, is an error (an unknown
        name would otherwise be dropped silently); a value outside its joint's range warns, as
        every command does. ``error``: the exception class (``FileFormatError`` for a file's line)."""
        self.check_joint_names(at, what, error)
        missing = [j for j in self.joint_names if j not in at]
        if missing:
            raise error(f"{what} must give every joint of the machine (missing {', '.join(missing)})")
        cmd = self.commands_array([float(at[j]) for j in self.joint_names], what)
        self.warn_out_of_range(cmd, what)
        return cmd[0]

    def sample_commands(self, n: int, seed: Optional[int] = 0) -> np.ndarray:
        """``n`` quasi-random commands (shifted Halton) over the joint ranges, file units
        (the 290-point identification sets of Sec. 3.2.1)."""
        r = self.ranges
        return r[:, 0] + halton(n, len(self.joints), seed) * (r[:, 1] - r[:, 0])

    # ----- kinematics (Rust) ---------------------------------------------------------------
    def nominal(self, commands: Any) -> np.ndarray:
        """Nominal target positions (n, 3) in the table frame, mm (Eq. 3.1)."""
        return self._chain.nominal(self._internal(commands))

    def positions(self, commands: Any, params: Any) -> np.ndarray:
        """Target positions (n, 3) of the exactly perturbed chain (Eq. 3.7), mm."""
        p = np.ascontiguousarray(np.asarray(params, dtype=np.float64).reshape(-1))
        if p.shape[0] != self.n_parameters:
            raise InvalidInputError(f"parameters: expected {self.n_parameters} values, got {p.shape[0]}")
        return self._chain.exact(self._internal(commands), p)

    def design_matrix(self, commands: Any) -> np.ndarray:
        """The design matrix M (3n, P) of Eq. 3.13: rows x, y, z of the volumetric error of
        each command in the table frame, columns ``parameter_names``; analytic first-order
        derivatives, assembled in parallel in Rust."""
        return self._chain.design_matrix(self._internal(commands))

    def command_jacobian(self, commands: Any) -> np.ndarray:
        """d(nominal position)/d(command), (3n, J), per file unit (mm, or deg/rad)."""
        jac = self._chain.command_jacobian(self._internal(commands))
        return jac * self._angle_factor()

    def volumetric_error(self, commands: Any, params: Any) -> np.ndarray:
        """First-order volumetric error (n, 3) = M p (Eq. 3.9, 3.13), mm, table frame."""
        m = self.design_matrix(commands)
        return (m @ np.asarray(params, dtype=np.float64)).reshape(-1, 3)

    def reduced_design_matrix(self, commands: Any, structure: Optional["ModelStructure"] = None) -> np.ndarray:
        """The design matrix of the identifiable groups (3n, rank), Eq. 3.14 / 4.9: the
        leader columns of M, in the order of ``structure.groups``."""
        st = structure if structure is not None else self.structure()
        return st.reduce(self.design_matrix(commands))

    def length_scale(self, commands: Any) -> float:
        """RMS distance of the nominal targets from the table origin plus the tool length."""
        p = self.nominal(commands)
        return float(np.sqrt((p**2).sum(axis=1).mean())) + float(np.linalg.norm(self.tool)) + 1.0

    def structure(self, commands: Any = None, n: int = 2000, seed: int = 0, rtol: float = 1e-9) -> ModelStructure:
        """Which parameters and combinations the volumetric error reveals (Eq. 3.14).

        Rank by SVD of the column-equilibrated design matrix over ``commands`` (default:
        ``n`` quasi-random commands over the joint ranges); groups by an ordered pivoted QR
        (leaders = first independent columns in chain order), coefficients in the parameters'
        own units.
        """
        if commands is None:
            key = (self, n, seed, rtol)
            if key not in _STRUCTURES:
                _STRUCTURES[key] = self.structure(self.sample_commands(n, seed), rtol=rtol)
            return _STRUCTURES[key]
        cmds = self.commands_array(commands)
        m = self.design_matrix(cmds)
        res = _core.kinematics.identifiability(m, self.length_scale(cmds), self.parameter_length_powers, rtol)
        names = self.parameter_names
        coef = np.asarray(res.coefficients)
        groups = []
        for k, lead in enumerate(res.leaders):
            terms = {names[j]: float(_tidy(coef[k, j])) for j in np.flatnonzero(coef[k])}
            groups.append(Group(name=_group_name(names[lead], terms), leader=names[lead], terms=terms))
        return ModelStructure(
            parameters=tuple(names),
            rank=int(res.rank),
            groups=tuple(groups),
            no_effect=tuple(names[j] for j in res.no_effect),
            singular_values=tuple(float(s) for s in res.singular_values),
            coefficients=coef,
            leaders=tuple(int(j) for j in res.leaders),
            n_commands=int(cmds.shape[0]),
        )

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "length_unit": self.length_unit,
            "angle_unit": self.angle_unit,
            "chain": list(self.chain),
            "elements": [e.to_dict() for e in self.elements],
            "tool": list(self.tool),
            "parameters": self.parameter_names,
        }


_STRUCTURES: dict = {}


def _tidy(c: float) -> float:
    """Round a coefficient to 10 significant digits (drops the last bits of round-off)."""
    return float(f"{c:.10g}")


def _group_name(leader: str, terms: dict) -> str:
    """'T1.dx + T2.dx - 312.035*T5.beta' with the leader first."""
    parts = []
    for name in [leader] + [n for n in terms if n != leader]:
        c = terms[name]
        mag = abs(c)
        body = name if math.isclose(mag, 1.0, rel_tol=1e-9) else f"{mag:.10g}*{name}"
        if not parts:
            parts.append(body if c > 0 else f"-{body}")
        else:
            parts.append(("+ " if c > 0 else "- ") + body)
    return " ".join(parts)


# ----- loading and validation ----------------------------------------------------------------
def load_machine(path: Union[str, Path]) -> Machine:
    """Read and validate a machine file (TOML). Raises ConfigFileError (a FileFormatError) for an unreadable file or invalid TOML and
    ConfigError naming the exact entry for anything inconsistent."""
    return parse_machine(read_text(path, "machine"), source=str(path))


def parse_machine(text: str, source: str = "<machine>") -> Machine:
    """Validate the text of a machine file against its schema (:mod:`gagekit.schema.machine`,
    ``gagekit schema machine``), then the rules of the chain; see :func:`load_machine`."""
    doc = parse_toml(text, source)
    f = validate_document("machine", doc, source)

    def fail(msg: str) -> ConfigError:
        return ConfigError(f"{source}: {msg}")

    joints, shapes, chain = f.joints, f.shapes, f.chain
    for n in set(joints) & set(shapes):
        raise fail(f"'{n}' is defined both as [joints.{n}] and [shapes.{n}]")
    seen = set()
    for c in chain:
        if c in seen:
            raise fail(f"chain: '{c}' appears more than once")
        seen.add(c)
        if c not in joints and c not in shapes:
            raise fail(f"chain: unknown element '{c}' (define it as [joints.{c}] or [shapes.{c}])")
    for n in list(joints) + list(shapes):
        if n not in seen:
            kind = "joints" if n in joints else "shapes"
            raise fail(f"[{kind}.{n}] is defined but not listed in chain")
        if not _NAME.match(n) or n in _RESERVED:
            raise fail(
                f"element name '{n}' is not allowed: use letters, digits and _ (not starting with a digit), "
                "and not x, y or z (observation columns)"
            )
    elements: list = [_joint(c, joints[c], fail) if c in joints else ShapeSpec(name=c, offset=tuple(shapes[c].offset))
                      for c in chain]
    if not any(isinstance(e, JointSpec) for e in elements):
        raise fail("the chain has no joint: nothing moves")
    name = f.name if "name" in f.model_fields_set else Path(source).stem
    m = Machine(name=name, chain=tuple(chain), elements=tuple(elements), tool=tuple(f.tool.offset),
                angle_unit=f.angle_unit, source=source)
    m.n_parameters  # the Rust side validates the chain once more
    return m


def _joint(name: str, t: Any, fail) -> JointSpec:
    """A joint's rules between keys: a unit axis, min < max, Fourier terms on rotary joints only."""
    where = f"joints.{name}"
    norm = math.sqrt(sum(a * a for a in t.axis))
    if abs(norm - 1.0) > _UNIT_TOL:
        raise fail(f"{where}.axis must be a unit vector, its length is {norm:.6g}")
    axis = tuple(a / norm for a in t.axis)
    lo, hi = t.range
    if not lo < hi:
        raise fail(f"{where}.range: min {lo} must be less than max {hi}")
    if t.type != "rotary" and "fourier_terms" in t.model_fields_set:
        raise fail(f"{where}: fourier_terms applies to rotary joints only")
    return JointSpec(name=name, kind=t.type, axis=axis, range=(lo, hi), terms=t.fourier_terms if t.type == "rotary" else 0)
