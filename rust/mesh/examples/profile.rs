//! Timing harness (not a test): `cargo run --release -p gagekit-mesh --example profile -- [points] [nu nv] [fit|shuffle|of=N] [from=K]`.
//! The torus and scan-line scan of benches/bench_compare.py, built in Rust; `of=N`: the
//! first `points` points of an N-point scan (the density of the full scan on a subset); `from=K`: from its K-th point on.
//! `build [runs] [nu nv] [nohash]`: only `TriMesh::new` of the torus, `runs` times (wall and CPU seconds of each, and a
//! fingerprint of all it built).
use gagekit_mesh::align::{best_fit, FitOptions};
use gagekit_mesh::distance::Query;
use gagekit_mesh::rigid::Pose;
use gagekit_mesh::TriMesh;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use std::time::Instant;

fn tube(u: f64, v: f64, bumpy: bool) -> f64 {
    30.0 + if bumpy { 5.0 * u.cos() + 3.0 * (v + 2.0 * u).sin() } else { 0.0 }
}

fn torus(nu: usize, nv: usize, bumpy: bool) -> (Vec<f64>, Vec<u32>) {
    gagekit_mesh::grid::periodic_grid(nu, nv, |u, w| {
        let r = tube(u, w, bumpy);
        [((100.0 + r * w.cos()) * u.cos()) as f32 as f64, ((100.0 + r * w.cos()) * u.sin()) as f32 as f64, (r * w.sin()) as f32 as f64]
    })
}

fn scan(n: usize, seed: u64, bumpy: bool) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let rows = ((n / 3) as f64).sqrt() as usize;
    let per = n / rows + 1;
    let mut p = Vec::with_capacity(3 * n);
    for k in 0..n {
        let (i, j) = (k / per, k % per);
        let u = 2.0 * PI * i as f64 / rows as f64;
        let v = 2.0 * PI * j as f64 / per as f64;
        let mut h: f64 = rng.random_range(-0.35..0.35);
        if rng.random_range(0.0..1.0) < 0.02 {
            h = rng.random_range(-5.0..5.0);
        }
        let r = tube(u, v, bumpy) + h;
        p.extend([(100.0 + r * v.cos()) * u.cos(), (100.0 + r * v.cos()) * u.sin(), r * v.sin()]);
    }
    p
}

/// The process's counters so far (from /proc/self/stat): user and system CPU seconds, and
/// minor page faults.
fn counters() -> (f64, f64, f64) {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let f: Vec<&str> = s.rsplit(')').next().unwrap_or("").split_whitespace().collect();
    let t = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (t(11) / 100.0, t(12) / 100.0, t(7))
}

/// On-CPU seconds of all the process's threads so far, to the nanosecond (the sum of
/// /proc/self/task/*/schedstat's first field; the clock ticks of /proc/self/stat are 10 ms).
fn cpu_ns() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return f64::NAN };
    let mut ns = 0u64;
    for t in tasks.flatten() {
        let s = std::fs::read_to_string(t.path().join("schedstat")).unwrap_or_default();
        ns += s.split_whitespace().next().and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    }
    ns as f64 * 1e-9
}

/// CPU seconds used by the process so far (user + system).
fn cpu() -> f64 {
    let (u, s, _) = counters();
    u + s
}

/// `TriMesh::new` of the torus alone, `runs` times: each run's wall and CPU seconds.
fn build_only(args: &[String]) {
    let runs: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let nu: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let nv: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(500);
    let (v, t) = torus(nu, nv, false);
    for _ in 0..runs {
        let (c0, t0) = (counters(), Instant::now());
        let mesh = TriMesh::new(&v, &t).unwrap();
        let (wall, c1) = (t0.elapsed().as_secs_f64(), counters());
        let (user, sys, faults) = (c1.0 - c0.0, c1.1 - c0.1, c1.2 - c0.2);
        let c = user + sys;
        // `nohash`: no fingerprint (its instructions would hide the build's in a count)
        let hash = if args.iter().any(|s| s == "nohash") { String::new() } else { format!(", mesh {:016x}", mesh_hash(&mesh)) };
        println!("{} tri: TriMesh::new {wall:.3} s wall, {c:.2} s cpu ({user:.2} user, {sys:.2} system, {faults:.0} page faults), {} nodes{hash}", t.len() / 3, mesh.bvh.nodes.len());
    }
}

/// A fingerprint of every bit the build makes: the tree (nodes, root, slots' triangles,
/// corners and bound data), the normals and pseudonormals, the area and the topology.
fn mesh_hash(m: &TriMesh) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::hash::DefaultHasher::new();
    let b = &m.bvh;
    for n in &b.nodes {
        n.lo.iter().chain(n.hi.iter()).flatten().for_each(|x| x.to_bits().hash(&mut h));
        n.child.iter().for_each(|c| (c.index, c.count).hash(&mut h));
    }
    (b.root.index, b.root.count, &b.order).hash(&mut h);
    let f = |x: &f64| x.to_bits();
    let bits = b.root_lo.iter().chain(&b.root_hi).chain(b.corners.iter().flatten().flatten());
    bits.map(f).for_each(|x| x.hash(&mut h));
    b.bounds.iter().flat_map(|q| q.n.iter().chain(q.m.iter().flatten()).chain(&q.w)).for_each(|x| x.to_bits().hash(&mut h));
    (b.slack.to_bits(), b.size.to_bits(), m.area.to_bits(), format!("{:?}", m.topology)).hash(&mut h);
    m.face_normals.iter().chain(&m.vertex_normals).chain(m.edge_normals.iter().flatten()).flatten().map(f).for_each(|x| x.hash(&mut h));
    h.finish()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(|s| s == "build").unwrap_or(false) {
        return build_only(&args);
    }
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1_400_000);
    let nu: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let nv: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(500);
    let fit = args.get(4).map(|s| s == "fit").unwrap_or(false);
    let (v, t) = torus(nu, nv, fit);
    let of = args.get(4).and_then(|s| s.strip_prefix("of=")).and_then(|s| s.parse().ok()).unwrap_or(n);
    // `from=K` (any argument after the first): the points from the K-th on
    let from: usize = args.iter().skip(2).find_map(|s| s.strip_prefix("from=")).and_then(|s| s.parse().ok()).unwrap_or(0);
    let mut pts = scan(of.max(n + from), 0, fit);
    pts.drain(..3 * from);
    pts.truncate(3 * n);
    if args.get(4).map(|s| s == "shuffle").unwrap_or(false) {
        // a deterministic shuffle (Fisher-Yates, seeded)
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for i in (1..n).rev() {
            let j = rng.random_range(0..=i);
            for k in 0..3 {
                pts.swap(3 * i + k, 3 * j + k);
            }
        }
    }
    let c0 = cpu();
    let t0 = Instant::now();
    let mesh = TriMesh::new(&v, &t).unwrap();
    let t_mesh = t0.elapsed().as_secs_f64();
    println!("TriMesh::new cpu {:.2} s", cpu() - c0);
    let t1 = Instant::now();
    let _ = gagekit_mesh::bvh::Bvh::new(&mesh.bvh.corners);
    let t_bvh = t1.elapsed().as_secs_f64();
    println!("{} tri, {} pts: TriMesh::new {:.3} s (BVH alone {:.3} s, {} nodes)", t.len() / 3, n, t_mesh, t_bvh, mesh.bvh.nodes.len());
    if fit {
        let pose = Pose::from_params(&[300.0, -200.0, 150.0, 2.0, -1.0, 0.7]);
        let moved: Vec<f64> = pts.chunks_exact(3).flat_map(|p| pose.apply([p[0], p[1], p[2]])).collect();
        let c2 = cpu();
        let t2 = Instant::now();
        let f = best_fit(&mesh, &moved, &FitOptions::default()).unwrap();
        println!("best_fit {:.3} s, {} iterations, rms {:.3} -> {:.5}, start {}", t2.elapsed().as_secs_f64(), f.iterations, f.rms_before, f.rms_after, f.start);
        println!("best_fit cpu {:.2} s", cpu() - c2);
        return;
    }
    let (c2, s2) = (cpu(), cpu_ns());
    let t2 = Instant::now();
    let d = mesh.distances(&pts, &Query::default()).unwrap();
    let el = t2.elapsed().as_secs_f64();
    let s3 = cpu_ns();
    println!("distances cpu {:.2} s ({:.0} ns/pt), on-cpu {:.4} s", cpu() - c2, (cpu() - c2) * 1e9 / n as f64, s3 - s2);
    let s: f64 = d.distance.iter().map(|x| x.abs()).sum();
    println!("distances {:.3} s ({:.1} ns/pt wall), sum|d| {:.6}", el, el * 1e9 / n as f64, s);
    // the outputs' fingerprints (std's SipHash with its fixed keys): any change of a bit shows
    use std::hash::{Hash, Hasher};
    let fp = |f: &dyn Fn(&mut std::hash::DefaultHasher)| {
        let mut h = std::hash::DefaultHasher::new();
        f(&mut h);
        h.finish()
    };
    let hd = fp(&|h| d.distance.iter().map(|x| x.to_bits()).collect::<Vec<u64>>().hash(h));
    let ht = fp(&|h| d.triangle.hash(h));
    println!("hash distance {hd:016x} triangle {ht:016x}");
}
