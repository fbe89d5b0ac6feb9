"""Virtual-gage analysis speed: gagekit vs a NumPy + Qhull + HiGHS pipeline.

Cases (one line each: case, gagekit time, peer time, ratio peer / gagekit):

* ``lp filtered``: the linearised LP of Eq. 5.11 on the hull vertices of the
  bundled ``casting_ok`` scan; clarabel (assembly in Rust included) vs
  ``scipy.optimize.linprog(method="highs")`` on the same prebuilt matrix.
* ``lp unfiltered``: the same LP on every point of the sampling volumes of a
  denser simulated scan (about 10^5 rows), clarabel on the whole LP and with
  constraint generation (the default above 4000 points).
* ``end to end``: a simulated 14-million-point casting in the part frame
  (the dissertation's scan size): cut the regions, hull-filter them, solve
  Eq. 5.11 to convergence. Peer: NumPy masks, ``scipy.spatial.ConvexHull``
  (Qhull), HiGHS re-linearised with a NumPy assembly. The file read is excluded.

    python benches/bench_gage.py [--points 14000000] [--quick]
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import csc_matrix
from scipy.spatial import ConvexHull

import gagekit
from gagekit import _core
from gagekit.data.make_castings import make_casting
from gagekit.gage import build_problem, solve_problem
from gagekit.gage.align import apply
from _timing import timed


def line(case, tg, tp, peer):
    print(f"{case:<44}{tg:>10.4f}{tp:>10.4f}{tp / tg:>8.1f}  {peer}")


def highs_lp(args, params):
    lp = _core._testing.gage_lp(*args, params)
    c, colptr, rowval, nzval, b, m = lp.c, lp.colptr, lp.rowval, lp.nzval, lp.b, lp.nrows
    A = csc_matrix((nzval, rowval, colptr), shape=(m, len(c)))
    return c, A, np.asarray(b)


def bench_lp(label, args, repeat, generate=True):
    params = [0.0] * 6
    c, A, b = highs_lp(args, params)
    tg, sol = timed(lambda: _core._testing.gage_lp_solve(*args, params, generate=generate), repeat)
    x, obj, status, rows = sol.x, sol.objective, sol.status, sol.nrows
    tp, res = timed(lambda: linprog(c, A_ub=A, b_ub=b, bounds=(None, None), method="highs"), repeat)
    assert status == "solved" and res.status == 0 and abs(obj - res.fun) <= 1e-6 * (1 + abs(res.fun))
    how = "" if rows == A.shape[0] else f", clarabel on {rows} generated rows"
    line(f"{label} ({A.shape[0]} rows)", tg, tp, f"scipy linprog HiGHS, same matrix{how}")


# ---------------------------------------------------------------- the peer pipeline


def _rot_and_grads(p):
    def rz(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]), np.array([[-s, -c, 0], [c, -s, 0], [0, 0, 0.0]])

    def ry(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]]), np.array([[-s, 0, c], [0, 0, 0.0], [-c, 0, -s]])

    def rx(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]]), np.array([[0, 0, 0.0], [0, -s, -c], [0, c, -s]])

    (Z, dZ), (Y, dY), (X, dX) = rz(p[0]), ry(p[1]), rx(p[2])
    return Z @ Y @ X, [dZ @ Y @ X, Z @ dY @ X, Z @ Y @ dX]


def peer_solve(sets, planes, f, g, free, max_angle, max_shift, max_iter=20):
    """Eq. 5.11 re-linearised about the exact transform, assembled with NumPy, solved by HiGHS."""
    k = len(sets)
    fi = [m for m in range(6) if free[m]]
    nf = len(fi)
    p = np.zeros(6)
    for _ in range(max_iter):
        R, dR = _rot_and_grads(p)
        rows, rhs = [], []
        for i, (r, pl) in enumerate(zip(sets, planes)):
            n, d = pl[:3], pl[3]
            e0 = r @ (R.T @ n) + n @ p[3:] + d
            J = np.column_stack([r @ (dR[m].T @ n) if m < 3 else np.full(len(r), n[m - 3]) for m in fi])
            blk = np.zeros((2 * len(r), nf + 2 * k + 1))
            blk[: len(r), :nf], blk[: len(r), nf + i] = J, -1.0
            blk[len(r):, :nf], blk[len(r):, nf + k + i] = -J, -1.0
            rows.append(blk)
            rhs.append(np.concatenate([-e0, e0]))
        su = np.zeros((k, nf + 2 * k + 1))
        su[np.arange(k), nf + k + np.arange(k)] = 1.0
        su[:, -1] = -1.0
        A = np.vstack(rows + [su])
        b = np.concatenate(rhs + [np.zeros(k)])
        c = np.concatenate([np.zeros(nf), f, g, [1.0]])
        bounds = [(-(max_angle if m < 3 else max_shift) - p[m], (max_angle if m < 3 else max_shift) - p[m]) for m in fi]
        bounds += [(None, None)] * k + [(0, None)] * k + [(0, None)]
        res = linprog(c, A_ub=csc_matrix(A), b_ub=b, bounds=bounds, method="highs")
        assert res.status == 0, res.message
        step = res.x[:nf]
        p[fi] += step
        if np.abs(step).max() < 1e-10:
            break
    return p, res.fun


def peer_pipeline(pts, spec):
    sets = {}
    for r in spec.regions:
        b = r.box
        m = np.all(np.abs(pts - np.asarray(b.center)) <= 0.5 * np.asarray(b.size), axis=1)
        sub = pts[m]
        sets[r.name] = sub[ConvexHull(sub).vertices]
    gs = spec.gages
    return peer_solve([sets[g.region] for g in gs], np.array([g.plane for g in gs]),
                      np.array([g.weight for g in gs]), np.array([g.slack_weight for g in gs]),
                      spec.motion.flags(), spec.motion.max_angle, spec.motion.max_shift)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--points", type=float, default=14e6)
    ap.add_argument("--quick", action="store_true", help="1.4 M points end to end")
    args = ap.parse_args()
    npts = 1.4e6 if args.quick else args.points
    print(f"{'case':<44}{'gagekit s':>10}{'peer s':>10}{'ratio':>8}  peer")

    pts, doc = make_casting("casting_ok")
    prob = build_problem(pts, gagekit.GageSpec.from_dict(doc))
    bench_lp("lp filtered", prob.args(), 20)

    # unfiltered: every point of the sampling volumes of a denser scan
    pts, doc = make_casting("casting_ok", density=4.0)
    spec = gagekit.GageSpec.from_dict(doc)
    prob = build_problem(pts, spec)
    from gagekit.gage.analysis import box_in_scanner

    boxes = [box_in_scanner(spec.region(g.region).box, prob.alignment.frame) for g in spec.gages]
    idx = gagekit.classify(pts, boxes)
    raw = [apply(prob.alignment.H, pts[i]) for i in idx]
    offsets = np.concatenate([[0], np.cumsum([len(r) for r in raw])]).tolist()
    unf = (np.ascontiguousarray(np.vstack(raw)), offsets, *prob.args()[2:])
    bench_lp("lp unfiltered, whole LP", unf, 3, generate=False)
    bench_lp("lp unfiltered", unf, 3)

    # end to end on a big scan, in the part frame (no alignment: both pipelines do the same steps)
    density = 1.5 * npts / 120_000
    pts, doc = make_casting("casting_ok", density=density)
    pts = apply(build_problem(pts, gagekit.GageSpec.from_dict(doc)).alignment.H, pts)
    doc = {k: v for k, v in doc.items() if k != "alignment"}
    doc["region"] = [r for r in doc["region"] if r["frame"] == "part"]
    spec = gagekit.GageSpec.from_dict(doc)
    tg, res = timed(lambda: solve_problem(build_problem(pts, spec)))
    tp, (p, fun) = timed(lambda: peer_pipeline(pts, spec))
    assert abs(fun - res.objective) < 1e-6 * (1 + abs(fun)), (fun, res.objective)
    line(f"end to end ({len(pts) / 1e6:.1f} M points)", tg, tp, "numpy masks + scipy ConvexHull (Qhull) + HiGHS SLP")


if __name__ == "__main__":
    main()
