//! Brute-force cross-checks of the circle fits on small random sets.

use super::voronoi::farthest_delaunay;
use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_set(seed: u64, n: usize, kind: u8) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut v = Vec::with_capacity(2 * n);
    for _ in 0..n {
        let (x, y) = match kind {
            // noisy circle
            0 => {
                let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let r = 10.0 + rng.random_range(-0.3..0.3);
                (3.0 + r * a.cos(), -2.0 + r * a.sin())
            }
            // noisy arc of 120 degrees
            1 => {
                let a: f64 = rng.random_range(0.0..2.1);
                let r = 5.0 + rng.random_range(-0.2..0.2);
                (r * a.cos(), r * a.sin())
            }
            // uniform in a square
            _ => (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)),
        };
        v.push(x);
        v.push(y);
    }
    v
}

fn pts2(v: &[f64]) -> Vec<[f64; 2]> {
    v.chunks_exact(2).map(|p| [p[0], p[1]]).collect()
}

fn f_r(p: &[[f64; 2]], c: [f64; 2]) -> f64 {
    let (lo, hi) = mz::radii(p, c);
    hi - lo
}

#[test]
fn mc_matches_all_two_and_three_point_circles() {
    for seed in 0..30 {
        let v = random_set(seed, 5 + (seed as usize % 20), (seed % 3) as u8);
        let p = pts2(&v);
        let mc = min_circumscribed(&v).unwrap();
        for q in &p {
            assert!(dist(*q, mc.center) <= mc.radius + 1e-12);
        }
        let contains = |c: [f64; 2], r: f64| p.iter().all(|q| dist(*q, c) <= r * (1.0 + 1e-12));
        let mut best = f64::INFINITY;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let c = [(p[i][0] + p[j][0]) / 2.0, (p[i][1] + p[j][1]) / 2.0];
                let r = dist(c, p[i]);
                if contains(c, r) {
                    best = best.min(r);
                }
                for k in j + 1..p.len() {
                    if let Some(c) = circumcenter(p[i], p[j], p[k]) {
                        let r = dist(c, p[i]);
                        if contains(c, r) {
                            best = best.min(r);
                        }
                    }
                }
            }
        }
        assert!(
            (mc.radius - best).abs() < 1e-9,
            "seed {seed}: {} vs {best}",
            mc.radius
        );
        for &k in &mc.control {
            assert!((dist(p[k], mc.center) - mc.radius).abs() < 1e-9);
        }
    }
}

#[test]
fn mc_small_and_degenerate() {
    let one = min_circumscribed(&[1.0, 2.0]).unwrap();
    assert_eq!((one.center, one.radius), ([1.0, 2.0], 0.0));
    let two = min_circumscribed(&[0.0, 0.0, 2.0, 0.0]).unwrap();
    assert!((two.radius - 1.0).abs() < 1e-15 && two.control == vec![0, 1]);
    let line = min_circumscribed(&[0.0, 0.0, 1.0, 0.0, 4.0, 0.0]).unwrap();
    assert!((line.radius - 2.0).abs() < 1e-15);
    assert!(min_circumscribed(&[]).is_err());
    let e = min_circumscribed(&[0.0, 0.0, f64::NAN, 1.0]).unwrap_err();
    assert!(e.message.contains("point 1"), "{}", e.message);
}

/// max over a grid (then refined) of g(c) = min(r_MC - |c - c_MC|, min_i |c - p_i|)
fn mi_brute(p: &[[f64; 2]], cmc: [f64; 2], rmc: f64) -> f64 {
    let g = |c: [f64; 2]| {
        let near = p.iter().map(|q| dist(*q, c)).fold(f64::INFINITY, f64::min);
        near.min(rmc - dist(c, cmc))
    };
    let mut best = ([0.0, 0.0], f64::NEG_INFINITY);
    let m = 200;
    for i in 0..=m {
        for j in 0..=m {
            let c = [
                cmc[0] + rmc * (2.0 * i as f64 / m as f64 - 1.0),
                cmc[1] + rmc * (2.0 * j as f64 / m as f64 - 1.0),
            ];
            let v = g(c);
            if v > best.1 {
                best = (c, v);
            }
        }
    }
    // pattern search refinement
    let mut step = rmc / m as f64;
    while step > 1e-12 * rmc {
        let mut moved = false;
        for d in [
            [1.0, 0.0],
            [-1.0, 0.0],
            [0.0, 1.0],
            [0.0, -1.0],
            [0.7, 0.7],
            [-0.7, 0.7],
            [0.7, -0.7],
            [-0.7, -0.7],
        ] {
            let c = [best.0[0] + step * d[0], best.0[1] + step * d[1]];
            let v = g(c);
            if v > best.1 {
                best = (c, v);
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    best.1
}

#[test]
fn mi_matches_grid_search() {
    for seed in 0..24 {
        let v = random_set(100 + seed, 6 + (seed as usize % 30), (seed % 3) as u8);
        let p = pts2(&v);
        let mc = min_circumscribed(&v).unwrap();
        let mi = max_inscribed(&v).unwrap();
        let brute = mi_brute(&p, mc.center, mc.radius);
        // no point strictly inside, inside MC
        for q in &p {
            assert!(dist(*q, mi.center) >= mi.radius - 1e-12);
        }
        assert!(dist(mi.center, mc.center) + mi.radius <= mc.radius + 1e-9);
        assert!(
            mi.radius >= brute - 1e-9,
            "seed {seed}: MI {} < brute {brute}",
            mi.radius
        );
    }
}

/// min over a grid of centres (then refined by pattern search from the best few)
fn mz_brute(p: &[[f64; 2]], c0: [f64; 2], span: f64) -> f64 {
    let m = 120;
    let mut cands = Vec::new();
    for i in 0..=m {
        for j in 0..=m {
            let c = [
                c0[0] + span * (2.0 * i as f64 / m as f64 - 1.0),
                c0[1] + span * (2.0 * j as f64 / m as f64 - 1.0),
            ];
            cands.push((f_r(p, c), c));
        }
    }
    cands.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    for &(v0, c0) in cands.iter().take(12) {
        let (mut c, mut v) = (c0, v0);
        let mut step = span / m as f64;
        while step > 1e-13 * span {
            let mut moved = false;
            for k in 0..16 {
                let a = k as f64 * std::f64::consts::TAU / 16.0;
                let cc = [c[0] + step * a.cos(), c[1] + step * a.sin()];
                let vv = f_r(p, cc);
                if vv < v {
                    (c, v) = (cc, vv);
                    moved = true;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        best = best.min(v);
    }
    best
}

#[test]
fn mz_matches_grid_search() {
    for seed in 0..24 {
        let v = random_set(200 + seed, 5 + (seed as usize % 40), (seed % 3) as u8);
        let p = pts2(&v);
        let z = min_zone(&v).unwrap();
        let w = z.form_error();
        assert!((f_r(&p, z.center) - w).abs() < 1e-12);
        let mc = min_circumscribed(&v).unwrap();
        let brute = mz_brute(&p, mc.center, 2.0 * mc.radius);
        assert!(w <= brute + 1e-9, "seed {seed}: MZ {w} > brute {brute}");
        for &k in &z.control_in {
            assert!((dist(p[k], z.center) - z.r_in).abs() < 1e-9, "seed {seed}");
        }
        for &k in &z.control_out {
            assert!((dist(p[k], z.center) - z.r_out).abs() < 1e-9, "seed {seed}");
        }
        assert!(
            is_local_min(&p, z.center, &z.control_in, &z.control_out),
            "seed {seed}: not a local minimum"
        );
    }
}

#[test]
fn farthest_delaunay_circles_contain_all() {
    for seed in 0..20 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let k = 3 + (seed as usize * 7) % 40;
        let mut ang: Vec<f64> = (0..k)
            .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
            .collect();
        ang.sort_by(f64::total_cmp);
        let q: Vec<[f64; 2]> = ang.iter().map(|a| [3.0 * a.cos(), 2.0 * a.sin()]).collect();
        let tris = farthest_delaunay(&q);
        assert_eq!(tris.len(), k - 2);
        for t in tris {
            let c = circumcenter(q[t[0]], q[t[1]], q[t[2]]).unwrap();
            let r = dist(c, q[t[0]]);
            for x in &q {
                assert!(dist(*x, c) <= r * (1.0 + 1e-12), "seed {seed}");
            }
        }
    }
}

#[test]
fn lsq_perfect_circle_and_errors() {
    let v: Vec<f64> = (0..7)
        .flat_map(|k| {
            let a = k as f64 * 0.9;
            [1e6 + 3.0 + 2.0 * a.cos(), -1e6 + 2.0 * a.sin()]
        })
        .collect();
    let c = least_squares(&v).unwrap();
    assert!((c.center[0] - (1e6 + 3.0)).abs() < 1e-8 && (c.center[1] + 1e6).abs() < 1e-8);
    assert!((c.radius - 2.0).abs() < 1e-9);
    for f in [least_squares, |v: &[f64]| max_inscribed(v).map(|c| c)] {
        assert!(f(&[0.0, 0.0, 1.0, 1.0, 2.0, 2.0]).is_err());
        assert!(f(&[0.0, 0.0, 1.0, 1.0]).is_err());
    }
    assert!(min_zone(&[0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 3.0, 3.0]).is_err());
    let z = min_zone(&[1.0, 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, -1.0]).unwrap();
    assert!(z.form_error().abs() < 1e-15 && z.center[0].abs() < 1e-15);
}

#[test]
fn angular_gap() {
    let v: Vec<f64> = (0..10)
        .flat_map(|k| {
            let a = k as f64 * 0.1;
            [a.cos(), a.sin()]
        })
        .collect();
    let g = max_angular_gap(&v, [0.0, 0.0]);
    assert!((g - (std::f64::consts::TAU - 0.9)).abs() < 1e-12);
}

/// All candidates of Eqs. 6.6-6.8 without any pruning, each evaluated on all points.
fn mz_all_candidates(p: &[[f64; 2]]) -> (f64, [f64; 2]) {
    use super::voronoi::{convex_hull, intersect, Farthest, Nearest};
    let mut nvd = Nearest::build(p, "t").unwrap();
    nvd.extract(p, f64::NEG_INFINITY);
    let fvd = Farthest::new(p, &convex_hull(p));
    let mut best = (f64::INFINITY, [0.0, 0.0]);
    let mut eval = |c: [f64; 2]| {
        let w = f_r(p, c);
        if w < best.0 {
            best = (w, c);
        }
    };
    for v in nvd.verts.iter().chain(&fvd.verts) {
        eval(v.c);
    }
    for e in &nvd.edges {
        for f in &fvd.edges {
            if let Some((t, s)) = intersect(e, f) {
                if e.contains(t, 1e-9) && f.contains(s, 1e-9) {
                    eval(e.at(t));
                }
            }
        }
    }
    best
}

#[test]
fn mz_matches_unpruned_candidates_near_perfect_circles() {
    for (seed, n, noise) in [
        (1u64, 200usize, 1e-9),
        (2, 120, 1e-7),
        (3, 300, 1e-5),
        (4, 60, 1e-3),
    ] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let v: Vec<f64> = (0..n)
            .flat_map(|_| {
                let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let r = 50.0 + rng.random_range(-noise..noise);
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let p = pts2(&v);
        let z = min_zone(&v).unwrap();
        let (wb, cb) = mz_all_candidates(&p);
        let w0 = f_r(&p, [0.0, 0.0]);
        assert!(wb <= w0 + 1e-15, "unpruned {wb} > f(0) {w0}");
        // equal up to the rounding of the Voronoi geometry (~1e-13 of the part size)
        assert!(
            z.form_error() <= wb + 5e-12,
            "seed {seed}: MZ {} at {:?} > unpruned {wb} at {cb:?}",
            z.form_error(),
            z.center
        );
        assert!(
            is_local_min(&p, z.center, &z.control_in, &z.control_out),
            "seed {seed}: not a local minimum"
        );
    }
}

/// First-order optimality of a zone: zero lies in the convex hull of the gradients
/// `u_i - u_j` (u = unit vector from the point to the centre) of the active pairs
/// (i outer, j inner); in the plane that means the gradients are not all within an open
/// half-plane. Equivalently the control points alternate inner/outer around the centre.
fn is_local_min(p: &[[f64; 2]], c: [f64; 2], inner: &[usize], outer: &[usize]) -> bool {
    let u = |k: usize| {
        let d = dist(p[k], c);
        [(c[0] - p[k][0]) / d, (c[1] - p[k][1]) / d]
    };
    let mut g = Vec::new();
    for &i in outer {
        for &j in inner {
            let (a, b) = (u(i), u(j));
            g.push((a[1] - b[1]).atan2(a[0] - b[0]));
        }
    }
    g.sort_by(f64::total_cmp);
    // largest angular gap between gradient directions must not exceed pi
    let mut gap = g[0] + std::f64::consts::TAU - g[g.len() - 1];
    for w in g.windows(2) {
        gap = gap.max(w[1] - w[0]);
    }
    gap <= std::f64::consts::PI + 1e-9
}

#[test]
fn subset_iteration_matches_exact_on_all_points() {
    // above subset::SMALL points the fits run by constraint generation
    for (seed, kind) in [(7u64, 0u8), (8, 1), (9, 2)] {
        let v = random_set(seed, 6000, kind);
        let data = Centered::new(&v, "t", 3).unwrap();
        let p = &data.pts;
        let z = min_zone(&v).unwrap();
        let zf = mz::exact(p, data.scale).unwrap();
        assert!(
            (z.form_error() - zf.form_error()).abs() < 1e-12,
            "seed {seed}: {} vs {}",
            z.form_error(),
            zf.form_error()
        );
        assert!((f_r(&pts2(&v), z.center) - z.form_error()).abs() < 1e-12);
        let m = max_inscribed(&v).unwrap();
        let (cmc, _) = mc::welzl(p, data.scale);
        let rmc = p.iter().map(|q| dist(*q, cmc)).fold(0.0, f64::max);
        let (_, rf, _) = mi::exact(p, cmc, rmc, data.scale).unwrap();
        assert!(
            (m.radius - rf).abs() < 1e-12,
            "seed {seed}: MI {} vs {rf}",
            m.radius
        );
    }
}

#[test]
fn extreme_coordinates_give_results_or_clear_errors() {
    // tiny and huge coordinates: a result, or an InvalidInput error, never a panic
    let tiny = [
        0.0, 0.0, 1e-300, 0.0, 0.0, 1e-300, 1e-300, 1e-300, 5e-301, 2e-300,
    ];
    for r in [
        min_zone(&tiny).map(|z| z.form_error()),
        max_inscribed(&tiny).map(|c| c.radius),
    ] {
        match r {
            Ok(w) => assert!(w.is_finite()),
            Err(e) => assert!(!e.message.is_empty()),
        }
    }
    let huge = [1e200, 0.0, -1e200, 0.0, 0.0, 1e200, 3e199, -2e199];
    let big = [1e100, 0.0, -1e100, 0.0, 0.0, 1e100, 3e99, -2e99];
    assert!(min_circumscribed(&huge).is_err() && least_squares(&huge).is_err());
    assert!((min_circumscribed(&big).unwrap().radius - 1e100).abs() < 1e88);
    for r in [
        min_zone(&huge).map(|z| z.form_error()),
        max_inscribed(&huge).map(|c| c.radius),
    ] {
        if let Err(e) = r {
            assert!(
                e.message.contains("beyond 1e150") || e.message.contains("too large"),
                "{}",
                e.message
            );
        }
    }
    let square = [1.0, 1.0, -1.0, 1.0, -1.0, -1.0, 1.0, -1.0, 1.0, 1.0];
    let z = min_zone(&square).unwrap();
    assert!(z.form_error().abs() < 1e-15);
}

/// Points 30 mm along a shallow noisy arc of radius `r` (sagitta 4e-3 mm of noise).
fn shallow_arc(r: f64) -> Vec<f64> {
    (0..30)
        .flat_map(|i| {
            let a = (i as f64 / 29.0 - 0.5) * 20.0 / r;
            let rr = r + 0.001 * ((i * 7) % 5) as f64;
            [rr * a.sin(), rr * a.cos() - r]
        })
        .collect()
}

#[test]
fn min_zone_of_nearly_straight_points_is_finite_or_degenerate() {
    // moderately shallow arcs: the true zone (width 4e-3 mm of radial noise)
    for r in [1e3, 1e4] {
        let z = min_zone(&shallow_arc(r)).unwrap();
        assert!((z.form_error() - 4e-3).abs() < 1e-9, "R {r}: width {}", z.form_error());
        assert!((z.center[1] + r).abs() < 1e-3 * r);
    }
    // all but straight: an error, never a zone of width 0 around a centre at 1e18 mm
    for r in [1e6, 1e8] {
        let e = min_zone(&shallow_arc(r)).unwrap_err();
        assert_eq!(e.kind, gagekit_core::ErrorKind::DegenerateGeometry, "R {r}: {e}");
    }
    // a noisy strip (a cylinder's points projected almost along its length): every
    // accepted zone is finite, holds every point and has the strip's positive width
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..200 {
        let tilt: f64 = rng.random_range(1e-7..1e-3);
        let pts: Vec<f64> = (0..24)
            .flat_map(|i| {
                let x = -30.0 + 60.0 * (i as f64 / 23.0);
                let y = tilt * x * x + 0.002 * ((i * 5 % 7) as f64 / 3.0 - 1.0);
                [x, y]
            })
            .collect();
        match min_zone(&pts) {
            Ok(z) => {
                assert!(z.form_error() > 1e-4, "width {} at centre {:?}", z.form_error(), z.center);
                assert!(z.center[0].hypot(z.center[1]) < 1e4 * 31.0);
                for p in pts.chunks_exact(2) {
                    let d = (p[0] - z.center[0]).hypot(p[1] - z.center[1]);
                    assert!(d >= z.r_in - 1e-9 && d <= z.r_out + 1e-9);
                }
            }
            Err(e) => assert_eq!(e.kind, gagekit_core::ErrorKind::DegenerateGeometry),
        }
    }
}

#[test]
fn near_kernel_finds_the_exact_optimum_from_a_nearby_centre() {
    for seed in 0..20u64 {
        let v = random_set(seed, 40, 0);
        let m = max_inscribed(&v).unwrap();
        let n = max_inscribed_near(&v, [m.center[0] + 1e-3, m.center[1]]).unwrap().unwrap();
        assert!(n.radius <= m.radius + 1e-12);
        assert!((n.radius - m.radius).abs() < 1e-9, "seed {seed}: {} vs {}", n.radius, m.radius);
        assert_eq!(n.control, m.control);
    }
}

/// Points for the tiled MI: uniform in a square (optimum outside the square, near MC),
/// uniform in a disk (optimum in an inner gap), a lattice (many equal empty circles),
/// clusters with empty space between them.
fn area_set(seed: u64, n: usize, kind: u8) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let side = (n as f64).sqrt().ceil() as usize;
    let mut v = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (x, y) = match kind {
            0 => (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)),
            1 => {
                let r: f64 = rng.random_range(0.0f64..1.0).sqrt();
                let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                (r * a.cos(), r * a.sin())
            }
            2 => ((i % side) as f64, (i / side) as f64),
            _ => {
                let c = (i % 5) as f64;
                (100.0 * c.cos() + rng.random_range(-3.0..3.0), 100.0 * c.sin() + rng.random_range(-3.0..3.0))
            }
        };
        v.push(x);
        v.push(y);
    }
    v
}

#[test]
fn tiled_mi_matches_exact_on_all_points() {
    for (seed, kind, n) in [(1u64, 0u8, 20000usize), (2, 1, 20000), (3, 2, 10000), (4, 3, 20000), (5, 1, 4000)] {
        let v = area_set(seed, n, kind);
        let data = Centered::new(&v, "t", 3).unwrap();
        let p = &data.pts;
        let (cmc, _) = mc::welzl(p, data.scale);
        let rmc = p.iter().map(|q| dist(*q, cmc)).fold(0.0, f64::max);
        let (ce, re, _) = mi::exact(p, cmc, rmc, data.scale).unwrap();
        let (ct, rt, ctrl) = mi_tiled::exact_tiled(p, cmc, rmc, data.scale).unwrap();
        assert!((re - rt).abs() <= 1e-12 * data.scale, "kind {kind}: exact {re} vs tiled {rt}");
        // the reported circle is empty and inside MC, and its control points lie on it
        let nn = p.iter().map(|q| dist(*q, ct)).fold(f64::INFINITY, f64::min);
        assert!((nn.min(rmc - dist(ct, cmc)) - rt).abs() <= 1e-12 * data.scale, "kind {kind}");
        for &k in &ctrl {
            assert!((dist(p[k], ct) - rt).abs() <= 1e-9 * data.scale, "kind {kind}: control {k}");
        }
        if kind != 2 {
            // a unique optimum: the same centre
            assert!(dist(ce, ct) <= 1e-9 * data.scale, "kind {kind}: {ce:?} vs {ct:?}");
        }
        // the public fit (subset rounds, then tiles) agrees
        let m = max_inscribed(&v).unwrap();
        assert!((m.radius - re).abs() <= 1e-12 * data.scale, "kind {kind}: fit {} vs {re}", m.radius);
    }
}
