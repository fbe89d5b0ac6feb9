//! Tests of the Chebyshev spheres: containment, optimality and invariance, on seeded
//! random sets (proptest).

use super::*;
use proptest::prelude::*;

fn ball_points(n: usize, seed: u64, c: [f64; 3], r: f64, noise: f64) -> Vec<f64> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .flat_map(|_| {
            let z: f64 = rng.random_range(-1.0..1.0);
            let t: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            let rr = r + noise * rng.random_range(-1.0..1.0);
            [c[0] + rr * s * t.cos(), c[1] + rr * s * t.sin(), c[2] + rr * z]
        })
        .collect()
}

fn value(pts: &[f64], c: &[f64; 3]) -> (f64, f64) {
    let (lo, hi, _, _) = extremes(pts, c, 0.0);
    (lo, hi)
}

#[test]
fn mc_of_a_tetrahedron_and_of_a_pair() {
    let pts = [1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0, -1.0, -1.0, -1.0, 1.0];
    let s = min_circumscribed(&pts).unwrap();
    assert!(s.center.iter().all(|v| v.abs() < 1e-15) && (s.r_out - 3f64.sqrt()).abs() < 1e-15);
    assert_eq!(s.control_out.len(), 4);
    let two = min_circumscribed(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 1.0, 0.1, 0.0]).unwrap();
    assert!((two.r_out - 1.0).abs() < 1e-15 && two.control_out == vec![0, 1]);
}

#[test]
fn mz_finds_the_generating_sphere() {
    let pts = ball_points(300, 1, [10.0, -20.0, 5.0], 25.0, 0.01);
    let z = min_zone(&pts).unwrap();
    let (lo, hi) = value(&pts, &z.center);
    assert!((hi - lo - (z.r_out - z.r_in)).abs() < 1e-12);
    assert!(z.r_out - z.r_in <= 0.02 + 1e-12);
    // no nearby centre is better (local optimality, by sampling)
    for k in 0..200 {
        let t = k as f64 * 0.731;
        let d = [1e-4 * t.cos(), 1e-4 * t.sin(), 1e-4 * (1.7 * t).cos()];
        let c = [z.center[0] + d[0], z.center[1] + d[1], z.center[2] + d[2]];
        let (l, h) = value(&pts, &c);
        assert!(h - l >= z.r_out - z.r_in - 1e-12);
    }
}

#[test]
fn coplanar_points_are_degenerate() {
    let pts: Vec<f64> = (0..10).flat_map(|i| { let t = i as f64; [t.cos(), t.sin(), 0.0] }).collect();
    assert!(min_zone(&pts).is_err() && max_inscribed(&pts).is_err());
    assert!(min_circumscribed(&pts).is_ok());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn mc_contains_every_point_and_is_minimal(seed in 0u64..10_000, n in 1usize..60, far in 0.0f64..1e6) {
        let pts = ball_points(n, seed, [far, -far, 0.5 * far], 30.0, 5.0);
        let s = min_circumscribed(&pts).unwrap();
        let (_, hi) = value(&pts, &s.center);
        prop_assert!(hi <= s.r_out);
        // the control points lie on the sphere, and adding a point never shrinks it
        for &i in &s.control_out {
            prop_assert!((dist(&pts[3 * i..3 * i + 3], &s.center) - s.r_out).abs() <= 1e-9 * (1.0 + s.r_out));
        }
        let mut more = pts.clone();
        more.extend([far + 3.0, -far + 1.0, 0.5 * far]);
        prop_assert!(min_circumscribed(&more).unwrap().r_out >= s.r_out - 1e-9 * s.r_out);
        // a rigid motion moves the sphere with the points
        let moved: Vec<f64> = pts.chunks_exact(3).flat_map(|p| [-p[1] + 7.0, p[0] - 3.0, p[2] + 11.0]).collect();
        let m = min_circumscribed(&moved).unwrap();
        prop_assert!((m.r_out - s.r_out).abs() <= 1e-9 * (1.0 + s.r_out));
    }

    #[test]
    fn mz_and_mi_certificates(seed in 0u64..10_000, n in 8usize..120) {
        let pts = ball_points(n, seed, [3.0, 4.0, -5.0], 20.0, 0.05);
        let z = min_zone(&pts).unwrap();
        let (lo, hi) = value(&pts, &z.center);
        prop_assert!((lo - z.r_in).abs() < 1e-12 && (hi - z.r_out).abs() < 1e-12);
        let ls = crate::lsq::sphere(&pts, 3).unwrap();
        let (l2, h2) = value(&pts, &[ls.center[0], ls.center[1], ls.center[2]]);
        prop_assert!(z.r_out - z.r_in <= h2 - l2 + 1e-12);
        let mi = max_inscribed(&pts).unwrap();
        let mc = min_circumscribed(&pts).unwrap();
        let (lo, _) = value(&pts, &mi.center);
        prop_assert!(mi.r_in <= lo + 1e-12 && mi.r_in <= mc.r_out);
        prop_assert!(mi.r_in >= l2.min(mc.r_out - (v3(&ls.center) - v3(&mc.center)).norm()) - 1e-12);
    }
}

fn v3(v: &[f64]) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(v[0], v[1], v[2])
}
