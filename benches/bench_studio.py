"""gagekit studio: opening a large scan, time to first render, live recount of a box.

Scans: the bundled casting (casting_ok.ply, 120,929 points) tiled with 0.05 mm seeded
noise to 1 M and 14 M points, written as binary PLY. Each case prints one line:
case, gagekit time, peer time, ratio (peer / gagekit; "-" where there is no peer).

* open: ``load_scan`` (read the PLY, index the points in the cell grid, choose the
  display subsample); the peer is plyfile's read of x, y, z alone (what any viewer pays).
* first render: headless Chromium (Debian's, through Playwright) is started first (a
  user's browser is already running; its start is printed, not counted), then
  ``gagekit studio SCAN --no-browser`` in a child process; the page is opened as soon as
  the server prints its address. The figure is the wall time from the command's start to
  the first frame with the points drawn (the page's clock, ``performance.timeOrigin``);
  the server's start, the page's share and the time until every region is counted and
  the datum frame found (``ready``) are printed below it.
* recount: the page moves a box (``__studio.moveBox``) and waits for the server's count
  over all points and the highlight mask of the shown ones: median and largest of 30
  round trips through HTTP; the peer is one numpy pass of the same box test over all
  points, in-process (no HTTP).

Run: ``python benches/bench_studio.py [--sizes 1000000 14000000] [--keep DIR]``
(about 2 minutes, 3 GB of memory at 14 M points).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import gagekit
from gagekit.samples import data_path
from gagekit.studio.session import load_scan

ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


def make_scan(n: int, folder: Path) -> Path:
    path = folder / f"casting_{n // 1_000_000}M.ply"
    if path.exists():
        return path
    base = gagekit.read_points(data_path("casting_ok.ply"))
    rng = np.random.default_rng(0)
    reps = -(-n // len(base))
    pts = np.tile(base, (reps, 1))[:n]
    pts += rng.normal(0.0, 0.05, pts.shape)
    gagekit.write_points(path, pts)
    return path


def numpy_count(pts: np.ndarray, centre, size, rotvec) -> int:
    from gagekit._rotation import rotation_from_vector

    R = rotation_from_vector(rotvec)
    local = (pts - np.asarray(centre)) @ R
    return int(np.all(np.abs(local) <= np.asarray(size) / 2, axis=1).sum())


def line(case: str, ours: float, peer=None, unit: str = "s") -> None:
    ratio = f"{peer / ours:.1f}x" if peer else "-"
    peer_s = f"{peer:.3f} {unit}" if peer else "-"
    print(f"{case:<52} gagekit {ours:8.3f} {unit}   peer {peer_s:>12}   ratio {ratio}", flush=True)


def bench_open(path: Path) -> None:
    from plyfile import PlyData

    t = time.perf_counter()
    scan = load_scan(path)
    ours = time.perf_counter() - t
    t = time.perf_counter()
    v = PlyData.read(str(path))["vertex"].data
    np.column_stack([v["x"], v["y"], v["z"]])
    peer = time.perf_counter() - t
    line(f"open {path.name} ({len(scan.points):,} pts, read+index+LOD)", ours, peer)
    del scan


def bench_browser(path: Path, spec: Path, recount: bool) -> None:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        # the user's browser is already running: its start is not the studio's to pay
        t = time.perf_counter()
        browser = p.chromium.launch(executable_path=shutil.which("chromium") or "/usr/bin/chromium", args=ARGS)
        launch = time.perf_counter() - t
        page = browser.new_page(viewport={"width": 1400, "height": 850})
        t0_epoch, t0 = time.time(), time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "gagekit", "studio", str(path), str(spec), "--no-browser", "--port", "0"],
                                stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
        try:
            url = None
            for row in proc.stderr:
                m = re.search(r"open (http://\S+)", row)
                if m:
                    url = m.group(1)
                    break
            assert url, "the studio did not start"
            served = time.perf_counter() - t0
            page.goto(url)
            page.wait_for_function("window.__studio && window.__studio.ready", timeout=300000)
            ready = time.perf_counter() - t0
            first = page.evaluate("window.__studio.firstRenderMs") / 1000
            first_epoch = page.evaluate("performance.timeOrigin + window.__studio.firstRenderMs") / 1000
            n = page.evaluate("window.__studio.state.scan.count")
            line(f"first render {path.name} ({n:,} pts), from command start", first_epoch - t0_epoch)
            line(f"  (server ready after)", served)
            line(f"  (page: navigation to first frame)", first)
            line(f"  (regions counted, datum frame found)", ready)
            line(f"  (browser start, not counted)", launch)
            if recount:
                ms = page.evaluate("""async () => {
                    const st = window.__studio, i = st.state.doc.region.findIndex(r => r.name === 'flange_top');
                    const c0 = st.state.doc.region[i].center.slice(), out = [], counts = [];
                    for (let k = 0; k < 31; k++) {
                        const c = [c0[0] + 0.5 * (k % 7), c0[1] - 0.3 * (k % 5), c0[2]];
                        const t = performance.now();
                        counts.push(await st.moveBox(i, c));
                        out.push(performance.now() - t);
                    }
                    return {ms: out.slice(1), first: out[0], counts};
                }""")
                times = np.array(ms["ms"])
                pts = gagekit.read_points(path)
                doc = page.evaluate("window.__studio.state.doc")
                spec_obj = gagekit.GageSpec.from_dict(doc)
                al = gagekit.gage.datum_alignment(pts, spec_obj)
                box = gagekit.gage.region_in_scanner(spec_obj.region("flange_top"), al)
                t = time.perf_counter()
                want = numpy_count(pts, box.center, box.size, box.rotation)
                peer = time.perf_counter() - t
                assert ms["counts"][-1] == want, (ms["counts"][-1], want)
                line(f"recount box over {n:,} pts, median of 30 (HTTP)", float(np.median(times)) / 1000, peer)
                line(f"recount box over {n:,} pts, largest of 30 (HTTP)", float(times.max()) / 1000, peer)
                line(f"  (first: select the box, draw its handles, recount)", ms["first"] / 1000)
        finally:
            proc.terminate()
            proc.wait(timeout=30)
            browser.close()


def load_average() -> str:
    try:
        return open("/proc/loadavg").read().split()[0]
    except OSError:
        return "?"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1_000_000, 14_000_000])
    ap.add_argument("--keep", type=Path, help="folder to keep the generated scans in (reused next time)")
    args = ap.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="gagekit-bench-studio-"))
    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "casting_ok.toml"
    shutil.copy(data_path("casting_ok.toml"), spec)
    print(f"# {os.cpu_count()} cores, load average {load_average()} at start", flush=True)
    try:
        for n in args.sizes:
            path = make_scan(n, folder)
            bench_open(path)
            bench_browser(path, spec, recount=n == max(args.sizes))
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
