//! The best fit is a property of the whole cloud: clutter beyond the bound, the points'
//! order and a rigid motion of the scan leave the fitted pose the same to 1e-9 mm.

use super::{best_fit, FitOptions};
use crate::distance::Query;
use crate::mesh::TriMesh;
use crate::rigid::Pose;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// The tube radius of a torus (R = 100 mm) that varies with u and v: one pose fits.
fn tube(u: f64, v: f64) -> f64 {
    30.0 + 5.0 * u.cos() + 3.0 * (v + 2.0 * u).sin()
}

fn torus(nu: usize, nv: usize) -> (Vec<f64>, Vec<u32>) {
    crate::grid::periodic_grid(nu, nv, |u, w| {
        let r = tube(u, w);
        [(100.0 + r * w.cos()) * u.cos(), (100.0 + r * w.cos()) * u.sin(), r * w.sin()]
    })
}

/// `n` points near the torus at random (u, v): offsets +-0.35 mm, 2 % up to 5 mm.
fn scan(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let (u, v) = (rng.random_range(0.0..2.0 * PI), rng.random_range(0.0..2.0 * PI));
        let mut h: f64 = rng.random_range(-0.35..0.35);
        if rng.random_range(0.0..1.0) < 0.02 {
            h = rng.random_range(-5.0..5.0);
        }
        let r = tube(u, v) + h;
        p.extend([(100.0 + r * v.cos()) * u.cos(), (100.0 + r * v.cos()) * u.sin(), r * v.sin()]);
    }
    p
}

/// `n` points of a fixture beside the torus (250-480 mm out along x, beyond any bound the
/// tests give), and the scan `s` with half of them before it and half after it.
fn with_fixture(s: &[f64], n: usize, rng: &mut ChaCha8Rng) -> (Vec<f64>, Vec<f64>) {
    let fixture: Vec<f64> = (0..n).flat_map(|_| [rng.random_range(250.0..480.0), rng.random_range(-150.0..150.0), rng.random_range(-80.0..80.0)]).collect();
    let half = 3 * (n / 2);
    let cluttered = fixture[..half].iter().chain(s).chain(&fixture[half..]).cloned().collect();
    (fixture, cluttered)
}

fn moved(v: &[f64], pose: &Pose) -> Vec<f64> {
    v.chunks_exact(3).flat_map(|p| pose.apply([p[0], p[1], p[2]])).collect()
}

/// The largest distance between the points placed by two poses.
fn displacement(a: &[f64], pa: &Pose, b: &[f64], pb: &Pose) -> f64 {
    moved(a, pa).iter().zip(&moved(b, pb)).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// min, max, mean and RMS of the signed distances within the bound.
fn figures(mesh: &TriMesh, points: &[f64], max_distance: f64) -> [f64; 4] {
    let d = mesh.distances(points, &Query { max_distance: Some(max_distance), ..Default::default() }).unwrap().distance;
    let used: Vec<f64> = d.into_iter().filter(|x| x.is_finite()).collect();
    let n = used.len() as f64;
    [
        used.iter().cloned().fold(f64::INFINITY, f64::min),
        used.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        used.iter().sum::<f64>() / n,
        (used.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
    ]
}

/// 120 000 points (through the 30 000 and 100 000 subsample stages), with 5 000 points of
/// a fixture 110-350 mm beside the part (half before the scan, half after it), beyond the
/// 2 mm bound: the same pose to 1e-9 mm, and so for the points shuffled and for the scan
/// moved by a random rigid motion (the start search from there). A stop at a 1e-6 mm
/// step left 1e-7 to 1e-6 mm between them.
#[test]
fn clutter_order_and_motion_leave_the_fit_unchanged() {
    let (v, t) = torus(200, 60);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let s = scan(120_000, 1);
    let n = s.len() / 3;
    let opt = FitOptions { max_distance: Some(2.0), ..Default::default() };
    let plain = best_fit(&mesh, &s, &opt).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let (fixture, cluttered) = with_fixture(&s, 5000, &mut rng);
    let fit = best_fit(&mesh, &cluttered, &opt).unwrap();
    assert_eq!(fit.n_used, plain.n_used);
    let worst = displacement(&s, &plain.pose, &s, &fit.pose);
    assert!(worst < 1e-9, "clutter moved the fit by {worst:.3e} mm");
    // the figures of the aligned scan, and the clutter beyond the bound there
    let (a, b) = (figures(&mesh, &moved(&s, &plain.pose), 2.0), figures(&mesh, &moved(&s, &fit.pose), 2.0));
    for k in 0..4 {
        assert!((a[k] - b[k]).abs() < 1e-9, "figure {k}: {} vs {}", a[k], b[k]);
    }
    let far = mesh.distances(&moved(&fixture, &fit.pose), &Query { max_distance: Some(2.0), ..Default::default() }).unwrap();
    assert!(far.distance.iter().all(|d| d.is_nan()));
    // the points shuffled
    let mut perm: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        perm.swap(i, rng.random_range(0..=i));
    }
    let shuffled: Vec<f64> = perm.iter().flat_map(|&i| [s[3 * i], s[3 * i + 1], s[3 * i + 2]]).collect();
    let fit = best_fit(&mesh, &shuffled, &opt).unwrap();
    let worst = displacement(&s, &plain.pose, &s, &fit.pose);
    assert!(worst < 1e-9, "the point order moved the fit by {worst:.3e} mm");
    // a random rigid motion (any rotation, 300 mm): the start search finds the way back
    let motion = Pose::from_params(&[210.0, -300.0, 140.0, 2.1, -0.9, 0.6]);
    let fit = best_fit(&mesh, &moved(&s, &motion), &opt).unwrap();
    let worst = displacement(&s, &plain.pose, &s, &fit.pose.after(&motion));
    assert!(worst < 1e-9, "a rigid motion of the scan moved the fit by {worst:.3e} mm");
}

/// Anderson mixing (depth 3) on a linear contraction x -> x* + M (x - x*) with six modes,
/// two slow (0.9, and 0.58 as the bracket's), from 0.3 mm away: a step below the
/// tolerance in 22 steps where the plain iteration takes 186 (depth 6, every mode, would
/// take 7; on the fits it took one full pass more than depth 3).
#[test]
fn anderson_mixing_lands_on_the_fixed_point_of_a_linear_contraction() {
    use super::{anderson, FIXED, ANDERSON};
    let star = [0.3, -0.2, 0.1, 1e-3, -2e-3, 5e-4];
    let mut m = [[0.0; 6]; 6];
    for (k, r) in [0.9, 0.58, 0.3, 0.2, 0.1, 0.05].iter().enumerate() {
        m[k][k] = *r;
    }
    // coupled translations and rotations, as the rows of a fit's Jacobian couple them
    m[0][4] = 30.0 * 0.05;
    m[3][1] = 0.01 / 30.0;
    let step = |x: &[f64; 6]| -> [f64; 6] {
        std::array::from_fn(|i| star[i] + (0..6).map(|j| m[i][j] * (x[j] - star[j])).sum::<f64>() - x[i])
    };
    let size = |f: &[f64; 6]| (0..6).map(|k| f[k].abs() / if k < 3 { FIXED.tr } else { FIXED.rot }).fold(0.0, f64::max);
    let mut x = [0.0; 6];
    let mut hist: Vec<([f64; 6], [f64; 6], f64)> = Vec::new();
    let mut steps = 0;
    loop {
        let f = step(&x);
        if size(&f) < 1.0 {
            break;
        }
        steps += 1;
        assert!(steps < 30, "no fixed point after {steps} mixed steps (step size {:.3e} of the tolerance)", size(&f));
        hist.push((x, f, size(&f)));
        if hist.len() > ANDERSON + 1 {
            hist.remove(0);
        }
        x = anderson(&hist, &FIXED).unwrap_or(std::array::from_fn(|k| x[k] + f[k]));
    }
    let err = (0..6).map(|k| (x[k] - star[k]).abs()).fold(0.0, f64::max);
    assert!(err < 1e-9, "{err:.3e} from the fixed point after {steps} steps");
    // the plain iteration: 0.9^k below 1e-10 / 0.3 takes about 190 steps
    let mut y = [0.0; 6];
    let mut plain = 0;
    while size(&step(&y)) >= 1.0 {
        let f = step(&y);
        y = std::array::from_fn(|k| y[k] + f[k]);
        plain += 1;
    }
    assert!(steps * 5 < plain, "mixed {steps} steps, plain {plain}");
}

/// Clutter as many points as the scan, in place (the scan in the model's frame) and under
/// a 2 mm bound: the same fit as without it. A start search without the bound alone is
/// pulled off by it (the median |distance| is then near the clutter's); one under the
/// bound alone cannot find the way back from a random pose (the clutter test above).
#[test]
fn clutter_as_large_as_the_scan_leaves_a_fit_in_place_unchanged() {
    let (v, t) = torus(200, 60);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let s = scan(40_000, 3);
    let opt = FitOptions { max_distance: Some(2.0), ..Default::default() };
    let plain = best_fit(&mesh, &s, &opt).unwrap();
    let (_, cluttered) = with_fixture(&s, 40_000, &mut ChaCha8Rng::seed_from_u64(4));
    let fit = best_fit(&mesh, &cluttered, &opt).unwrap();
    assert_eq!(fit.n_used, plain.n_used);
    let worst = displacement(&s, &plain.pose, &s, &fit.pose);
    assert!(worst < 1e-9, "clutter moved the fit by {worst:.3e} mm");
}

/// A surface of revolution (a torus of constant tube radius, 300 x 100 facets): turning
/// about its axis is constrained only by the facets, and the last stage steps from facet
/// to facet with no fixed point (distances moved by about 1e-4 mm a step). The fit keeps
/// its last pose (the step immaterial against the scan's noise) instead of failing, with
/// and without clutter beyond the bound, and the deviations stay those of the scan in place
/// (the scan is the torus's own, in place).
#[test]
fn a_surface_of_revolution_is_fitted() {
    let (v, t) = crate::grid::periodic_grid(300, 100, |u, w| [(100.0 + 30.0 * w.cos()) * u.cos(), (100.0 + 30.0 * w.cos()) * u.sin(), 30.0 * w.sin()]);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let s: Vec<f64> = (0..200_000)
        .flat_map(|_| {
            let (u, w) = (rng.random_range(0.0..2.0 * PI), rng.random_range(0.0..2.0 * PI));
            let r = 30.0 + rng.random_range(-0.35..0.35);
            [(100.0 + r * w.cos()) * u.cos(), (100.0 + r * w.cos()) * u.sin(), r * w.sin()]
        })
        .collect();
    let opt = FitOptions { max_distance: Some(10.0), ..Default::default() };
    let in_place = figures(&mesh, &s, 10.0);
    let (_, cluttered) = with_fixture(&s, 5000, &mut rng);
    for pts in [&s, &cluttered] {
        let fit = best_fit(&mesh, pts, &opt).expect("a surface of revolution is fitted");
        let f = figures(&mesh, &moved(&s, &fit.pose), 10.0);
        for k in 0..4 {
            assert!((f[k] - in_place[k]).abs() < 1e-2, "figure {k}: {} against {} in place", f[k], in_place[k]);
        }
    }
}
