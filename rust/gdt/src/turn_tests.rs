//! Tests of the turn searches: analytic cases, the optimum against a dense sampling of the
//! turn, and invariance under rigid motions (proptest).

use crate::datum::{self, AxisFit};
use crate::turn::{self, Frame};
use crate::vec3::{self, dot, V3};
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

/// A rotation matrix (rows) from a rotation vector (Rodrigues).
fn rotation(rv: V3) -> [V3; 3] {
    let th = vec3::norm(rv);
    if th == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let k = vec3::scale(rv, 1.0 / th);
    let kk = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let k2: f64 = (0..3).map(|m| kk[i][m] * kk[m][j]).sum();
            r[i][j] = if i == j { 1.0 } else { 0.0 } + th.sin() * kk[i][j] + (1.0 - th.cos()) * k2;
        }
    }
    r
}

fn apply(r: &[V3; 3], v: V3) -> V3 {
    [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
}

fn moved(r: &[V3; 3], t: V3, p: V3) -> V3 {
    vec3::add(apply(r, p), t)
}

fn move_frame(r: &[V3; 3], t: V3, f: &Frame) -> Frame {
    Frame {
        origin: moved(r, t, f.origin),
        axes: [apply(r, f.axes[0]), apply(r, f.axes[1]), apply(r, f.axes[2])],
        free: f.free.iter().map(|d| apply(r, *d)).collect(),
        free_rotation: f.free_rotation,
    }
}

fn move_points(r: &[V3; 3], t: V3, pts: &[f64]) -> Vec<f64> {
    pts.chunks_exact(3).flat_map(|p| moved(r, t, [p[0], p[1], p[2]])).collect()
}

fn world(free: usize, free_rotation: bool) -> Frame {
    let e = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    Frame { origin: [0.0; 3], axes: e, free: e[..free].to_vec(), free_rotation }
}

/// The same value as the kernel's, at a turn psi, written out directly for the tests.
fn position_at(pts: &[f64], f: &Frame, p0: V3, d0: Option<V3>, psi: f64) -> f64 {
    let r = rotation(vec3::scale(f.axes[2], psi));
    let p = vec3::add(f.origin, apply(&r, vec3::sub(p0, f.origin)));
    let d = d0.map(|d| apply(&r, vec3::unit(d, "d").unwrap()));
    let w: Vec<V3> = pts
        .chunks_exact(3)
        .map(|q| {
            let e = vec3::sub([q[0], q[1], q[2]], p);
            match d {
                Some(d) => vec3::sub(e, vec3::scale(d, dot(e, d))),
                None => e,
            }
        })
        .collect();
    // free translations without their part along d, orthonormalised
    let mut fr: Vec<V3> = Vec::new();
    for t in &f.free {
        let mut t = *t;
        if let Some(d) = d {
            t = vec3::sub(t, vec3::scale(d, dot(t, d)));
        }
        for q in &fr {
            t = vec3::sub(t, vec3::scale(*q, dot(t, *q)));
        }
        if vec3::norm(t) > 1e-9 {
            fr.push(vec3::scale(t, 1.0 / vec3::norm(t)));
        }
    }
    turn::radius_free(&w, &fr).unwrap()
}

fn dense_min<F: Fn(f64) -> f64>(f: F, n: usize) -> f64 {
    (0..n).map(|k| f(TAU * k as f64 / n as f64)).fold(f64::INFINITY, f64::min)
}

#[test]
fn golden_section_reaches_machine_precision() {
    let (v, x) = turn::golden(&|x: f64| (x - 0.3).powi(2), -1.0, 2.0);
    assert!((x - 0.3).abs() < 1e-8, "{x}");
    assert!(v < 1e-16);
    // a V-shaped (non-smooth) minimum is located to rounding
    let (v, x) = turn::golden(&|x: f64| (x - 0.123456789).abs(), 0.0, 1.0);
    assert!((x - 0.123456789).abs() < 1e-15 && v < 1e-15, "{x} {v}");
}

#[test]
fn min_on_grid_finds_the_deeper_of_two_basins() {
    // a wide shallow basin at 1 and a narrow deeper one at 5.55 (off the grid): the best
    // local minima, not the best grid values, are refined
    let f = |x: f64| (0.01 * (x - 1.0).powi(2) - 0.29).min(-0.3 + 50.0 * (x - 5.55).powi(2));
    let (v, x) = turn::min_on_grid(&f, 0.0, TAU, 720, true, turn::TURN_CELLS);
    assert!((x - 5.55).abs() < 1e-7, "{x}");
    assert!((v + 0.3).abs() < 1e-13, "{v}");
    // an open interval: the minimum at its end is kept
    let (v, x) = turn::min_on_grid(&|x: f64| x, 2.0, 3.0, 40, false, 1);
    assert!(x == 2.0 && v == 2.0);
}

#[test]
fn min_max_sinusoids_is_exact_and_attained() {
    let a = [7.0, 6.5, 8.0, 5.5];
    let b = [3.0, 1.0, 4.5, 0.5];
    let phi = [0.3, -2.0, 2.5, 1.0];
    let (v, psi) = turn::min_max_sinusoids(&a, &b, &phi);
    let env = |p: f64| (0..4).map(|i| a[i] - b[i] * (p - phi[i]).cos()).fold(f64::NEG_INFINITY, f64::max);
    let dense = dense_min(env, 400_000);
    assert!(v <= dense + 1e-12, "{v} {dense}");
    assert!(v >= dense - 4.5 * TAU / 400_000.0 - 1e-12);
    assert!((env(psi) - v).abs() < 1e-12);
}

#[test]
fn min_in_disk_cases() {
    // points at (1, 0) and (3, 0): the enclosing circle's centre (2, 0)
    let w = [[1.0, 0.0], [3.0, 0.0]];
    assert!((turn::min_in_disk(&w, 5.0).unwrap().0 - 1.0).abs() < 1e-12);
    assert!((turn::min_in_disk(&w, 0.5).unwrap().0 - 2.5).abs() < 1e-12);
    assert!((turn::min_in_disk(&w, 0.0).unwrap().0 - 3.0).abs() < 1e-12);
    assert!(turn::min_in_disk(&[], 1.0).is_err());
}

#[test]
fn radius_free_along_a_line_is_the_constrained_enclosing_circle() {
    // points (x, y): centre free along x: the answer is max over the best x
    let w: Vec<V3> = vec![[0.0, 1.0, 0.0], [4.0, 2.0, 0.0], [1.0, -3.0, 0.0]];
    let r = turn::radius_free(&w, &[[1.0, 0.0, 0.0]]).unwrap();
    let f = |s: f64| w.iter().map(|p| ((p[0] - s).powi(2) + p[1] * p[1]).sqrt()).fold(0.0, f64::max);
    let dense = (0..=400_000).map(|k| f(-1.0 + 6.0 * k as f64 / 400_000.0)).fold(f64::INFINITY, f64::min);
    assert!(r <= dense + 1e-12 && r >= dense - 1e-4, "{r} {dense}");
}

#[test]
fn position_of_a_centre_turned_off_its_nominal_is_zero_with_a_free_turn() {
    // a centre at radius 10 from z, nominal at radius 10 but another angle: the free turn
    // brings the nominal onto it
    let f = world(0, true);
    let c = [10.0 * 0.7f64.cos(), 10.0 * 0.7f64.sin(), 5.0];
    let (r, psi) = turn::position(&c, &f, [10.0, 0.0, 5.0], None).unwrap();
    assert!(r < 1e-6, "{r}");
    assert!(((psi - 0.7 + PI).rem_euclid(TAU) - PI).abs() < 1e-6);
    // no free turn: the chord
    let f = world(0, false);
    let (r, _) = turn::position(&c, &f, [10.0, 0.0, 5.0], None).unwrap();
    assert!((r - 20.0 * 0.35f64.sin()).abs() < 1e-12);
}

#[test]
fn plane_location_with_a_free_turn_finds_the_leaning_face() {
    // a face whose normal is (cos 0.4, sin 0.4, 0) at distance 20 from z; nominal normal x
    let n = [0.4f64.cos(), 0.4f64.sin(), 0.0];
    let t = [-0.4f64.sin(), 0.4f64.cos(), 0.0];
    let mut pts = Vec::new();
    for i in 0..20 {
        for j in 0..5 {
            let h = 0.01 * ((i * 7 + j * 3) % 5) as f64 - 0.02;
            let p = vec3::add(vec3::add(vec3::scale(n, 20.0 + h), vec3::scale(t, i as f64 - 10.0)), [0.0, 0.0, j as f64]);
            pts.extend(p);
        }
    }
    let f = world(0, true);
    let (w, psi) = turn::plane_location(&pts, &f, [20.0, 0.0, 0.0], [1.0, 0.0, 0.0]).unwrap();
    assert!((w - 0.04).abs() < 1e-9, "{w}");
    assert!((psi.rem_euclid(TAU) - 0.4).abs() < 1e-6, "{psi}");
    // the offset free along x: the slab's own width, the same here
    let (w2, _) = turn::plane_location(&pts, &world(1, true), [0.0; 3], [1.0, 0.0, 0.0]).unwrap();
    assert!((w2 - 0.04).abs() < 1e-9, "{w2}");
    // no free turn: about the nominal x = 20 plane
    let (w3, _) = turn::plane_location(&pts, &world(0, false), [20.0, 0.0, 0.0], [1.0, 0.0, 0.0]).unwrap();
    let h: Vec<f64> = pts.chunks(3).map(|p| (p[0] - 20.0).abs()).collect();
    assert!((w3 - 2.0 * h.iter().cloned().fold(0.0, f64::max)).abs() < 1e-12);
}

#[test]
fn cylinder_on_cone_of_a_straight_leaning_axis_is_thin() {
    // axis points along a direction 30 degrees from z, turned by 1.1 rad
    let d = turn::cone_dir([0.0, 0.0, 1.0], 30f64.to_radians(), 1.1);
    let pts: Vec<f64> = (0..30).flat_map(|k| vec3::add([5.0, -2.0, 1.0], vec3::scale(d, k as f64))).collect();
    let (w, axis) = turn::cylinder_on_cone(&pts, [0.0, 0.0, 1.0], 30f64.to_radians()).unwrap();
    assert!(w < 1e-6, "{w}");
    assert!(dot(axis, d) > 1.0 - 1e-12);
}

fn cylinder_points(axis: V3, r: f64, n: usize, bump: f64) -> Vec<f64> {
    let (u, v) = vec3::basis(axis);
    let mut pts = Vec::new();
    for k in 0..n {
        let t = TAU * k as f64 / 37.0;
        let h = (k % 11) as f64 * 2.0;
        let rr = r + bump * (3.0 * t).cos();
        pts.extend(vec3::add(vec3::scale(axis, h), vec3::add(vec3::scale(u, rr * t.cos()), vec3::scale(v, rr * t.sin()))));
    }
    pts
}

#[test]
fn axis_on_cone_finds_the_leaning_cylinder() {
    let a = [0.0, 0.0, 1.0];
    let tilt = 25f64.to_radians();
    let d = turn::cone_dir(a, tilt, 0.8);
    let pts = cylinder_points(d, 6.0, 400, 0.0);
    // the least-squares axis slightly off the true turn
    let d_ls = turn::cone_dir(a, tilt, 0.8 + 0.05);
    for fit in [AxisFit::Circumscribed, AxisFit::Inscribed] {
        let ax = turn::axis_on_cone(&pts, a, tilt, d_ls, fit).unwrap();
        assert!((ax.radius - 6.0).abs() < 1e-7, "{fit:?} {}", ax.radius);
        assert!(dot(ax.direction, d) > 1.0 - 1e-12, "{fit:?}");
    }
    // least squares: the direction on the cone nearest d_ls
    let ax = turn::axis_on_cone(&pts, a, tilt, d_ls, AxisFit::LeastSquares).unwrap();
    assert!(dot(ax.direction, d_ls) > 1.0 - 1e-12);
    assert!(turn::axis_on_cone(&pts, a, f64::NAN, d_ls, AxisFit::Inscribed).is_err());
    assert!(turn::axis_on_cone(&pts[..6], a, tilt, d_ls, AxisFit::Inscribed).is_err());
}

#[test]
fn axis_on_cone_is_no_worse_than_a_dense_turn() {
    let a = [0.0, 0.0, 1.0];
    let tilt = 20f64.to_radians();
    let d = turn::cone_dir(a, tilt, -0.3);
    let pts = cylinder_points(d, 4.0, 300, 0.02);
    let d_ls = turn::cone_dir(a, tilt, -0.25);
    let phi0 = -0.25f64;
    let mc = turn::axis_on_cone(&pts, a, tilt, d_ls, AxisFit::Circumscribed).unwrap();
    let mi = turn::axis_on_cone(&pts, a, tilt, d_ls, AxisFit::Inscribed).unwrap();
    for k in 0..=400 {
        let phi = phi0 - turn::CONE_TURN + 2.0 * turn::CONE_TURN * k as f64 / 400.0;
        let dir = turn::cone_dir(a, tilt, phi);
        assert!(mc.radius <= datum::axis_along(&pts, dir, AxisFit::Circumscribed).unwrap().radius + 1e-12);
        assert!(mi.radius >= datum::axis_along(&pts, dir, AxisFit::Inscribed).unwrap().radius - 1e-12);
    }
}

#[test]
fn bad_frames_and_inputs_are_errors() {
    let nan = [f64::NAN, 0.0, 0.0];
    assert!(Frame::checked([0.0; 3], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]], vec![], true).is_err());
    assert!(Frame::checked(nan, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![], true).is_err());
    let f = world(0, true);
    assert!(turn::position(&[], &f, [0.0; 3], None).is_err());
    assert!(turn::position(&[1.0, 2.0, f64::NAN], &f, [0.0; 3], None).is_err());
    assert!(turn::position(&[1.0, 2.0, 3.0], &f, [0.0; 3], Some([0.0; 3])).is_err());
    assert!(turn::plane_location(&[1.0, 2.0, 3.0], &f, [0.0; 3], [0.0; 3]).is_err());
    assert!(turn::position_with_shift(&[1.0, 2.0, 3.0], &f, [0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], -1.0).is_err());
    assert!(turn::cylinder_on_cone(&[1.0, 2.0, 3.0], [0.0; 3], 0.3).is_err());
}

fn arb_points(n: std::ops::Range<usize>) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-20.0f64..20.0, n).prop_map(|mut v| {
        v.truncate(v.len() / 3 * 3);
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The position zone over a free turn is no worse than a dense sampling of the turn,
    /// and the same after a rigid motion of the whole problem.
    #[test]
    fn position_is_optimal_and_invariant(pts in arb_points(3..30), free in 0usize..3, line in any::<bool>(),
                                         rv in prop::array::uniform3(-3.0f64..3.0), t in prop::array::uniform3(-50.0f64..50.0),
                                         p0 in prop::array::uniform3(-10.0f64..10.0)) {
        let f = world(free, true);
        // a line along z keeps the exact envelope; a leaning line takes the grid search
        let d0 = line.then_some(if free == 0 { [0.0, 0.0, 1.0] } else { [0.3, 0.0, 1.0] });
        let (r, _) = turn::position(&pts, &f, p0, d0).unwrap();
        let dense = dense_min(|psi| position_at(&pts, &f, p0, d0, psi), 2880);
        prop_assert!(r <= dense + 1e-9 * (1.0 + dense), "{} > {}", r, dense);
        let rot = rotation(rv);
        let (r2, _) = turn::position(&move_points(&rot, t, &pts), &move_frame(&rot, t, &f), moved(&rot, t, p0), d0.map(|d| apply(&rot, d))).unwrap();
        prop_assert!((r - r2).abs() <= 1e-7 * (1.0 + r), "{} vs {}", r, r2);
    }

    /// The plane location zone over a free turn: no worse than a dense sampling, and
    /// invariant under a rigid motion.
    #[test]
    fn plane_location_is_optimal_and_invariant(pts in arb_points(3..60), free in 0usize..2, lean in 0.1f64..1.5,
                                               rv in prop::array::uniform3(-3.0f64..3.0), t in prop::array::uniform3(-50.0f64..50.0)) {
        let f = world(free, true);
        let n0 = [lean.sin(), 0.0, lean.cos()];
        let p0 = [3.0, 1.0, 2.0];
        let (w, _) = turn::plane_location(&pts, &f, p0, n0).unwrap();
        let at = |psi: f64| {
            let r = rotation(vec3::scale([0.0, 0.0, 1.0], psi));
            let (p, n) = (apply(&r, p0), apply(&r, n0));
            let h: Vec<f64> = pts.chunks(3).map(|q| dot(vec3::sub([q[0], q[1], q[2]], p), n)).collect();
            let (lo, hi) = h.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), v| (l.min(*v), u.max(*v)));
            if free > 0 { hi - lo } else { 2.0 * hi.max(-lo) }
        };
        let dense = dense_min(at, 2880);
        prop_assert!(w <= dense + 1e-9 * (1.0 + dense), "{} > {}", w, dense);
        let rot = rotation(rv);
        let (w2, _) = turn::plane_location(&move_points(&rot, t, &pts), &move_frame(&rot, t, &f), moved(&rot, t, p0), apply(&rot, n0)).unwrap();
        prop_assert!((w - w2).abs() <= 1e-7 * (1.0 + w), "{} vs {}", w, w2);
    }

    /// The cylindrical zone at a basic angle: no worse than a dense turn, invariant.
    #[test]
    fn cylinder_on_cone_is_optimal_and_invariant(pts in arb_points(3..24), angle in 0.1f64..1.4,
                                                 rv in prop::array::uniform3(-3.0f64..3.0), t in prop::array::uniform3(-50.0f64..50.0)) {
        let a = [0.0, 0.0, 1.0];
        let (w, _) = turn::cylinder_on_cone(&pts, a, angle).unwrap();
        let dense = dense_min(|phi| 2.0 * datum::axis_along(&pts, turn::cone_dir(a, angle, phi), AxisFit::Circumscribed).unwrap().radius, 1440);
        prop_assert!(w <= dense + 1e-9 * (1.0 + dense), "{} > {}", w, dense);
        let rot = rotation(rv);
        let (w2, _) = turn::cylinder_on_cone(&move_points(&rot, t, &pts), apply(&rot, a), angle).unwrap();
        prop_assert!((w - w2).abs() <= 1e-6 * (1.0 + w), "{} vs {}", w, w2);
    }

    /// The envelope minimum is exact: never above a dense sampling, attained at its turn.
    #[test]
    fn min_max_sinusoids_is_never_above_a_dense_sampling(m in 1usize..12, seed in prop::collection::vec((5.0f64..10.0, 0.0f64..5.0, -PI..PI), 12)) {
        let a: Vec<f64> = seed[..m].iter().map(|s| s.0).collect();
        let b: Vec<f64> = seed[..m].iter().map(|s| s.1).collect();
        let phi: Vec<f64> = seed[..m].iter().map(|s| s.2).collect();
        let (v, psi) = turn::min_max_sinusoids(&a, &b, &phi);
        let env = |p: f64| (0..m).map(|i| a[i] - b[i] * (p - phi[i]).cos()).fold(f64::NEG_INFINITY, f64::max);
        let n = 100_000;
        let dense = dense_min(env, n);
        prop_assert!(v <= dense + 1e-12);
        prop_assert!(v >= dense - 5.0 * TAU / n as f64 - 1e-12);
        prop_assert!((env(psi) - v).abs() <= 1e-12);
    }
}
