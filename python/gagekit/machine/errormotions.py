"""Per-element error motions of the first-order model and their composition (Sec. 3.1).

Every element of the chain (Eq. 3.1) carries a small rigid error motion, a twist (omega, t):
omega a small rotation (about x, y, z; rad), t a translation (mm). Where it acts:

- shape T_i (Eq. 3.2): after the nominal offset, omega = (gamma, beta, alpha), t = (dx, dy, dz);
- prismatic joint with axis u at command s (Eq. 3.3 for any axis): in its moving frame,
  omega = s eps' with eps' = (dgamma, dbeta, dalpha), t = s delta u + s^2/2 eps' x u;
- rotary joint with axis a at angle theta (Eq. 3.5, 3.6, ERRATA 8, first order): in its fixed
  frame (before the rotation), omega = sum_n w_n (gamma.n, beta.n, alpha.n),
  t = sum_n w_n (dx.n, dy.n, dz.n), w_n = sin(n theta / 2).

A twist attached to the chain frame F = A_1 ... A_k (rotation R, origin o) moves the target
P by omega_w x (P - o) + R t, omega_w = R omega; the volumetric error (Eq. 3.9) is the sum over
the elements. This is exactly the first-order model the Rust kernel differentiates (M p,
Eq. 3.13); :func:`compose` rebuilds it from twists, which is how the controller tables of
:mod:`gagekit.machine.export` are read back.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from .._rotation import rotations_about
from .model import JointSpec, Machine, ShapeSpec

__all__ = ["Twist", "element_twists", "frames", "compose", "transport"]


@dataclass(frozen=True)
class Twist:
    """Small error motions (n, 6): omega (rad, about x, y, z), then t (mm), attached to the
    chain frame after element ``index`` (``side="after"``) or before it (``"before"``)."""

    index: int
    side: str
    values: np.ndarray


def _element_transforms(machine: Machine, commands: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Nominal (rotation (n,3,3), translation (n,3)) of every element at ``commands`` (internal units)."""
    n = commands.shape[0]
    out = []
    j = 0
    for e in machine.elements:
        if isinstance(e, ShapeSpec):
            out.append((np.broadcast_to(np.eye(3), (n, 3, 3)), np.broadcast_to(np.asarray(e.offset), (n, 3))))
            continue
        q = commands[:, j]
        j += 1
        u = np.asarray(e.axis, dtype=np.float64)
        if e.kind == "prismatic":
            out.append((np.broadcast_to(np.eye(3), (n, 3, 3)), q[:, None] * u))
        else:
            out.append((rotations_about(u, q), np.zeros((n, 3))))
    return out


def frames(machine: Machine, commands) -> tuple[list, np.ndarray]:
    """Chain frames F_0 = I, F_k = A_1 ... A_k at ``commands`` (file units) as a list of
    (R (n,3,3), o (n,3)), and the nominal target P (n, 3) in the table frame."""
    c = machine.commands_array(commands) * machine._angle_factor()
    n = c.shape[0]
    r = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    o = np.zeros((n, 3))
    out = [(r, o)]
    for rot, tr in _element_transforms(machine, c):
        o = o + np.einsum("nij,nj->ni", r, tr)
        r = r @ rot
        out.append((r, o))
    p = o + np.einsum("nij,j->ni", r, np.asarray(machine.tool))
    return out, p


def element_twists(machine: Machine, params, commands) -> list[Twist]:
    """The error twist of every element (chain order) for the parameter vector ``params`` at
    ``commands`` (file units); see the module docstring for the convention."""
    p = np.asarray(params, dtype=np.float64).reshape(-1)
    names = machine.parameter_names
    value = dict(zip(names, p))
    c = machine.commands_array(commands) * machine._angle_factor()
    n = c.shape[0]
    out = []
    j = 0
    for k, e in enumerate(machine.elements):
        v = np.zeros((n, 6))
        if isinstance(e, ShapeSpec):
            g = lambda s: value.get(f"{e.name}.{s}", 0.0)  # noqa: E731
            v[:] = [g("gamma"), g("beta"), g("alpha"), g("dx"), g("dy"), g("dz")]
            out.append(Twist(k, "after", v))
            continue
        q = c[:, j]
        j += 1
        u = np.asarray(e.axis, dtype=np.float64)
        if e.kind == "prismatic":
            g = lambda s: value.get(f"{e.name}.{s}", 0.0)  # noqa: E731
            eps = np.array([g("dgamma"), g("dbeta"), g("dalpha")])
            v[:, :3] = q[:, None] * eps
            v[:, 3:] = q[:, None] * g("delta") * u + 0.5 * (q**2)[:, None] * np.cross(eps, u)
            out.append(Twist(k, "after", v))
        else:
            for t in range(1, e.terms + 1):
                g = lambda s: value.get(f"{e.name}.{s}.{t}", 0.0)  # noqa: E731
                w = np.sin(t * q / 2.0)[:, None]
                v += w * np.array([g("gamma"), g("beta"), g("alpha"), g("dx"), g("dy"), g("dz")])
            out.append(Twist(k, "before", v))
    return out


def transport(values: np.ndarray, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """A twist attached to frame F_a = F_b T, T = (rotation Q, translation c), expressed in
    F_b: omega' = Q omega, t' = Q t - (Q omega) x c (same effect on every point)."""
    v = np.asarray(values, dtype=np.float64)
    w = np.einsum("...ij,...j->...i", rotation, v[..., :3])
    t = np.einsum("...ij,...j->...i", rotation, v[..., 3:]) - np.cross(w, translation)
    return np.concatenate([w, t], axis=-1)


def compose(machine: Machine, twists: list[Twist], commands, chain: Optional[tuple] = None) -> np.ndarray:
    """Volumetric error (n, 3), mm, table frame, of the twists at ``commands`` (file units):
    sum of omega_w x (P - o) + R t over the twists (first order, Eq. 3.9)."""
    fr, p = chain if chain is not None else frames(machine, commands)
    e = np.zeros_like(p)
    for tw in twists:
        r, o = fr[tw.index + 1] if tw.side == "after" else fr[tw.index]
        v = np.asarray(tw.values, dtype=np.float64)
        v = np.broadcast_to(v, (p.shape[0], 6))
        w = np.einsum("nij,nj->ni", r, v[:, :3])
        e += np.cross(w, p - o) + np.einsum("nij,nj->ni", r, v[:, 3:])
    return e


def joint_index(machine: Machine) -> dict:
    """{joint name: element index} in the chain."""
    return {e.name: k for k, e in enumerate(machine.elements) if isinstance(e, JointSpec)}
