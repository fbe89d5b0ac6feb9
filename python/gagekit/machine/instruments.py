"""Observers other than the laser tracker, alone or mixed: a probed reference sphere, the R-test
(ISO 10791-6), and the tracker of Ch. 3 (Sec. 3.1.5), identified together.

Observation files are the CSVs of :mod:`.observations` with ``# key = value`` lines before the
header. ``# kind = tracker`` (the default: joint columns and x, y, z), ``sphere`` or ``rtest``;
``# sigma_um = S`` the standard deviation of one reading (default: tracker 8.9, sphere 1,
R-test 0.5).

- ``kind = sphere``: joint columns, optionally ``sphere`` (an integer naming the sphere location
  when several are probed). A row holds the joint positions at which the probe's touch cycle
  found the centre of a sphere fixed on the table: there the actual tool sits at the sphere
  centre S (table frame), nominal(c) + M(c) p = S (Eq. 3.9, 3.13). S is unknown, one per
  location, estimated with the errors.
- ``kind = rtest``: joint columns and ``d1, d2, d3`` (mm): three displacement sensors fixed on
  the table read the ball on the spindle; ``# directions = ux uy uz; ...`` their unit
  directions in the table frame (default the table axes). d_k = n_k . (nominal(c) + M(c) p -
  S) with S (the nest's zero, unknown) estimated.
- ``kind = ballbar``: a ballbar run in the layout of :mod:`.ballbar` (``angle_deg,
  deviation_um, direction``) with ``# plane = XY``, ``# radius = R`` (mm) and ``# at = B=0,X=0,
  ...`` (the joint positions of the circle's centre). The commands of reading i are ``at`` with
  the plane's joints moved by R (cos, sin); the deviation is u_i . ((M_i - M_at) p) + l with u_i
  the nominal direction from the pivot and l the ballbar's length error (estimated). Readings
  of both directions at the same angle are averaged first: backlash and servo mismatch change
  sign with the direction and drop out (they are not geometric errors of the model).
- ``kind = tracker``: q = T0 (nominal + M p); T0 from the closed-form rigid fit (Step 1), its
  small correction estimated with the errors (the joint method of :func:`identify`).

All rows are weighted by 1/sigma and solved together (generalized least squares). The unknowns
are the identifiable groups of Eq. 3.14 (``unknowns = "groups"``, the default when a tracker
file is in the mix), or only the location errors of the rotary axes (``"location"``, the
default for sphere and R-test data alone: the linear axes taken as calibrated, as the
controllers' kinematics cycles do). Which of them the data see is decided on the weighted
design matrix: an unknown is *seen* when its unit vector lies in the row space (its estimate is
unique whatever the unseen ones are); unseen unknowns are reported as such and kept at zero.

Location errors of a rotary axis J, ISO 230-7 / ISO 230-1 names: EXOJ, EYOJ, EZOJ (offsets of
the axis average line, mm) and EAOJ, EBOJ, ECOJ (its tilts about x, y, z, rad), at the joint's
frame origin. In the chain (Eq. 3.1) they are the displacement D of the joint, Phi_J' = D Phi_J
D^-1: the shape after the joint takes D^-1 (rotation -w, translation -e - w x offset), the shape
before it D (rotation +w, translation +e); a joint first in the chain moves the table frame
itself, which the sphere position and the tracker frame take up.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ..errors import DegenerateGeometryError, FileFormatError, InvalidInputError
from .frame import frame_columns, rigid_fit
from .model import Machine, ModelStructure, ShapeSpec
from .simulate import TRACKER_SIGMA

__all__ = [
    "KINDS",
    "InstrumentObservations",
    "MixedResult",
    "read_instrument",
    "identify_mixed",
    "location_names",
    "location_matrix",
    "instrument_view",
    "cycles_kind",
    "track_sphere",
]

KINDS = ("tracker", "sphere", "rtest", "ballbar")
#: Standard deviation of one reading by kind, mm (tracker: Sec. 3.2.1).
DEFAULT_SIGMA = {"tracker": TRACKER_SIGMA, "sphere": 0.001, "rtest": 0.0005, "ballbar": 0.0005}
_META = re.compile(r"^\s*#\s*([A-Za-z_]+)\s*=\s*(.*?)\s*$")
_LOC = ("X", "Y", "Z", "A", "B", "C")


@dataclass(frozen=True)
class InstrumentObservations:
    """One observation file: ``kind``, commands (n, J), readings (tracker (n, 3) positions,
    rtest (n, 3) sensor readings, sphere: none), sphere ids, sensor directions, sigma (mm)."""

    kind: str
    commands: np.ndarray
    readings: Optional[np.ndarray] = None
    sphere: Optional[np.ndarray] = None
    directions: Optional[np.ndarray] = None
    sigma: float = 0.0
    source: Optional[str] = None

    def __len__(self) -> int:
        return int(self.commands.shape[0])


def _metadata(text: str) -> dict:
    out = {}
    for line in text.splitlines():
        if not line.strip():
            continue
        if not line.lstrip().startswith("#"):
            break
        m = _META.match(line)
        if m:
            out[m.group(1).lower()] = m.group(2)
    return out


def read_instrument(path: Union[str, Path], machine: Machine) -> InstrumentObservations:
    """Read an observation file of any kind (see the module's doc)."""
    from .._files import read_text
    from .observations import _read_table

    p = Path(path)
    meta = _metadata(read_text(p, "observations"))
    kind = meta.get("kind", "tracker").lower()
    if kind not in KINDS:
        raise FileFormatError(f"{p}: kind must be one of {', '.join(KINDS)}, got {kind!r}")
    sigma = DEFAULT_SIGMA[kind]
    if "sigma_um" in meta:
        try:
            sigma = 1e-3 * float(meta["sigma_um"])
        except ValueError:
            raise FileFormatError(f"{p}: sigma_um must be a number, got {meta['sigma_um']!r}") from None
        if not (math.isfinite(sigma) and sigma > 0):
            raise InvalidInputError(f"{p}: sigma_um must be positive, got {meta['sigma_um']}")
    if kind == "ballbar":
        return _read_ballbar_kind(p, machine, meta, sigma)
    header, data = _read_table(p)
    if data.shape[0] == 0:
        raise DegenerateGeometryError(f"{p}: no observations")
    joints = machine.joint_names
    want = {"tracker": ["x", "y", "z"], "sphere": [], "rtest": ["d1", "d2", "d3"]}[kind]
    optional = ["sphere"] if kind == "sphere" else []
    missing = [c for c in joints + want if c not in header]
    if missing:
        raise FileFormatError(f"{p}: missing column(s) {', '.join(missing)} for kind {kind} (expected {', '.join(joints + want + optional)})")
    extra = [c for c in header if c not in joints + want + optional]
    if extra:
        raise FileFormatError(f"{p}: unknown column(s) {', '.join(extra)} for kind {kind}")
    cmds = machine.commands_array(data[:, [header.index(c) for c in joints]], str(p))
    readings = data[:, [header.index(c) for c in want]] if want else None
    sphere = None
    if kind == "sphere":
        sphere = data[:, header.index("sphere")] if "sphere" in header else np.zeros(len(cmds))
        if np.any(sphere != np.round(sphere)):
            raise FileFormatError(f"{p}: the sphere column must hold integers (one per sphere location)")
        sphere = sphere.astype(np.int64)
    directions = None
    if kind == "rtest":
        directions = _directions(meta.get("directions"), p)
    return InstrumentObservations(kind, cmds, readings, sphere, directions, sigma, str(p))


def _read_ballbar_kind(p: Path, machine: Machine, meta: dict, sigma: float) -> InstrumentObservations:
    """A ballbar run as an observation: commands on the circle, mean deviation of both
    directions per angle (mm) in ``readings`` (n, 1), the circle centre's commands last."""
    from .ballbar import PLANES, circle_commands, read_ballbar

    for key in ("plane", "radius", "at"):
        if key not in meta:
            raise FileFormatError(f"{p}: a ballbar observation file needs a '# {key} = ...' line (plane, radius, at)")
    plane = meta["plane"].upper()
    if plane not in PLANES:
        raise FileFormatError(f"{p}: plane must be XY, YZ or ZX, got {meta['plane']!r}")
    try:
        radius = float(meta["radius"])
    except ValueError:
        raise FileFormatError(f"{p}: radius must be a number of mm, got {meta['radius']!r}") from None
    if not (math.isfinite(radius) and radius > 0):
        raise InvalidInputError(f"{p}: radius must be positive, got {radius}")
    at = {}
    for part in meta["at"].split(","):
        if "=" not in part:
            raise FileFormatError(f"{p}: at must be NAME=VALUE items separated by commas, got {meta['at']!r}")
        k, v = (x.strip() for x in part.split("=", 1))
        try:
            at[k] = float(v)
        except ValueError:
            raise FileFormatError(f"{p}: at {k}: {v!r} is not a number") from None
    centre = machine.position(at, f"{p}: at", FileFormatError)
    for name in PLANES[plane]:
        if name not in machine.joint_names or machine.joints[machine.joint_names.index(name)].kind != "prismatic":
            raise InvalidInputError(f"{p}: plane {plane} needs prismatic joints named {' and '.join(PLANES[plane])}")
    run = read_ballbar(p)
    ang = np.round(np.mod(run.angles_deg, 360.0), 9)
    uniq = np.unique(ang)
    dev = np.array([run.deviations_um[ang == a].mean() for a in uniq]) * 1e-3  # both directions averaged
    cmds = circle_commands(machine, plane, radius, centre, np.radians(uniq))
    return InstrumentObservations("ballbar", machine.commands_array(cmds, str(p)), np.append(dev, 0.0)[:, None],
                                  None, np.array([[radius]]), sigma, str(p))


def _directions(text: Optional[str], p: Path) -> np.ndarray:
    if text is None:
        return np.eye(3)
    try:
        rows = [[float(v) for v in part.replace(",", " ").split()] for part in text.split(";") if part.strip()]
        d = np.array(rows, dtype=np.float64)
    except ValueError:
        raise FileFormatError(f"{p}: directions must be three vectors 'ux uy uz; ...', got {text!r}") from None
    if d.shape != (3, 3) or not np.isfinite(d).all():
        raise FileFormatError(f"{p}: directions must be three vectors of three numbers, got {text!r}")
    n = np.linalg.norm(d, axis=1)
    if np.any(n < 1e-9) or abs(np.linalg.det(d / n[:, None])) < 1e-3:
        raise InvalidInputError(f"{p}: the three R-test sensor directions must be independent")
    return d / n[:, None]


# ----- location errors of the rotary axes (ISO 230-7) ------------------------------------------
def location_names(machine: Machine) -> list[str]:
    """EXOB, EYOB, ... for every rotary joint, in chain order."""
    return [f"E{c}O{j.name}" for j in machine.joints if j.kind == "rotary" for c in _LOC]


def location_matrix(machine: Machine) -> np.ndarray:
    """(P, 6 R) map from location errors (mm, rad) to the error parameters (see the module)."""
    names = machine.parameter_names
    index = {n: k for k, n in enumerate(names)}
    rotary = [k for k, e in enumerate(machine.elements) if getattr(e, "kind", "") == "rotary"]
    out = np.zeros((len(names), 6 * len(rotary)))
    for r, k in enumerate(rotary):
        joint = machine.elements[k]
        after = machine.elements[k + 1] if k + 1 < len(machine.elements) else None
        before = machine.elements[k - 1] if k > 0 else None
        if not isinstance(after, ShapeSpec):
            raise InvalidInputError(f"rotary joint {joint.name}: its location errors need a shape right after it in the chain")
        o = np.asarray(after.offset)
        for c in range(6):
            e = np.zeros(3)
            w = np.zeros(3)
            (e if c < 3 else w)[c % 3] = 1.0
            col = 6 * r + c
            # after the joint: D^-1 = rotation -w, translation -e - w x offset
            t_after = -e - np.cross(w, o)
            for sh, sign, t in ((after, -1.0, t_after), (before, 1.0, e)):
                if not isinstance(sh, ShapeSpec):
                    continue
                for pname, v in (("gamma", w[0]), ("beta", w[1]), ("alpha", w[2])):
                    out[index[f"{sh.name}.{pname}"], col] += sign * v
                for pname, v in zip(("dx", "dy", "dz"), t):
                    out[index[f"{sh.name}.{pname}"], col] += v
    return out


# ----- rows of each kind ---------------------------------------------------------------------
@dataclass
class _Block:
    kind: str
    a: np.ndarray  # (m, P) rows in the full parameters
    n: np.ndarray  # (m, k) nuisance columns
    b: np.ndarray  # (m,)
    sigma: float
    nuisance: list
    source: str
    raw: Optional[np.ndarray] = None  # (3n, P) the errors at the commands, before any projection


def _rows(machine: Machine, obs: InstrumentObservations, index: int) -> _Block:
    c = obs.commands
    nom = machine.nominal(c)
    m = machine.design_matrix(c)  # (3n, P)
    src = obs.source or f"observations {index + 1}"
    if obs.kind == "tracker":
        frame = rigid_fit(nom, obs.readings)
        r = frame.to_table(obs.readings) - nom
        names = [f"{src}: frame.{k}" for k in ("alpha0", "beta0", "gamma0", "x0", "y0", "z0")]
        return _Block("tracker", m, frame_columns(nom), r.reshape(-1), obs.sigma, names, src)
    if obs.kind == "ballbar":
        radius = float(obs.directions[0, 0])
        from .ballbar import radial_rows

        n = len(c) - 1
        rows, length = radial_rows(machine, c, m)
        b = obs.readings[:n, 0] - (length - radius)
        names = [f"{src}: ballbar length"]
        return _Block("ballbar", rows, np.ones((n, 1)), b, obs.sigma, names, src, m)
    ids = obs.sphere if obs.kind == "sphere" else np.zeros(len(c), dtype=np.int64)
    uniq = sorted(set(int(i) for i in ids))
    s0 = {i: nom[ids == i].mean(axis=0) for i in uniq}
    # the errors act where the tool is, at the sphere: the rows are taken at the commands that
    # put the nominal tool there (one Newton step on the prismatic joints; the shift is the
    # errors' size, a second-order change of the rows). Taken at the probed commands, a rotation
    # of the table frame would look slightly different from a move of the sphere.
    target = np.array([s0[int(i)] for i in ids])
    jac = machine.command_jacobian(c).reshape(len(c), 3, -1)
    lin = [k for k, j in enumerate(machine.joints) if j.kind == "prismatic"]
    shifted = c.copy()
    jl = jac[:, :, lin]  # minimum-norm step J^T (J J^T)^-1 (target - nominal), batched 3 x 3 solves
    shifted[:, lin] += np.einsum("nji,nj->ni", jl, np.linalg.solve(jl @ jl.transpose(0, 2, 1), (target - nom)[:, :, None])[:, :, 0])
    m = machine.design_matrix(shifted)
    nn = np.zeros((len(c), 3, len(uniq), 3))
    slot = np.searchsorted(np.array(uniq), ids)
    for a in range(3):
        nn[np.arange(len(c)), a, slot, a] = -1.0
    nn = nn.reshape(3 * len(c), 3 * len(uniq))
    base = np.array([s0[int(i)] for i in ids]) - nom  # M p - dS = S0 - nominal
    names = [f"{src}: sphere {i}.{a}" for i in uniq for a in "xyz"]
    if obs.kind == "sphere":
        return _Block("sphere", m, nn, base.reshape(-1), obs.sigma, names, src)
    # rtest: d_k = n_k . (nominal + M p - S0 - dS)
    d = obs.directions
    proj = np.kron(np.eye(len(c)), d)  # (3n, 3n): rows n_k per point
    b = obs.readings.reshape(-1) + (proj @ base.reshape(-1))
    names = [f"{src}: nest.{a}" for a in "xyz"]
    return _Block("rtest", proj @ m, proj @ nn, b, obs.sigma, names, src, m)


# ----- the joint solve ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MixedResult:
    """Groups (or location errors) seen by the mix, their values and uncertainties, the
    location errors of the rotary axes, and each instrument's residuals."""

    unknowns: str
    names: tuple
    values: np.ndarray
    std: np.ndarray
    seen: np.ndarray
    groups: dict
    location: dict
    instruments: list
    condition_number: float
    calibration: object = field(repr=False, default=None)

    def to_dict(self) -> dict:
        return {
            "unknowns": self.unknowns,
            "seen": [n for n, s in zip(self.names, self.seen) if s],
            "not_seen": [n for n, s in zip(self.names, self.seen) if not s],
            "groups": self.groups,
            "location_errors": self.location,
            "instruments": self.instruments,
            "condition_number": self.condition_number,
        }


#: Relative singular value below which a direction counts as unseen: the readings resolve
#: parts in 1e6 at best, and first-order effects of the errors themselves reach 1e-9.
RANK_RTOL = 1e-6


#: Largest variance inflation (equilibrated columns) of an unknown counted as seen: beyond it
#: the estimate is more than 1000 times noisier than the unknown's own column would make it.
MAX_INFLATION = 1e6


def _seen(vt: np.ndarray, sv: np.ndarray, r: int, k: int) -> np.ndarray:
    """Which of the first k columns are estimable: their unit vectors lie in the row space
    (the first r right singular vectors of the weighted, equilibrated matrix), and not so
    nearly dependent on the others that the estimate is meaningless."""
    resid = 1.0 - (vt[:r, :k] ** 2).sum(axis=0)
    inflation = ((vt[:r, :k] / sv[:r, None]) ** 2).sum(axis=0)
    return (resid < 1e-6) & (inflation < MAX_INFLATION) & (np.abs(vt[:r, :k]).sum(axis=0) > 0)


def identify_mixed(
    machine: Machine,
    observations: Sequence[InstrumentObservations],
    unknowns: Optional[str] = None,
    structure: Optional[ModelStructure] = None,
    require_seen: bool = True,
) -> MixedResult:
    """Identify from any mix of tracker, sphere and R-test observations (see the module's doc):
    generalized least squares over all rows, each kind with its own sigma. Observations that
    see none of the unknowns are an error unless ``require_seen`` is False (what an instrument
    sees, :func:`instrument_view`)."""
    if not observations:
        raise InvalidInputError("no observations given")
    kinds = {o.kind for o in observations}
    if unknowns is None:
        unknowns = "groups" if kinds & {"tracker", "ballbar"} else "location"
    if unknowns not in ("groups", "location"):
        raise InvalidInputError(f"unknowns must be 'groups' or 'location', got {unknowns!r}")
    st = structure if structure is not None else machine.structure()
    blocks = [_rows(machine, o, i) for i, o in enumerate(observations)]
    lmat = location_matrix(machine)
    lnames = location_names(machine)
    if unknowns == "groups":
        basis = np.zeros((machine.n_parameters, st.rank))
        basis[list(st.leaders), np.arange(st.rank)] = 1.0  # M p = M[:, leaders] g
        names = [g.name for g in st.groups]
    else:
        basis = lmat
        names = lnames
    k = basis.shape[1]
    # the normal matrix of the weighted rows [A_b | N_b] / sigma_b, block by block (the nuisance
    # columns of a block meet only its own rows): nothing of size 3n x unknowns is stacked
    nuis = [b.n.shape[1] for b in blocks]
    q = k + sum(nuis)
    normal = np.zeros((q, q))
    atb = np.zeros(q)
    raw2 = np.zeros(k)
    ab_all = []
    col = k
    select = list(st.leaders) if unknowns == "groups" else None  # the basis only picks columns
    for b, w in zip(blocks, nuis):
        ab = (b.a[:, select] if select is not None else b.a @ basis) / b.sigma
        nb = b.n / b.sigma
        rb = b.b / b.sigma
        ab_all.append((ab, nb, rb, col))
        sl = slice(col, col + w)
        normal[:k, :k] += ab.T @ ab
        normal[:k, sl] += ab.T @ nb
        normal[sl, :k] += nb.T @ ab
        normal[sl, sl] += nb.T @ nb
        atb[:k] += ab.T @ rb
        atb[sl] += nb.T @ rb
        # an unknown whose effect the readings cancel (a ballbar's length under a rotation of
        # the whole table) has a column of round-off only: no effect
        raw2 += ((b.raw @ basis / b.sigma) ** 2).sum(axis=0) if b.raw is not None else (ab**2).sum(axis=0)
        col += w
    n_rows = sum(len(b.b) for b in blocks)
    norms = np.sqrt(np.clip(np.diag(normal), 0.0, None))
    dead = np.zeros(q, bool)
    dead[:k] = norms[:k] <= 1e-9 * np.sqrt(raw2)
    normal[dead, :] = 0.0
    normal[:, dead] = 0.0
    atb[dead] = 0.0
    norms[dead | (norms == 0)] = 1.0
    eqn = normal / np.outer(norms, norms)  # eq^T eq of the column-equilibrated rows
    eqb = atb / norms  # eq^T rhs
    lam, v = np.linalg.eigh(eqn)
    order = np.argsort(lam)[::-1]
    lam, v = np.clip(lam[order], 0.0, None), v[:, order]
    sv = np.sqrt(lam)
    vt = v.T
    qtb = (vt @ eqb) / np.where(sv > 0, sv, 1.0)  # = U^T rhs on the row space
    r = int((sv > RANK_RTOL * sv[0]).sum())
    if r == 0:
        raise DegenerateGeometryError("the observations see none of the unknowns")
    seen = _seen(vt, sv, r, k)
    if require_seen and not seen.any():  # r > 0 from the nuisance columns alone (a sphere's centre, a ballbar's length)
        raise DegenerateGeometryError(f"the observations see none of the {'groups' if unknowns == 'groups' else 'location errors'} "
                                      f"(only the instruments' own unknowns): take readings at several positions of the axes")
    x = (vt[:r].T @ (qtb[:r] / sv[:r])) / norms
    cov = ((vt[:r].T / sv[:r] ** 2) @ vt[:r]) / np.outer(norms, norms)  # unit weight: sigmas as given
    x[dead] = 0.0
    dof = max(n_rows - r, 1)
    rss = 0.0
    instruments = []
    for b, (ab, nb, rb, col) in zip(blocks, ab_all):
        res = rb - ab @ x[:k] - nb @ x[col : col + nb.shape[1]]
        rss += float(res @ res)
        instruments.append({
            "source": b.source, "kind": b.kind, "readings": int(len(b.b)), "sigma_um": 1e3 * b.sigma,
            "residual_rms_um": 1e3 * b.sigma * float(np.sqrt((res**2).mean())),
        })
    chi2 = rss / dof
    values = np.where(seen, x[:k], 0.0)
    std = np.where(seen, np.sqrt(np.clip(np.diag(cov)[:k], 0.0, None)), np.nan)
    # groups and location errors from the estimate
    if unknowns == "groups":
        gvals, gstd, gseen = values, std, seen
        gcov = cov[:k, :k] * np.outer(seen, seen)
        lvals, lstd, lseen = _location_from_groups(st, lmat, values, cov[:k, :k], seen)
    else:
        cg = st.coefficients @ lmat  # groups of the location errors
        gvals = cg @ values
        gcov = cg @ (cov[:k, :k] * np.outer(seen, seen)) @ cg.T
        gstd = np.sqrt(np.clip(np.diag(gcov), 0.0, None))
        gseen = np.abs(cg[:, seen]).sum(axis=1) > 0 if seen.any() else np.zeros(st.rank, bool)
        lvals, lstd, lseen = values, std, seen
    groups = {g.name: ({"value": float(v), "std": float(s)} if ok else {"seen": False})
              for g, v, s, ok in zip(st.groups, gvals, gstd, gseen)}
    location = {}
    for n, v, s, ok in zip(lnames, lvals, lstd, lseen):
        unit = "mm" if n[1] in "XYZ" else "rad"
        location[n] = {"value": float(v), "std": float(s), "unit": unit} if ok else {"seen": False}
    cal = _calibration(machine, st, gvals, gstd, gseen, unknowns, chi2, dof, n_rows, gcov * np.outer(gseen, gseen))
    return MixedResult(unknowns, tuple(names), values, std, seen, groups, location, instruments,
                       float(sv[0] / sv[r - 1]), cal)


def _location_from_groups(st, lmat, g, gcov, gseen):
    """Location errors from identified groups: each location error maps onto the groups by
    C L; those whose groups are all seen are solved from them by least squares."""
    cg = st.coefficients @ lmat  # (rank, 6R)
    n = cg.shape[1]
    vals, std, seen = np.zeros(n), np.full(n, np.nan), np.zeros(n, bool)
    for j in range(n):
        rows = np.flatnonzero(np.abs(cg[:, j]) > 1e-12)
        if rows.size == 0 or not gseen[rows].all():
            continue
        # groups touched only by this location error give it alone
        own = [r for r in rows if np.count_nonzero(np.abs(cg[r]) > 1e-12) == 1]
        if not own:
            continue
        c = cg[own, j]
        w = c / (c @ c)
        vals[j] = float(w @ g[own])
        std[j] = float(np.sqrt(max(w @ gcov[np.ix_(own, own)] @ w, 0.0)))
        seen[j] = True
    return vals, std, seen


def _calibration(machine, st, gvals, gstd, gseen, unknowns, chi2, dof, n_rows, gcov=None):
    """A :class:`Calibration` of the groups (unseen ones at zero, with zero rows and columns in
    the covariance ``gcov``: the predictions' uncertainty does not count them) for predict and export."""
    from .calibration import Calibration, GroupEstimate, ResidualStats
    from .frame import Frame

    units = machine.parameter_units()
    groups = tuple(
        GroupEstimate(name=g.name, leader=g.leader, terms=dict(g.terms), value=float(v) if ok else 0.0,
                      std=float(s) if ok else None, unit=units[st.leaders[i]])
        for i, (g, v, s, ok) in enumerate(zip(st.groups, gvals, gstd, gseen))
    )
    zero = np.zeros((1, 3))
    return Calibration(
        machine=machine.name, method=f"mixed ({unknowns})", rank=st.rank, condition_number=1.0, groups=groups,
        unidentifiable=tuple(st.no_effect), frame=Frame.identity(), residuals=ResidualStats.of(zero, zero),
        sigma=math.sqrt(chi2), dof=int(dof), covariance=gcov,
    )


# ----- what each instrument sees -------------------------------------------------------------
def _sample(machine: Machine, kind: str, seed: int = 0) -> list:
    """A rich synthetic set-up of ``kind`` over the machine's ranges (for `machine check`)."""
    from .simulate_instruments import simulate_sphere

    if kind == "tracker":
        c = machine.sample_commands(300, seed=seed + 1)
        return [InstrumentObservations("tracker", c, machine.nominal(c), sigma=DEFAULT_SIGMA["tracker"])]
    if kind == "ballbar":
        from .ballbar import PLANES, circle_commands

        mid = np.array([0.0 if j.kind == "rotary" else 0.5 * (j.range[0] + j.range[1]) for j in machine.joints])
        radius = 0.25 * min(j.range[1] - j.range[0] for j in machine.joints if j.kind == "prismatic")
        out = []
        for plane, axes in PLANES.items():
            if all(a in machine.joint_names for a in axes):
                c = circle_commands(machine, plane, radius, mid, np.radians(np.arange(0.0, 360.0, 10.0)))
                out.append(InstrumentObservations("ballbar", c, np.zeros((len(c), 1)), None, np.array([[radius]]), DEFAULT_SIGMA["ballbar"]))
        if not out:
            raise InvalidInputError(f"machine '{machine.name}' has no pair of joints named X, Y, Z for a ballbar circle")
        return out
    rot = [j for j in machine.joints if j.kind == "rotary"]
    if not rot:
        raise InvalidInputError(f"machine '{machine.name}' has no rotary axis: a sphere or R-test observes rotary axes")
    lin = [j for j in machine.joints if j.kind == "prismatic"]
    mid = {j.name: 0.5 * (j.range[0] + j.range[1]) for j in lin}
    at = {n: v for n, v in mid.items() if n not in [x.name for x in lin[:3]]}
    out = []
    for j in rot:
        pos = np.linspace(j.range[0], j.range[1], 13)[:-1] if j.range[1] - j.range[0] >= 359 else np.linspace(*j.range, 12)
        spheres = [np.array([100.0, 50.0, 200.0]), np.array([-150.0, 120.0, -100.0])]
        cmds = [simulate_sphere(machine, j.name, pos, s, {**at, **{r.name: 0.0 for r in rot if r is not j}}, {}) for s in spheres]
        c = np.vstack(cmds)
        ids = np.repeat(np.arange(len(cmds)), [len(x) for x in cmds])
        out.append(InstrumentObservations(kind, c, np.zeros((len(c), 3)) if kind == "rtest" else None,
                                          ids if kind == "sphere" else None, np.eye(3) if kind == "rtest" else None,
                                          DEFAULT_SIGMA[kind]))
    return out


def instrument_view(machine: Machine, kinds: Sequence[str]) -> dict:
    """Which groups and location errors each instrument of ``kinds`` sees alone, and the
    combination (unknowns = groups; for sphere and R-test alone also the location errors)."""
    st = machine.structure()
    out = {}
    sets = {k: _sample(machine, k) for k in kinds}
    for label, obs in list(sets.items()) + ([("combined", [o for k in kinds for o in sets[k]])] if len(kinds) > 1 else []):
        res_g = identify_mixed(machine, obs, unknowns="groups", structure=st, require_seen=False)
        entry = {
            "groups_seen": [n for n, s in zip(res_g.names, res_g.seen) if s],
            "groups_not_seen": [n for n, s in zip(res_g.names, res_g.seen) if not s],
        }
        res_l = identify_mixed(machine, obs, unknowns="location", structure=st, require_seen=False)
        entry["location_errors_seen"] = [n for n, s in zip(res_l.names, res_l.seen) if s]
        entry["location_errors_not_seen"] = [n for n, s in zip(res_l.names, res_l.seen) if not s]
        out[label] = entry
    return out


# ----- daily tracking with sphere-probing cycles ---------------------------------------------
def cycles_kind(path: Union[str, Path]) -> str:
    """The ``# kind`` of a cycles file (tracker when none is given)."""
    from .._files import read_text

    return _metadata(read_text(Path(path), "cycles")).get("kind", "tracker").lower()


def track_sphere(machine: Machine, path: Union[str, Path]) -> dict:
    """Sphere-probing cycles (``# kind = sphere``; columns ``cycle``, the joints, optional
    ``sphere``, ``time`` (h), ``temp_*``): the rotary-axis location errors of each cycle with
    their uncertainties, their drift from the first cycle, and a straight-line trend per error
    against time (or the cycle number)."""
    from .._files import read_text
    from .observations import _read_table

    p = Path(path)
    meta = _metadata(read_text(p, "cycles"))
    sigma = 1e-3 * float(meta.get("sigma_um", 1e3 * DEFAULT_SIGMA["sphere"]))
    if not (math.isfinite(sigma) and sigma > 0):
        raise InvalidInputError(f"{p}: sigma_um must be positive")
    header, data = _read_table(p)
    joints = machine.joint_names
    missing = [c for c in ["cycle", *joints] if c not in header]
    if missing:
        raise FileFormatError(f"{p}: missing column(s) {', '.join(missing)} (expected cycle, {', '.join(joints)}, optional sphere, time, temp_*)")
    extra = [c for c in header if c not in ["cycle", "sphere", "time", *joints] and not c.startswith("temp_")]
    if extra:
        raise FileFormatError(f"{p}: unknown column(s) {', '.join(extra)}")
    if len(data) == 0:
        raise FileFormatError(f"{p}: no data rows")
    col = {c: data[:, header.index(c)] for c in header}
    cyc = col["cycle"]
    if not np.allclose(cyc, np.round(cyc)):
        raise FileFormatError(f"{p}: the cycle column must hold whole numbers")
    ids = sorted({int(round(v)) for v in cyc})
    cmds_all = machine.commands_array(np.column_stack([col[j] for j in joints]), str(p))
    sph = col.get("sphere", np.zeros(len(cyc)))
    rows = []
    for cid in ids:
        sel = np.round(cyc) == cid
        obs = InstrumentObservations("sphere", cmds_all[sel], None, sph[sel].astype(np.int64), None, sigma, f"cycle {cid}")
        res = identify_mixed(machine, [obs], unknowns="location")
        entry = {"cycle": cid, "points": int(sel.sum()), "location_errors": res.location,
                 "residual_rms_um": res.instruments[0]["residual_rms_um"]}
        if "time" in col:
            entry["time"] = float(col["time"][sel].mean())
        temps = {c: float(col[c][sel].mean()) for c in header if c.startswith("temp_")}
        if temps:
            entry["temperatures"] = temps
        rows.append(entry)
    first = rows[0]["location_errors"]
    names = [k for k, v in first.items() if "value" in v]
    x = np.array([r.get("time", r["cycle"]) for r in rows], dtype=np.float64)
    trend = {}
    for k in names:
        y = np.array([r["location_errors"][k].get("value", np.nan) for r in rows])
        for r, v in zip(rows, y):
            if math.isfinite(v):
                r.setdefault("drift", {})[k] = float(v - first[k]["value"])
        ok = np.isfinite(y)
        if ok.sum() >= 2 and np.ptp(x[ok]) > 0:
            slope, icpt = np.polyfit(x[ok], y[ok], 1)
            trend[k] = {"per": "hour" if "time" in col else "cycle", "slope": float(slope), "intercept": float(icpt)}
    return {"kind": "sphere", "cycles": rows, "trend": trend, "sigma_um": 1e3 * sigma}
