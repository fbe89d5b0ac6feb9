"""GD&T inspection end to end: gagekit vs what a user would write with NumPy + SciPy.

The bundled bracket (python/gagekit/data/make_bracket.py) at ~2 M points, 12 callouts:
flatness of A, perpendicularity of B to A and of C to A|B, parallelism and profile of the
top to A, angularity of the chamfer to A, position (A|B|C) and perpendicularity (A) of the
bore, coaxiality / circular / total run-out of the upper boss to datum D, position of the
ball. End to end from the points in memory: regions, fits, datums, zones.

The peer: boolean masks for the boxes; datum planes and flatness by
scipy.optimize.linprog (HiGHS) on the zone LP in the least-squares frame (Eq. 5.13, the
dissertation's own formulation; the orthogonal width then recomputed along the LP's
normal); the secondary datum by the same 2-D LP; cylinders and spheres by
scipy.optimize.least_squares on the orthogonal distances; angularity by a turn grid and
scipy.optimize.minimize_scalar; run-outs and positions with NumPy. Datum D is a perfect
cylinder, so its least-squares axis is its minimum circumscribed one and both programs
must agree on every value.

Second case, sizes (ISO 14405-1): the LP two-point size callouts of bracket_sizes.toml (bore,
boss, pin: every two-point size, 10 sections x 180 directions per cylinder) on the same
~2 M points, end to end (regions, least-squares axes, sizes). The peer: boolean masks, the
least-squares axis by scipy.optimize.least_squares, then per section np.argsort by angle and
np.interp (periodic) for the opposite points -- the same definition.

Prints one line per case: case, gagekit time, peer time, ratio (peer / gagekit), then
every callout's value from both and the largest difference.
Run: python benches/bench_inspect.py [--quick]
"""

from __future__ import annotations

import importlib.util
import math
import os
import sys
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares, linprog, minimize_scalar

from gagekit.samples import data_path
from gagekit.inspect import inspect, load_part_spec
from gagekit.inspect.spec import PartSpec
from _timing import timed

CALLOUTS = [(0, "flatness"), (1, "perpendicularity"), (2, "perpendicularity"), (4, "parallelism"), (6, "profile"),
            (7, "angularity"), (8, "position"), (9, "perpendicularity"), (12, "coaxiality"), (13, "circular-runout"),
            (14, "total-runout"), (15, "position")]


def generator():
    spec = importlib.util.spec_from_file_location("make_bracket", data_path("make_bracket.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def twelve(spec: PartSpec) -> PartSpec:
    tols = tuple(spec.tolerances[i] for i, _ in CALLOUTS)
    assert [t.characteristic for t in tols] == [c for _, c in CALLOUTS]
    used = {t.feature for t in tols} | {spec.datums[d].feature for t in tols for d in t.datums}
    return PartSpec(spec.name, {k: v for k, v in spec.features.items() if k in used}, spec.datums, tols, spec.source)


# -- the peer ----------------------------------------------------------------------------


def rotvec(rv):
    r = np.asarray(rv, float)
    th = np.linalg.norm(r)
    if th == 0:
        return np.eye(3)
    k = r / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def box(pts, f):
    R = rotvec(f.region.rotation)
    local = (pts - np.array(f.region.center)) @ R
    return pts[np.all(np.abs(local) <= np.array(f.region.size) / 2, axis=1)]


def basis(n):
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def lp_zone(h, T):
    """min w s.t. 0 <= h - T s - c <= w (slopes s, offset c), HiGHS."""
    n, k = T.shape
    A = np.block([[-T, -np.ones((n, 1)), -np.ones((n, 1))], [T, np.ones((n, 1)), np.zeros((n, 1))]])
    b = np.concatenate([-h, h])
    cost = np.zeros(k + 2)
    cost[-1] = 1
    res = linprog(cost, A_ub=A, b_ub=b, bounds=[(None, None)] * (k + 2), method="highs")
    return res.x[:k]


def peer_plane(pts, out, perp=None):
    """Chebyshev tangent plane (free, or normal perpendicular to `perp`): normal out of the material."""
    c = pts.mean(0)
    q = pts - c
    if perp is None:
        n = np.linalg.svd(q, full_matrices=False)[2][2]
        u, v = basis(n)
        s = lp_zone(q @ n, np.column_stack([q @ u, q @ v]))
        n = n - s[0] * u - s[1] * v
    else:
        u, v = basis(perp)
        xy = np.column_stack([q @ u, q @ v])
        d = np.linalg.svd(xy - xy.mean(0), full_matrices=False)[2]
        t, m = d[0], d[1]
        s = lp_zone(xy @ m, (xy @ t)[:, None])
        m2 = m - s[0] * t
        n = m2[0] * u + m2[1] * v
    n /= np.linalg.norm(n)
    if n @ out < 0:
        n = -n
    h = pts @ n
    return n, h.max(), h.max() - h.min()


def peer_cylinder(pts, hint):
    c = pts.mean(0)
    a0 = hint / np.linalg.norm(hint)  # the nominal axis from the drawing as the start
    u, v = basis(a0)

    def res(x):
        p = c + x[0] * u + x[1] * v
        a = a0 + x[2] * u + x[3] * v
        a = a / np.linalg.norm(a)
        d = pts - p
        return np.linalg.norm(d - np.outer(d @ a, a), axis=1) - x[4]

    r0 = np.linalg.norm((pts - c) - np.outer((pts - c) @ a0, a0), axis=1).mean()
    x = least_squares(res, [0, 0, 0, 0, r0], method="lm").x
    a = a0 + x[2] * u + x[3] * v
    return c + x[0] * u + x[1] * v, a / np.linalg.norm(a)


def peer_sphere(pts):
    c0 = pts.mean(0)
    x = least_squares(lambda x: np.linalg.norm(pts - x[:3], axis=1) - x[3], [*c0, np.linalg.norm(pts - c0, axis=1).mean()],
                      method="lm").x
    return x[:3]


def peer(pts, spec: PartSpec) -> list[float]:
    F = spec.features
    P = {k: box(pts, f) for k, f in F.items()}
    nA, dA, flatA = peer_plane(P["A"], np.array(F["A"].outward))
    nB, dB, perpB = peer_plane(P["B"], np.array(F["B"].outward), perp=nA)
    nC = np.cross(nA, nB)
    nC = nC if nC @ np.array(F["C"].outward) > 0 else -nC
    hC = P["C"] @ nC
    dC = hC.max()
    N = np.array([nC, nB, nA])
    origin = np.linalg.solve(N, [dC, dB, dA])
    axes = -N  # x, y, z into the material
    frame_pt = lambda p: origin + np.asarray(p) @ axes  # noqa: E731
    frame_dir = lambda d: np.asarray(d) @ axes  # noqa: E731
    out = [flatA, perpB, float(np.ptp(hC))]
    top = P["top"] @ nA
    out.append(float(np.ptp(top)))
    t_prof = spec.tolerances[4]
    h = (P["top"] - frame_pt(t_prof.nominal_point)) @ frame_dir(t_prof.nominal_direction)
    out.append(2 * float(np.abs(h).max()))
    # angularity: normals 45 degrees from A's normal, turned about it
    ch = P["chamfer"]
    a = nA if np.array(F["chamfer"].outward) @ nA > 0 else -nA
    u, v = basis(a)
    ang = math.radians(spec.tolerances[5].angle)
    hu, hv, ha = ch @ u, ch @ v, ch @ a

    def width(f):
        d = math.cos(ang) * ha + math.sin(ang) * (math.cos(f) * hu + math.sin(f) * hv)
        return d.max() - d.min()

    grid = np.linspace(-math.pi, math.pi, 361)
    f0 = grid[np.argmin([width(f) for f in grid])]
    out.append(float(minimize_scalar(width, bounds=(f0 - 0.02, f0 + 0.02), method="bounded", options={"xatol": 1e-12}).fun))
    # bore: least-squares axis limited to the span
    p, d = peer_cylinder(P["bore"], np.array(F["bore"].direction))
    t = (P["bore"] - p) @ d
    ends = np.array([p + t.min() * d, p + t.max() * d])
    tp = spec.tolerances[6]
    P0, D0 = frame_pt(tp.nominal_point), frame_dir(tp.nominal_direction)
    w = ends - P0
    w = w - np.outer(w @ D0, D0)
    out.append(2 * float(np.linalg.norm(w, axis=1).max()))
    e = ends[1] - ends[0]
    out.append(float(np.linalg.norm(e - (e @ nA) * nA)))
    # datum D and the upper boss
    pD, dD = peer_cylinder(P["boss"], np.array(F["boss"].direction))
    p2, d2 = peer_cylinder(P["boss-top"], np.array(F["boss-top"].direction))
    t2 = (P["boss-top"] - p2) @ d2
    ends = np.array([p2 + t2.min() * d2, p2 + t2.max() * d2]) - pD
    out.append(2 * float(np.linalg.norm(ends - np.outer(ends @ dD, dD), axis=1).max()))
    q = P["boss-top"] - pD
    tq = q @ dD
    r = np.linalg.norm(q - np.outer(tq, dD), axis=1)
    k = np.minimum(((tq - tq.min()) / np.ptp(tq) * F["boss-top"].sections).astype(int), F["boss-top"].sections - 1)
    out.append(max(float(np.ptp(r[k == i])) for i in range(F["boss-top"].sections) if (k == i).sum() >= 2))
    out.append(float(np.ptp(r)))
    # ball: least-squares centre against its basic position
    c = peer_sphere(P["ball"])
    out.append(2 * float(np.linalg.norm(c - frame_pt(spec.tolerances[11].nominal_point))))
    return out


def lp_sizes(spec: PartSpec) -> PartSpec:
    """The LP two-point size callouts of a drawing (no envelope: only the two-point sizes)."""
    tols = tuple(replace(t, envelope=False) for t in spec.tolerances
                 if t.characteristic == "size" and (t.modifier or "LP") == "LP")
    used = {t.feature for t in tols}
    return PartSpec(spec.name, {k: v for k, v in spec.features.items() if k in used}, spec.datums, tols, spec.source)


def peer_two_point(pts, p, d, ref, sections, angles):
    d = d / np.linalg.norm(d)
    u = ref - (ref @ d) * d
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    q = pts - p
    t, x, y = q @ d, q @ u, q @ v
    th, rho = np.arctan2(y, x), np.hypot(x, y)
    span = np.ptp(t)
    k = np.minimum(((t - t.min()) / span * sections).astype(int), sections - 1) if span > 0 else np.zeros(len(t), int)
    phi = -np.pi + np.pi * np.arange(angles) / angles
    out = []
    for i in range(sections):
        m = k == i
        o = np.argsort(th[m])
        a, r = th[m][o], rho[m][o]
        out.append(np.interp(phi, a, r, period=2 * np.pi) + np.interp(phi + np.pi, a, r, period=2 * np.pi))
    return np.concatenate(out)


def peer_sizes(pts, spec: PartSpec) -> list[float]:
    out = []
    for t in spec.tolerances:
        f = spec.features[t.feature]
        P = box(pts, f)
        ref = rotvec(f.region.rotation)[:, 0]
        if f.shape == "circle":
            c = P.mean(0)
            n = np.linalg.svd(P - c, full_matrices=False)[2][2]
            x = least_squares(lambda z: np.linalg.norm(P - (c + z[0] * basis(n)[0] + z[1] * basis(n)[1]), axis=1) - z[2],
                              [0, 0, np.linalg.norm(P - c, axis=1).mean()], method="lm").x
            p = c + x[0] * basis(n)[0] + x[1] * basis(n)[1]
            s = peer_two_point(P, p, n, ref, 1, 180)
        else:
            p, d = peer_cylinder(P, np.array(f.direction))
            s = peer_two_point(P, p, d, ref, t.sections or f.sections, 180)
        U, L = t.upper_limit, t.lower_limit
        out.append(float(s.max() if U - s.max() <= s.min() - L else s.min()))
    return out


def main() -> None:
    quick = "--quick" in sys.argv
    density = 3.0 if quick else 70.0
    gen = generator()
    pts = gen.make_bracket(density)
    spec = twelve(load_part_spec(data_path("bracket.toml")))
    t_g, res = timed(lambda: inspect(pts, spec), 1 if quick else 3)
    t_p, ref = timed(lambda: peer(pts, spec), 1)
    ours = [t.measured for t in res.tolerances]
    diff = max(abs(a - b) for a, b in zip(ours, ref))
    print(f"threads: {os.cpu_count()} cores visible, RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'default')}")
    print(f"{'case':48s} {'gagekit s':>10s} {'peer s':>10s} {'ratio':>7s}")
    print(f"{f'bracket {len(pts)} points, 12 callouts end to end':48s} {t_g:10.3f} {t_p:10.3f} {t_p / t_g:7.1f}")
    print(f"\n{'callout':40s} {'gagekit (mm)':>16s} {'peer (mm)':>16s} {'|diff|':>9s}")
    for t, a, b in zip(res.tolerances, ours, ref):
        print(f"{t.characteristic + ' of ' + t.feature + ('|' + '|'.join(t.datums) if t.datums else ''):40s} {a:16.12f} {b:16.12f} {abs(a - b):9.1e}")
    print(f"largest difference: {diff:.2e} mm")
    # sizes: every two-point size of the LP callouts
    sspec = lp_sizes(load_part_spec(data_path("bracket_sizes.toml")))
    t_s, sres = timed(lambda: inspect(pts, sspec), 1 if quick else 3)
    t_sp, sref = timed(lambda: peer_sizes(pts, sspec), 1)
    n_sizes = sum(t.extra["local_sizes"]["n"] for t in sres.tolerances)
    print(f"\n{'case':48s} {'gagekit s':>10s} {'peer s':>10s} {'ratio':>7s}")
    case = f"sizes {len(pts)} points, {len(sres.tolerances)} LP callouts, {n_sizes} two-point sizes"
    print(f"{case:48s} {t_s:10.3f} {t_sp:10.3f} {t_sp / t_s:7.1f}")
    for t, b in zip(sres.tolerances, sref):
        print(f"{t.name or t.feature:40s} {t.measured:16.12f} {b:16.12f} {abs(t.measured - b):9.1e}")


if __name__ == "__main__":
    main()
