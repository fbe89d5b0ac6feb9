use super::exact::{orient3d, pt, P3};
use super::*;
use gagekit_core::ErrorKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn flat(p: &[P3]) -> Vec<f64> {
    p.iter().flatten().copied().collect()
}

fn hull(p: &[P3]) -> Vec<usize> {
    convex_hull_indices(&flat(p)).expect("hull")
}

/// Exact check of Eq. 5.21 and minimality, independent of the prefilter:
/// every point lies in the hull of the result, and no result point lies in the
/// hull of the other result points.
fn check_hull(points: &[f64], got: &[usize]) {
    let n = points.len() / 3;
    let inside_all = |sub: &[usize], x: P3| -> bool {
        let p: Vec<P3> = sub.iter().map(|&i| pt(points, i)).collect();
        match simplex(&p_sorted(&p)) {
            Simplex::Solid(_) => {
                let q = p_sorted(&p);
                let Simplex::Solid(init) = simplex(&q) else { unreachable!() };
                let h = quickhull::hull3d(&q, init).unwrap();
                h.faces.iter().all(|f| {
                    orient3d(q[f[0] as usize], q[f[1] as usize], q[f[2] as usize], x) >= 0.0
                })
            }
            _ => true, // lower-dimensional cases are checked by their own tests
        }
    };
    assert!(got.windows(2).all(|w| w[0] < w[1]), "ascending, no repeats");
    if got.len() >= 4 {
        for i in 0..n {
            assert!(inside_all(got, pt(points, i)), "point {i} outside the hull of the result");
        }
        for (k, &v) in got.iter().enumerate() {
            let rest: Vec<usize> = got.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, &i)| i).collect();
            assert!(!inside_all(&rest, pt(points, v)), "vertex {v} is not extreme");
        }
    }
}

fn p_sorted(p: &[P3]) -> Vec<P3> {
    let mut q = p.to_vec();
    q.sort_by(|a, b| a.partial_cmp(b).unwrap());
    q.dedup();
    q
}

#[test]
fn empty_and_tiny_inputs() {
    assert_eq!(hull(&[]), Vec::<usize>::new());
    assert_eq!(hull(&[[1.0, 2.0, 3.0]]), vec![0]);
    assert_eq!(hull(&[[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]), vec![0]);
    assert_eq!(hull(&[[1.0, 2.0, 3.0], [0.0, 2.0, 3.0]]), vec![0, 1]);
    assert_eq!(hull(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), vec![0, 1, 2]);
    assert_eq!(hull(&[[0.0; 3], [2.0, 2.0, 2.0], [1.0, 1.0, 1.0]]), vec![0, 1]);
    assert_eq!(hull(&[[5.0; 3], [5.0; 3], [5.0; 3]]), vec![0]);
}

#[test]
fn duplicates_report_lowest_index() {
    let mut p = vec![[1.0, 1.0, 1.0]; 3];
    p.extend([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    p.extend([[0.0; 3], [1.0, 0.0, 0.0], [-0.0, 1.0, -0.0]]);
    assert_eq!(hull(&p), vec![0, 3, 4, 5, 6]);
}

#[test]
fn collinear_gives_end_points() {
    let p: Vec<P3> = (0..50).map(|i| [(i * 7 % 50) as f64 * 0.5, 1.0 + (i * 7 % 50) as f64 * 3.0, -2.0]).collect();
    let got = hull(&p);
    let ends: Vec<usize> = (0..50).filter(|&i| i * 7 % 50 == 0 || i * 7 % 50 == 49).collect();
    assert_eq!(got, ends);
}

#[test]
fn coplanar_grid_gives_polygon_corners() {
    // z = x + 2 y on an integer grid: exactly coplanar, tilted.
    let mut p = Vec::new();
    for i in 0..20 {
        for j in 0..15 {
            let (x, y) = (i as f64, j as f64);
            p.push([x, y, x + 2.0 * y]);
        }
    }
    let got = hull(&p);
    let corners: Vec<usize> = vec![0, 14, 19 * 15, 19 * 15 + 14];
    assert_eq!(got, corners);
    // a vertical plane (x constant) is also handled
    let q: Vec<P3> = p.iter().map(|v| [3.0, v[0], v[1]]).collect();
    assert_eq!(hull(&q), corners);
}

#[test]
fn cube_grid_gives_eight_corners() {
    let mut p = Vec::new();
    for i in 0..6 {
        for j in 0..6 {
            for k in 0..6 {
                p.push([i as f64, j as f64, k as f64]);
            }
        }
    }
    let got = hull(&p);
    let corner = |i: usize, j: usize, k: usize| i * 36 + j * 6 + k;
    let mut want: Vec<usize> = [0, 5].iter().flat_map(|&i| [0, 5].iter().flat_map(move |&j| [0, 5].map(|k| corner(i, j, k)))).collect();
    want.sort();
    assert_eq!(got, want);
}

#[test]
fn non_finite_points_are_named() {
    let mut p = vec![0.0; 12];
    p[10] = f64::NAN;
    let e = convex_hull_indices(&p).unwrap_err();
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    assert!(e.message.contains("point 3"), "{}", e.message);
    p[10] = f64::INFINITY;
    assert!(convex_hull_indices(&p).is_err());
    assert!(convex_hull_indices(&[1.0, 2.0]).is_err());
}

/// Brute force for general position: i is a vertex iff some plane through i
/// and two other points has every other point strictly on one side.
fn brute_force(p: &[P3]) -> Vec<usize> {
    let n = p.len();
    let mut out = Vec::new();
    'points: for i in 0..n {
        for j in 0..n {
            for k in j + 1..n {
                if i == j || i == k {
                    continue;
                }
                let s: Vec<f64> = (0..n).filter(|&l| l != i && l != j && l != k).map(|l| orient3d(p[i], p[j], p[k], p[l])).collect();
                if s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0) {
                    out.push(i);
                    continue 'points;
                }
            }
        }
    }
    out
}

#[test]
fn matches_brute_force_on_random_sets() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for trial in 0..40 {
        let n = 5 + trial % 30;
        let p: Vec<P3> = (0..n).map(|_| [rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>() * if trial % 2 == 0 { 1.0 } else { 1e-6 }]).collect();
        assert_eq!(hull(&p), brute_force(&p), "trial {trial}");
    }
}

#[test]
fn degenerate_integer_clouds_are_exact() {
    // Small integer coordinates: many coplanar faces, points on edges, duplicates.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for trial in 0..30 {
        let n = 10 + trial * 3;
        let m = 2 + trial % 4;
        let p: Vec<f64> = (0..3 * n).map(|_| rng.random_range(0..=m as i32) as f64).collect();
        let got = convex_hull_indices(&p).unwrap();
        check_hull(&p, &got);
    }
}

fn noisy_patch(n: usize, seed: u64, tilt: bool) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let (x, y) = (rng.random::<f64>() * 200.0, rng.random::<f64>() * 150.0);
        // sum of uniforms: a cheap bell-shaped noise of about 20 um
        let z: f64 = (0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * 0.035;
        if tilt {
            out.extend([x, 0.6 * y - 0.8 * z + 10.0, 0.8 * y + 0.6 * z - 5.0]);
        } else {
            out.extend([x, y, z]);
        }
    }
    out
}

#[test]
fn prefilter_does_not_change_the_result() {
    for (seed, tilt) in [(1, false), (2, true)] {
        let p = noisy_patch(40_000, seed, tilt);
        let fast = convex_hull_indices(&p).unwrap();
        let mut slow = hull_of(&p, (0..p.len() / 3).collect()).unwrap();
        slow.sort_unstable();
        assert_eq!(fast, slow);
        assert!(fast.len() > 20 && fast.len() < 2000, "{}", fast.len());
    }
}

#[test]
fn prefilter_handles_a_ball_and_exact_plane() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let p: Vec<f64> = (0..3 * 30_000).map(|_| rng.random::<f64>() - 0.5).collect();
    let fast = convex_hull_indices(&p).unwrap();
    let mut slow = hull_of(&p, (0..p.len() / 3).collect()).unwrap();
    slow.sort_unstable();
    assert_eq!(fast, slow);
    // exactly planar large input: the 2-D hull
    let q: Vec<f64> = (0..10_000).flat_map(|i| {
        let (x, y) = ((i % 100) as f64, (i / 100) as f64);
        [x, y, 0.5 * x - y]
    }).collect();
    assert_eq!(convex_hull_indices(&q).unwrap(), vec![0, 99, 9900, 9999]);
}

#[test]
fn jacobi_diagonalises() {
    let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1e-6]];
    let (vals, q) = super::prefilter::jacobi_eigen(a);
    for k in 0..3 {
        let av = [0, 1, 2].map(|r| (0..3).map(|c| a[r][c] * q[k][c]).sum::<f64>());
        for r in 0..3 {
            assert!((av[r] - vals[k] * q[k][r]).abs() < 1e-12);
        }
    }
}
