"""Optimal-design search: gagekit (Rust exchange with low-rank updates, multistart with
iterated local search, rayon)
against a plain one-point-at-a-time exchange written here in NumPy (exact criterion for every
candidate, vectorised over the candidates; single start).

    python benches/bench_design.py [--candidates 20000] [--points 80] [--starts 4]

One line per case: case, gagekit time (and CPU time), peer time, ratio (peer / gagekit), and
the objective each reached (lower is better; E: 1 / smallest eigenvalue, I: tr(W F^-1) with W
the mean information of the candidates). The peer's K search evaluates every candidate exactly with a
batched eigen-decomposition, which is slow: it gets a time budget (--peer-budget seconds) and
reports what it reached by then.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gagekit import _core, optimal_design
from gagekit.machine import example_machine_path, load_machine
from gagekit.machine.observer import ObserverSpace


def objective(F: np.ndarray, crit: str, W: np.ndarray | None = None) -> float:
    ev = np.linalg.eigvalsh(F)
    if ev[0] <= 1e-12 * ev[-1]:
        return np.inf
    if crit == "I":
        return float(np.sum(W * np.linalg.inv(F)))
    return {"A": np.sum(1 / ev), "D": -np.sum(np.log(ev)), "K": np.sqrt(ev[-1] / ev[0]), "E": 1 / ev[0]}[crit]


def peer_exchange(B: np.ndarray, n: int, crit: str, seed: int, budget: float,
                  W: np.ndarray | None = None) -> tuple[float, float]:
    """Plain Fedorov exchange: visit each point, try every candidate, keep the best; repeat."""
    N, r, k = B.shape
    rng = np.random.default_rng(seed)
    design = rng.choice(N, n)
    F = np.einsum("nrk,nrl->kl", B[design], B[design])
    t0 = time.perf_counter()
    cur = objective(F, crit, W)
    improved = True
    while improved and time.perf_counter() - t0 < budget:
        improved = False
        for i in range(n):
            O = B[design[i]]
            if crit in "KE":
                vals = np.full(N, np.inf)
                for s in range(0, N, 2000):  # batched exact eigenvalues of every exchanged F
                    Fs = F - O.T @ O + np.einsum("nrk,nrl->nkl", B[s : s + 2000], B[s : s + 2000])
                    ev = np.linalg.eigvalsh(Fs)
                    ok = ev[:, 0] > 1e-12 * ev[:, -1]
                    vals[s : s + 2000][ok] = np.sqrt(ev[ok, -1] / ev[ok, 0]) if crit == "K" else 1 / ev[ok, 0]
            else:
                Finv = np.linalg.inv(F)
                U = np.concatenate([B, np.broadcast_to(O, B.shape)], axis=1)  # (N, 2r, k)
                FU = U @ Finv  # (N, 2r, k)
                S = FU @ U.transpose(0, 2, 1)
                S[:, :r, :r] += np.eye(r)
                S[:, r:, r:] -= np.eye(r)
                if crit == "D":
                    sign, logabs = np.linalg.slogdet(S)
                    ratio_ok = sign * (-1) ** r > 0
                    vals = np.where(ratio_ok, cur - logabs, np.inf)
                else:
                    E = FU @ (FU if W is None else FU @ W).transpose(0, 2, 1)
                    vals = cur - np.trace(np.linalg.solve(S, E), axis1=1, axis2=2)
            j = int(np.argmin(vals))
            if vals[j] < cur - 1e-10 * abs(cur):
                F = F - O.T @ O + B[j].T @ B[j]
                design[i] = j
                cur = objective(F, crit, W)
                improved = True
            if time.perf_counter() - t0 > budget:
                break
    return time.perf_counter() - t0, cur


def line_case() -> None:
    line = lambda X: np.stack([X[:, 0], np.ones(len(X))], 1)[:, None, :]
    from scipy.optimize import minimize

    for crit in "ADK":
        t = time.perf_counter()
        r = optimal_design(line, [[0, 1]], 4, crit)
        tg = time.perf_counter() - t
        # peer: scipy multistart L-BFGS-B on the 4 continuous positions (as the dissertation's fmincon)
        def f(x):
            M = np.stack([x, np.ones(4)], 1)
            return objective(M.T @ M, crit) if crit != "D" else np.exp(objective(M.T @ M, "D"))
        t = time.perf_counter()
        rng = np.random.default_rng(0)
        best = min((minimize(f, rng.random(4), bounds=[(0, 1)] * 4, method="L-BFGS-B") for _ in range(20)), key=lambda o: o.fun)
        tp = time.perf_counter() - t
        peer_obj = best.fun if crit != "D" else np.log(best.fun)
        print(f"table-4.1 {crit}: gagekit {tg:.3f} s, scipy multistart {tp:.3f} s, ratio {tp / tg:.1f}; "
              f"objective {r.objective:.4f} vs {peer_obj:.4f}")


def machine_case(n_cand: int, n: int, starts: int, budget: float, crits: str) -> None:
    m = load_machine(example_machine_path())
    space = ObserverSpace.of(m)
    X = space.to_u(m.sample_commands(n_cand, seed=1))
    B = space.rows(X)
    flat = np.ascontiguousarray(B.reshape(-1, B.shape[2]))
    # I: average prediction variance over the candidates, W = mean of B_j^T B_j / r
    W = np.einsum("nrk,nrl->kl", B, B) / (n_cand * B.shape[1])
    for crit in crits:
        w = W if crit == "I" else None
        t, c = time.perf_counter(), time.process_time()
        out = _core.design.search(flat, 3, [np.arange(n_cand)], [0] * n, crit, weights=w, starts=starts, seed=0)
        tg, cg = time.perf_counter() - t, time.process_time() - c
        tp, peer = peer_exchange(B, n, crit, 0, budget, w)
        print(f"machine {n}-point {crit} from {n_cand} candidates ({starts} starts): gagekit {tg:.2f} s "
              f"({cg:.1f} s CPU), plain exchange {tp:.2f} s, ratio {tp / tg:.1f}; "
              f"objective {out.objective:.6g} vs {peer:.6g}"
              + (" (peer stopped at its time budget)" if tp >= budget else ""), flush=True)


def plan_case(n_cand: int, n: int, starts: int, criteria: str) -> None:
    """The whole `gagekit machine design` path: candidates, exchange, continuous refinement of
    every point inside its bounds (or zone), figures of the plan and of the quasi-random plans."""
    from gagekit.machine.observer import design_observer

    m = load_machine(example_machine_path())
    for crit in criteria:
        for zones in ("none", "dissertation-8"):
            t0 = time.perf_counter()
            plan = design_observer(m, n, crit, zones=zones, candidates=n_cand, starts=starts, seed=0)
            dt = time.perf_counter() - t0
            print(f"machine design {n}-point {crit} plan, {zones} zones, {n_cand} candidates, whole command "
                  f"(exchange + refinement): {dt:.2f} s; tr {plan.figures['trace']:.6g}, "
                  f"log det {plan.figures['log_det']:.6g}, kappa {plan.figures['condition_number']:.6g}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--candidates", type=int, default=20000)
    ap.add_argument("--points", type=int, default=80)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--peer-budget", type=float, default=120.0)
    ap.add_argument("--criteria", default="DAKEI", help="machine cases to run (letters of A, D, K, E, I)")
    a = ap.parse_args()
    line_case()
    machine_case(a.candidates, a.points, a.starts, a.peer_budget, a.criteria.upper())
    plan_case(a.candidates, a.points, a.starts, a.criteria.upper())


if __name__ == "__main__":
    main()
