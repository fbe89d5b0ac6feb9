"""Design-matrix assembly (Eq. 3.13) for the example machine: gagekit (Rust, rayon) against a
vectorised NumPy implementation of the same analytic derivatives, written here.

    python benches/bench_machine.py [--sizes 100000 300000 1000000]

Prints one line per case: case, gagekit time, peer time, ratio (peer / gagekit). The NumPy
result is checked against gagekit's before timing.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import gagekit
from _timing import timed

EXAMPLE = gagekit.machine.example_machine_path()


def _rot(axis: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations about the unit axis by angles theta (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def numpy_design_matrix(machine: gagekit.Machine, commands: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The same first-order derivatives as gagekit-kinematics, vectorised over commands."""
    cmd = commands * machine._angle_factor()
    n = cmd.shape[0]
    elems, jidx = [], 0
    for e in machine.elements:
        if isinstance(e, gagekit.ShapeSpec):
            elems.append(("shape", None, np.asarray(e.offset), 0, None))
        else:
            elems.append((e.kind, np.asarray(e.axis), None, e.terms, cmd[:, jidx]))
            jidx += 1
    # nominal element transforms; None rotation = identity
    rots, trans = [], []
    for kind, axis, off, _, s in elems:
        if kind == "shape":
            rots.append(None)
            trans.append(np.broadcast_to(off, (n, 3)))
        elif kind == "prismatic":
            rots.append(None)
            trans.append(s[:, None] * axis)
        else:
            rots.append(_rot(axis, s))
            trans.append(np.zeros((n, 3)))
    prefix, r = [], np.broadcast_to(np.eye(3), (n, 3, 3))
    for ra in rots:
        prefix.append(r)
        if ra is not None:
            r = r @ ra
    levers = [None] * len(elems)
    v = np.broadcast_to(np.asarray(machine.tool), (n, 3))
    for k in range(len(elems) - 1, -1, -1):
        q = v if rots[k] is None else np.einsum("nij,nj->ni", rots[k], v)
        levers[k] = np.einsum("nij,nj->ni", prefix[k], q)
        v = q + trans[k]
    p = machine.n_parameters
    m = np.empty((n, 3, p)) if out is None else out.reshape(n, 3, p)
    col = 0
    for k, (kind, axis, _, terms, s) in enumerate(elems):
        rk = prefix[k]
        if kind == "shape":
            for ax in (2, 1, 0):
                m[:, :, col] = np.cross(rk[:, :, ax], levers[k])
                col += 1
            for ax in range(3):
                m[:, :, col] = rk[:, :, ax]
                col += 1
        elif kind == "prismatic":
            u = np.einsum("nij,j->ni", rk, axis)
            arm = levers[k] * s[:, None] + u * (0.5 * s * s)[:, None]
            for ax in (2, 1, 0):
                m[:, :, col] = np.cross(rk[:, :, ax], arm)
                col += 1
            m[:, :, col] = u * s[:, None]
            col += 1
        else:
            for t in range(1, terms + 1):
                w = np.sin(t * s / 2.0)[:, None]
                for ax in (2, 1, 0):
                    m[:, :, col] = np.cross(rk[:, :, ax], levers[k]) * w
                    col += 1
                for ax in range(3):
                    m[:, :, col] = rk[:, :, ax] * w
                    col += 1
    return m.reshape(3 * n, p)


def numpy_chunked(machine, commands, chunk=100_000):
    out = np.empty((3 * commands.shape[0], machine.n_parameters))
    for i in range(0, commands.shape[0], chunk):
        numpy_design_matrix(machine, commands[i : i + chunk], out[3 * i : 3 * (i + chunk)])
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 300_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    m = gagekit.load_machine(EXAMPLE)
    small = m.sample_commands(2000, seed=1)
    assert np.allclose(numpy_design_matrix(m, small), m.design_matrix(small), rtol=1e-12, atol=1e-9)
    print(f"# threads: RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')} of {os.cpu_count()} cores; machine {m.name}, {m.n_parameters} parameters")
    print(f"{'case':<40} {'gagekit [s]':>12} {'numpy [s]':>12} {'ratio':>8}")
    for n in a.sizes:
        c = m.sample_commands(n, seed=2)
        tg, _ = timed(lambda: m.design_matrix(c), a.repeat)
        tn, _ = timed(lambda: numpy_chunked(m, c), max(1, a.repeat - 1))
        print(f"{f'design matrix {n} cmds ({3 * n}x{m.n_parameters})':<40} {tg:12.4f} {tn:12.4f} {tn / tg:8.1f}")


if __name__ == "__main__":
    main()
