"""Scan-to-CAD distances: gagekit vs Open3D's RaycastingScene and CloudCompare's C2M.

Model: a closed torus (R = 100 mm, r = 30 mm) of 1 M triangles, written as a binary STL.
Scan: 14 M points near its surface in scan-line order (u, v), normal offsets N(0, 0.2 mm)
plus 2 % far points (up to 5 mm), written as a binary PLY (float64). Cases:

- ``signed distances``: in memory, mesh arrays and points in, one signed distance per point
  out, acceleration structure built inside the timing: gagekit (``gagekit._core.mesh.Mesh``,
  BVH + exact point-triangle distance + pseudonormal sign) vs Open3D
  ``RaycastingScene.add_triangles`` + ``compute_signed_distance`` (float32 inside);
- ``C2M command line``: files in, distances out: ``gagekit compare SCAN MESH --deviations
  OUT.npy`` vs ``CloudCompare -SILENT -O SCAN -O MESH -C2M_DIST`` (Debian's cloudcompare,
  headless), each as its own process;
- ``best-fit``: 1 M points of a 100 k-triangle torus whose tube radius varies (no symmetry) moved by a random rigid motion (any
  rotation, 500 mm), from that pose: gagekit's robust best fit (principal axes + flips, ICP);
  no peer converges from an arbitrary pose (Open3D's ICP needs an initial guess).

Agreement: the largest |difference| of the distances, gagekit vs each peer.
Prints one line per case: case, gagekit time, peer time, ratio (peer / gagekit).
Run: python benches/bench_compare.py [--quick] [--cases distances,c2m,best-fit]   (--quick: 1.4 M points, 100 k triangles)
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _timing import timed


def tube(u, v, bumpy: bool, r: float = 30.0):
    """The tube radius: constant, or varying with u and v (no symmetry: a unique best fit)."""
    return r + (5.0 * np.cos(u) + 3.0 * np.sin(v + 2.0 * u) if bumpy else 0.0 * u)


def torus(n_u: int, n_v: int, R: float = 100.0, bumpy: bool = False):
    u = np.linspace(0, 2 * np.pi, n_u, endpoint=False)
    v = np.linspace(0, 2 * np.pi, n_v, endpoint=False)
    U, V = np.meshgrid(u, v, indexing="ij")
    r = tube(U, V, bumpy)
    verts = np.column_stack([((R + r * np.cos(V)) * np.cos(U)).ravel(), ((R + r * np.cos(V)) * np.sin(U)).ravel(),
                             (r * np.sin(V)).ravel()])
    i, j = np.meshgrid(np.arange(n_u), np.arange(n_v), indexing="ij")
    a = (i * n_v + j).ravel()
    b = (((i + 1) % n_u) * n_v + j).ravel()
    c = (((i + 1) % n_u) * n_v + (j + 1) % n_v).ravel()
    d = (i * n_v + (j + 1) % n_v).ravel()
    tris = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return verts, tris.astype(np.int64)


def scan(n: int, seed: int, R: float = 100.0, bumpy: bool = False) -> np.ndarray:
    rng = np.random.default_rng(seed)
    rows = int(math.sqrt(n / 3))
    u = np.repeat(np.linspace(0, 2 * np.pi, rows, endpoint=False), n // rows + 1)[:n]
    v = np.tile(np.linspace(0, 2 * np.pi, n // rows + 1, endpoint=False), rows)[:n]
    h = rng.normal(0, 0.2, n)
    far = rng.random(n) < 0.02
    h[far] = rng.uniform(-5, 5, far.sum())
    rr = tube(u, v, bumpy) + h
    return np.column_stack([(R + rr * np.cos(v)) * np.cos(u), (R + rr * np.cos(v)) * np.sin(u), rr * np.sin(v)])


def write_stl(path: Path, v: np.ndarray, t: np.ndarray) -> None:
    c = v[t]
    rec = np.zeros(len(t), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"] = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    rec["v"] = c
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + np.uint32(len(t)).tobytes())
        rec.tofile(fh)


def timed_cpu(fn):
    """(wall s, CPU s of the process in all threads, the result) of one run of ``fn``."""
    c0 = time.process_time()
    t, out = timed(fn)
    return t, time.process_time() - c0, out


def cpu_line(cpu: float) -> None:
    print(f"#   gagekit CPU {cpu:.3f} s in all threads, load average {os.getloadavg()[0]:.1f}")


def line(case: str, ours: float, peer: float | None) -> None:
    if peer is None:
        print(f"{case:58s} gagekit {ours:8.3f} s   peer      n/a")
    else:
        print(f"{case:58s} gagekit {ours:8.3f} s   peer {peer:8.3f} s   ratio {peer / ours:6.2f}")


def main() -> None:
    from gagekit import _core
    from gagekit.cad import read_cad

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="1.4 M points, 100 k triangles")
    ap.add_argument("--cases", default="distances,c2m,best-fit", help="comma separated: distances, c2m, best-fit")
    args = ap.parse_args()
    quick = args.quick
    n_pts = 1_400_000 if quick else 14_000_000
    nu, nv = (500, 100) if quick else (1000, 500)
    work = Path(tempfile.mkdtemp(prefix="bench_compare."))
    try:
        v, t = torus(nu, nv)
        stl = work / "torus.stl"
        write_stl(stl, v, t)
        model = read_cad(stl)  # float32 corners, as every peer reads them
        v, t = model.vertices, model.triangles
        pts = scan(n_pts, 0)
        print(f"# {len(t)} triangles, {len(pts)} points, {os.cpu_count()} cores")

        def ours():
            m = _core.mesh.Mesh(v, t)
            return m.distances(pts)[0]

        only = args.cases.split(",")
        if "distances" in only:
            t_ours, c_ours, d_ours = timed_cpu(ours)
            try:
                import open3d as o3d

                def peer():
                    scene = o3d.t.geometry.RaycastingScene()
                    scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(t.astype(np.uint32)))
                    return scene.compute_signed_distance(o3d.core.Tensor(pts.astype(np.float32))).numpy()

                t_o3d, d_o3d = timed(peer)
                # Open3D's sign: negative inside, as gagekit; it computes in float32
                line(f"signed distances {len(pts) / 1e6:.1f} M pts / {len(t) / 1e6:.1f} M tri (Open3D)", t_ours, t_o3d)
                cpu_line(c_ours)
                diff = np.abs(d_ours - d_o3d.astype(np.float64))
                dabs = np.abs(np.abs(d_ours) - np.abs(d_o3d.astype(np.float64)))
                print(f"#   largest |gagekit - Open3D| = {diff.max():.3e} mm, of the absolute values {dabs.max():.3e} mm, "
                      f"sign differs at {(np.sign(d_ours) != np.sign(d_o3d)).sum()} points (Open3D: float32, sign by ray parity)")
            except ImportError:
                line(f"signed distances {len(pts) / 1e6:.1f} M pts / {len(t) / 1e6:.1f} M tri (Open3D not installed)", t_ours, None)
                cpu_line(c_ours)

        if "c2m" in only:
            ply = work / "scan.ply"
            from gagekit.cloud import write_points

            write_points(ply, pts)
            out = work / "dev.npy"
            gk = [sys.executable, "-m", "gagekit", "--quiet", "compare", str(ply), str(stl), "--deviations", str(out)]
            t0 = time.perf_counter()
            subprocess.run(gk, check=True, stdout=subprocess.DEVNULL)
            t_cli = time.perf_counter() - t0
            cc = shutil.which("CloudCompare") or shutil.which("cloudcompare")
            if cc:
                env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
                cmd = [cc, "-SILENT", "-AUTO_SAVE", "ON", "-C_EXPORT_FMT", "PLY", "-PLY_EXPORT_FMT", "BINARY_LE",
                       "-O", str(ply), "-O", str(stl), "-C2M_DIST"]
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=work)
                t_cc = time.perf_counter() - t0
                line(f"C2M command line {len(pts) / 1e6:.1f} M pts / {len(t) / 1e6:.1f} M tri (CloudCompare)", t_cli, t_cc)
                outs = sorted(work.glob("scan_C2M_DIST*.ply"))
                if outs:
                    from plyfile import PlyData

                    vert = PlyData.read(str(outs[-1]))["vertex"]
                    sf = [p.name for p in vert.properties if p.name not in ("x", "y", "z")]
                    d_cc = np.asarray(vert[sf[-1]], dtype=np.float64)
                    d_ref = np.load(out)
                    ok = np.isfinite(d_cc)
                    print(f"#   largest |gagekit - CloudCompare| = {np.abs(d_ref[ok] - d_cc[ok]).max():.3e} mm, of the absolute "
                          f"values {np.abs(np.abs(d_ref[ok]) - np.abs(d_cc[ok])).max():.3e} mm, over {ok.sum()} points "
                          f"(scalar field '{sf[-1]}'; CloudCompare stores float32 coordinates)")
            else:
                line(f"C2M command line {len(pts) / 1e6:.1f} M pts / {len(t) / 1e6:.1f} M tri (CloudCompare not installed)", t_cli, None)
        if "best-fit" not in only:
            return

        # best fit: 1 M points of a 100 k-triangle torus, from a random pose
        from scipy.spatial.transform import Rotation

        v2, t2 = torus(500, 100, bumpy=True)
        m2 = _core.mesh.Mesh(v2, t2)
        p2 = scan(1_000_000, 1, bumpy=True)  # the tube radius varies with u and v: one pose fits
        rot = Rotation.random(random_state=7).as_matrix()
        # einsum, not `@`: a BLAS product wakes OpenBLAS's threads, which spin-wait for
        # more work for a while after it, on the cores (and in the CPU time) of the fit
        moved = np.ascontiguousarray(np.einsum("ij,kj->ik", p2, rot) + [300.0, -200.0, 150.0])
        t_fit, c_fit, fit = timed_cpu(lambda: m2.best_fit(moved))
        M = np.array(fit.matrix)
        back = np.einsum("ij,kj->ik", moved, M[:3, :3]) + M[:3, 3]
        line(f"best-fit {len(moved) / 1e6:.1f} M pts / {len(t2) / 1e3:.0f} k tri, random pose", t_fit, None)
        print(f"#   largest point displacement from the truth {np.abs(back - p2).max():.2e} mm, rms {fit.rms_before:.1f} -> "
              f"{fit.rms_after:.4f} mm, {fit.iterations} iterations")
        cpu_line(c_fit)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
