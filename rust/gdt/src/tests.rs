//! Tests of the zone kernels: analytic cases and properties (proptest).

use crate::datum::{self, AxisFit, Orientation, PlaneFit};
use crate::vec3::{self, dot};
use crate::{min_width3, width2, width3};
use proptest::prelude::*;

fn brute_width2(pts: &[f64], steps: usize) -> f64 {
    (0..steps)
        .map(|k| {
            let t = std::f64::consts::PI * k as f64 / steps as f64;
            let (c, s) = (t.cos(), t.sin());
            let d: Vec<f64> = pts.chunks(2).map(|p| c * p[0] + s * p[1]).collect();
            d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn rectangle_width_is_its_short_side() {
    let mut pts = Vec::new();
    for i in 0..=12 {
        for j in 0..=4 {
            pts.extend([1e5 + 10.0 * i as f64, -3.0 + 0.01 * j as f64]);
        }
    }
    let w = width2::min_width(&pts).unwrap();
    assert!((w.width - 0.04).abs() < 1e-12, "{}", w.width);
    assert!(w.normal[0].abs() < 1e-12 && (w.normal[1].abs() - 1.0).abs() < 1e-12);
}

#[test]
fn collinear_points_have_zero_width_and_coincident_points_fail() {
    let w = width2::min_width(&[0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 3.0, 3.0]).unwrap();
    assert!(w.width.abs() < 1e-15);
    assert!(width2::min_width(&[1.0, 1.0, 1.0, 1.0]).is_err());
    assert!(width2::min_width(&[1.0, f64::NAN, 1.0, 1.0]).is_err());
}

#[test]
fn large_sets_are_prefiltered_without_changing_the_width() {
    // a disc of 20000 points: prefilter path; compare with the hull of the same set
    // fed in small pieces (no prefilter below 4096 points)
    let mut pts = Vec::new();
    let mut s: u64 = 7;
    let mut rnd = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..20000 {
        let (r, t) = (rnd().sqrt() * 5.0, rnd() * std::f64::consts::TAU);
        pts.extend([r * t.cos() * 2.0, r * t.sin()]);
    }
    let w = width2::min_width(&pts).unwrap();
    let p: Vec<[f64; 2]> = pts.chunks(2).map(|q| [q[0], q[1]]).collect();
    let h = width2::hull(&p);
    let sub: Vec<f64> = h.iter().flat_map(|&i| p[i]).collect();
    let w2 = width2::min_width(&sub).unwrap();
    assert!((w.width - w2.width).abs() < 1e-12);
    assert!(w.width <= brute_width2(&pts, 3600) + 1e-12);
}

#[test]
fn chamfer_angularity_is_length_times_sin_of_the_error() {
    // a 45-degree chamfer tilted by d about y: 10 mm slant, 80 mm along y
    let d: f64 = 0.002;
    let t = std::f64::consts::FRAC_PI_4 + d;
    let mut pts = Vec::new();
    for i in 0..=20 {
        for j in 0..=16 {
            let s = 10.0 * i as f64 / 20.0;
            pts.extend([110.0 + s * t.cos(), 5.0 * j as f64, 40.0 - s * t.sin()]);
        }
    }
    // zone planes whose normal makes 45 degrees with z, free to turn about z
    let slab = width3::on_cone(&pts, [0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_4).unwrap();
    assert!((slab.width - 10.0 * d.sin()).abs() < 1e-12, "{} vs {}", slab.width, 10.0 * d.sin());
}

#[test]
fn tangent_plane_sits_on_the_air_side() {
    // bottom face z = 0, dented at the corners, a bump in the middle: the datum touches the corners
    let mut pts = Vec::new();
    for i in 0..=10 {
        for j in 0..=10 {
            let corner = (i == 0 || i == 10) && (j == 0 || j == 10);
            let z = if (i, j) == (5, 5) { 0.02 } else if corner { -0.01 } else { 0.0 };
            pts.extend([10.0 * i as f64, 8.0 * j as f64, z]);
        }
    }
    let a = datum::plane(&pts, [0.0, 0.0, -1.0], Orientation::Free, PlaneFit::Chebyshev).unwrap();
    assert!((a.normal[2] + 1.0).abs() < 1e-12, "{:?}", a.normal);
    // every point on the material side, the farthest 0.03 away
    let worst = pts.chunks(3).map(|p| dot([p[0], p[1], p[2]], a.normal) - a.offset).fold(f64::MIN, f64::max);
    assert!(worst <= 1e-12);
    assert!((a.deviation - 0.03).abs() < 1e-12);
    let ls = datum::plane(&pts, [0.0, 0.0, -1.0], Orientation::Free, PlaneFit::LeastSquares).unwrap();
    assert!(ls.point[2].abs() < 1e-3);
}

#[test]
fn secondary_datum_of_a_leaning_face() {
    // face y = s z (z in [0, 40], x in [0, 120]) leaning away from the air side (-y):
    // constrained perpendicular to A (z), the datum is y = 0
    let s = 1e-3;
    let mut pts = Vec::new();
    for i in 0..=24 {
        for k in 0..=8 {
            let z = 5.0 * k as f64;
            pts.extend([5.0 * i as f64, s * z, z]);
        }
    }
    let b = datum::plane(&pts, [0.0, -1.0, 0.0], Orientation::PerpendicularTo([0.0, 0.0, 1.0]), PlaneFit::Chebyshev).unwrap();
    assert!((b.normal[1] + 1.0).abs() < 1e-12 && b.offset.abs() < 1e-12, "{:?}", b);
    assert!((b.deviation - 40.0 * s).abs() < 1e-12);
}

#[test]
fn hole_and_shaft_axes_of_a_fixed_direction() {
    // a three-lobed bore r = 10 + 0.005 cos 3t about (40, 30), axis z
    let mut pts = Vec::new();
    for i in 0..360 {
        for k in 0..5 {
            let t = std::f64::consts::TAU * i as f64 / 360.0;
            let r = 10.0 + 0.005 * (3.0 * t).cos();
            pts.extend([40.0 + r * t.cos(), 30.0 + r * t.sin(), 5.0 * k as f64]);
        }
    }
    let mi = datum::axis_along(&pts, [0.0, 0.0, 1.0], AxisFit::Inscribed).unwrap();
    let mc = datum::axis_along(&pts, [0.0, 0.0, 1.0], AxisFit::Circumscribed).unwrap();
    for ax in [&mi, &mc] {
        assert!((ax.point[0] - 40.0).abs() < 1e-9 && (ax.point[1] - 30.0).abs() < 1e-9, "{:?}", ax.point);
    }
    assert!((mi.radius - 9.995).abs() < 1e-9 && (mc.radius - 10.005).abs() < 1e-9);
    assert!((mc.r_max - mc.r_min - 0.01).abs() < 1e-9);
}

/// Nominally flat features (as the zones are meant for): 50 mm across, 1 mm thick.
fn cloud(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec((-50.0f64..50.0, -50.0f64..50.0, -0.5f64..0.5), n..=n)
        .prop_map(|v| v.into_iter().flat_map(|(x, y, z)| [x, y, z + 0.002 * x]).collect())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn min_width_2d_is_a_lower_bound_and_motion_invariant(
        pts in prop::collection::vec(-10.0f64..10.0, 6..200),
        ang in 0.0f64..6.28, tx in -1e3f64..1e3, ty in -1e3f64..1e3,
    ) {
        let pts: Vec<f64> = pts[..pts.len() / 2 * 2].to_vec();
        prop_assume!(pts.len() >= 6);
        let Ok(w) = width2::min_width(&pts) else { return Ok(()) };
        prop_assert!(w.width >= 0.0);
        prop_assert!(w.width <= brute_width2(&pts, 720) + 1e-9);
        let (c, s) = (ang.cos(), ang.sin());
        let moved: Vec<f64> = pts.chunks(2).flat_map(|p| [c * p[0] - s * p[1] + tx, s * p[0] + c * p[1] + ty]).collect();
        let wm = width2::min_width(&moved).unwrap();
        prop_assert!((wm.width - w.width).abs() < 1e-9, "{} vs {}", wm.width, w.width);
    }

    #[test]
    fn constrained_slabs_contain_the_points_and_never_beat_the_free_zone(pts in cloud(40), ax in prop::array::uniform3(-1.0f64..1.0)) {
        prop_assume!(vec3::norm(ax) > 0.1);
        let free = datum::slab(&pts, Orientation::Free).unwrap();
        for o in [Orientation::PerpendicularTo(ax), Orientation::AtAngle(ax, 0.7), Orientation::Fixed(ax)] {
            let s = datum::slab(&pts, o).unwrap();
            prop_assert!(s.width >= free.width - 1e-9, "{:?}: {} < {}", o, s.width, free.width);
            for p in pts.chunks(3) {
                let d = dot([p[0], p[1], p[2]], s.normal);
                prop_assert!(d >= s.lo - 1e-9 && d <= s.hi + 1e-9);
            }
        }
        // perpendicular: the normal is perpendicular, and no perpendicular direction is thinner
        let a = vec3::unit(ax, "t").unwrap();
        let s = datum::slab(&pts, Orientation::PerpendicularTo(ax)).unwrap();
        prop_assert!(dot(s.normal, a).abs() < 1e-12);
        let (u, v) = vec3::basis(a);
        for k in 0..360 {
            let t = std::f64::consts::PI * k as f64 / 360.0;
            let n = vec3::add(vec3::scale(u, t.cos()), vec3::scale(v, t.sin()));
            let (lo, hi) = width3::extent(&pts, n);
            prop_assert!(hi - lo >= s.width - 1e-9);
        }
        // on the cone: the normal keeps its angle, and the grid of turns is no thinner
        let c = datum::slab(&pts, Orientation::AtAngle(ax, 0.7)).unwrap();
        prop_assert!((dot(c.normal, a) - 0.7f64.cos()).abs() < 1e-12);
        for k in 0..720 {
            let f = std::f64::consts::TAU * k as f64 / 720.0;
            let n = vec3::add(vec3::scale(a, 0.7f64.cos()), vec3::add(vec3::scale(u, 0.7f64.sin() * f.cos()), vec3::scale(v, 0.7f64.sin() * f.sin())));
            let (lo, hi) = width3::extent(&pts, n);
            prop_assert!(hi - lo >= c.width - 1e-9);
        }
    }

    #[test]
    fn datum_planes_are_tangent_on_the_air_side(pts in cloud(30), out in prop::array::uniform3(-1.0f64..1.0)) {
        prop_assume!(vec3::norm(out) > 0.1);
        for o in [Orientation::Free, Orientation::PerpendicularTo([out[1], -out[0], 0.3]), Orientation::Fixed(out)] {
            let Ok(d) = datum::plane(&pts, out, o, PlaneFit::Chebyshev) else { continue };
            prop_assert!(dot(d.normal, out) >= -1e-12);
            for p in pts.chunks(3) {
                let h = dot([p[0], p[1], p[2]], d.normal) - d.offset;
                prop_assert!(h <= 1e-9 && h >= -d.deviation - 1e-9);
            }
        }
    }
}

/// Width of the points along the unit `n`.
fn width_along(pts: &[f64], n: [f64; 3]) -> f64 {
    let (lo, hi) = width3::extent(pts, n);
    hi - lo
}

/// Brute force of the 3-D minimum width: every plane through three points (its normal)
/// and every direction perpendicular to two segments between points (edge-edge); the
/// thinnest slab has one of these normals (Houle & Toussaint 1988).
fn brute_width3(pts: &[f64]) -> f64 {
    let n = pts.len() / 3;
    let p = |i: usize| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
    let mut best = f64::INFINITY;
    let mut try_dir = |d: [f64; 3]| {
        let l = vec3::norm(d);
        if l > 1e-12 {
            best = best.min(width_along(pts, vec3::scale(d, 1.0 / l)));
        }
    };
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                try_dir(vec3::cross(vec3::sub(p(b), p(a)), vec3::sub(p(c), p(a))));
            }
        }
    }
    let segs: Vec<(usize, usize)> = (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b))).collect();
    for (k, &(a, b)) in segs.iter().enumerate() {
        for &(c, d) in &segs[k + 1..] {
            try_dir(vec3::cross(vec3::sub(p(b), p(a)), vec3::sub(p(d), p(c))));
        }
    }
    best
}

#[test]
fn min_width3_of_a_box_and_a_tetrahedron() {
    // a 10 x 6 x 2 box, turned: width 2 along the turned z
    let r = |p: [f64; 3]| [0.6 * p[0] - 0.8 * p[2] + 5.0, p[1] - 3.0, 0.8 * p[0] + 0.6 * p[2] + 1.0];
    let mut pts = Vec::new();
    for x in [0.0, 10.0] {
        for y in [0.0, 6.0] {
            for z in [0.0, 2.0] {
                pts.extend(r([x, y, z]));
            }
        }
    }
    let s = min_width3::min_width(&pts).unwrap();
    assert!((s.width - 2.0).abs() < 1e-12, "{}", s.width);
    // regular tetrahedron of edge sqrt(2) * 2: its width is between opposite edges, 2
    let tet = [1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0, -1.0, -1.0, -1.0, 1.0];
    let t = min_width3::min_width(&tet).unwrap();
    assert!((t.width - 2.0).abs() < 1e-12 && t.width < 4.0 / 3f64.sqrt(), "{}", t.width);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Exact against the brute force over every point triple and segment pair, on small
    /// sets of any shape (not only flat ones), and never beaten by a direction grid.
    #[test]
    fn min_width3_equals_the_brute_force(
        pts in prop::collection::vec(-10.0f64..10.0, 12..=30),
        flat in 0.01f64..1.0,
    ) {
        let pts: Vec<f64> = pts[..pts.len() / 3 * 3].chunks(3).flat_map(|p| [p[0], p[1], flat * p[2]]).collect();
        let s = min_width3::min_width(&pts).unwrap();
        let brute = brute_width3(&pts);
        prop_assert!((s.width - brute).abs() <= 1e-9 * (1.0 + brute), "{} vs brute {}", s.width, brute);
        prop_assert!((width_along(&pts, s.normal) - s.width).abs() <= 1e-12 * (1.0 + s.width));
    }

    #[test]
    fn min_width3_is_motion_invariant(pts in cloud(60), ang in 0.0f64..6.28, t in -1e3f64..1e3) {
        let s = min_width3::min_width(&pts).unwrap();
        let (c, sn) = (ang.cos(), ang.sin());
        let moved: Vec<f64> = pts.chunks(3).flat_map(|p| [c * p[0] - sn * p[2] + t, p[1] - t, sn * p[0] + c * p[2]]).collect();
        let m = min_width3::min_width(&moved).unwrap();
        prop_assert!((m.width - s.width).abs() < 1e-9, "{} vs {}", m.width, s.width);
    }
}
