//! Tests of the cylinder fits (search, subset, projection).

use super::projection::{fit2d, frame, objective};
use super::search::{fit_direct, Region};
use super::*;
use crate::lsq::{centroid, orthonormal_basis};
use std::f64::consts::FRAC_PI_2;

fn noisy(n: usize) -> Vec<f64> {
    (0..n)
        .flat_map(|i| {
            let t = i as f64 * 2.399963;
            let z = (i as f64 * 0.618034).fract() * 50.0;
            let r = 10.0 + 0.01 * (3.0 * t).sin() + 0.002 * ((i * 7919 % 101) as f64 / 50.0 - 1.0);
            [r * t.cos() + 0.01 * z, r * t.sin() - 0.02 * z, z]
        })
        .collect()
}

#[test]
fn active_subset_equals_the_full_fit() {
    let pts = noisy(2050);
    let opts = Options { max_iterations: 60, ..Options::default() };
    let sub = fit(&pts, Criterion::MinCircumscribed, &opts).unwrap();
    let lsq_axis = lsq::cylinder(&pts, None).ok().map(|c| Vector3::from(c.direction));
    let full = fit_direct(&pts, Criterion::MinCircumscribed, &opts, lsq_axis, &Region::half_sphere()).unwrap();
    assert!((sub.r_out - full.r_out).abs() < 1e-9, "{} vs {}", sub.r_out, full.r_out);
    assert!((sub.extent.max - sub.r_out).abs() < 1e-9);
    // the point is the foot of all the points' centroid, as the full fit's (not of the
    // active subset's: it moved along the axis with the subset)
    assert_foot_of_centroid(&pts, &sub);
    assert_foot_of_centroid(&pts, &full);
}

/// The reported point is the foot of the centroid of `pts` on the axis.
fn assert_foot_of_centroid(pts: &[f64], r: &CylinderFit) {
    let c = Vector3::from_column_slice(&centroid(pts, 3));
    let (p, d) = (Vector3::from(r.point), Vector3::from(r.direction));
    let off = c - p;
    assert!(off.dot(&d).abs() < 1e-9, "{:?} is {} mm along the axis from the centroid's foot", r.point, off.dot(&d));
}

/// Data set 3 of the dissertation (24 points; reference-data/seed-cylinders/set3.csv).
const SET3: [f64; 72] = [
    11.0943, 0.4522, 65.2328,
    5.094, 10.845, 65.0765,
    -6.9063, 10.8439, 65.0089,
    -12.9065, 0.4498, 65.0897,
    -6.9063, -9.9429, 65.054,
    5.094, -9.9418, 65.2216,
    10.9546, 0.522, 75.2316,
    4.9544, 10.9148, 75.0752,
    -7.0459, 10.9137, 75.077,
    -13.0461, 0.5196, 74.8964,
    -7.0459, -9.8731, 75.0528,
    4.9545, -9.872, 75.2204,
    10.815, 0.5918, 85.2304,
    4.8148, 10.9846, 85.074,
    -7.1855, 10.9835, 85.0641,
    -13.1858, 0.5894, 84.8952,
    -7.1855, -9.8033, 85.0516,
    4.8149, -9.8022, 85.2171,
    10.6754, 0.6616, 95.2291,
    4.6752, 11.0544, 95.0728,
    -7.3253, 11.0533, 94.9077,
    -13.3254, 0.6592, 95.094,
    -7.3252, -9.7335, 95.0504,
    4.6752, -9.7323, 95.217
];

/// The SLP local search from axes tilted 1e-3 rad off the optimum (four sides)
/// converges in a few LPs: MCC and MIC to the optimum of the full search; the
/// MZC valley of set 3 holds two minima 6.5e-5 rad and 9e-9 mm apart, so every
/// search ends in one of them and at least one in the optimum.
#[test]
fn local_search_reaches_the_optimum_from_1e3_rad_off() {
    let c = centroid(&SET3, 3);
    let q: Vec<f64> = SET3.chunks_exact(3).flat_map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]]).collect();
    let size = q.chunks_exact(3).map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0, f64::max);
    for crit in [Criterion::MinCircumscribed, Criterion::MaxInscribed, Criterion::MinZone] {
        let best = fit(&SET3, crit, &Options::default()).unwrap();
        let opt = Vector3::from(best.direction);
        let target = objective(&q, &opt, crit, size);
        let len = q.chunks_exact(3).map(|p| Vector3::new(p[0], p[1], p[2]).dot(&opt).abs()).fold(0.0, f64::max);
        let (u, v) = orthonormal_basis(&opt);
        let mut hits = 0;
        for k in 0..4 {
            let th = 0.5 + k as f64 * FRAC_PI_2;
            let a0 = (opt + (u * th.cos() + v * th.sin()) * 1e-3).normalize();
            let (t, f, zone) = fit2d(&q, &a0, crit).unwrap();
            let (fu, fv) = frame(t, f);
            let p0 = Vector3::from(fu) * zone.center[0] + Vector3::from(fv) * zone.center[1];
            let start = objective(&q, &a0, crit, size);
            let local = slp::descend(&q, crit, slp::Axis::new(a0, p0), 1e-3 * len, len, size, &|_| true);
            let reached = objective(&q, &local.axis.dir, crit, size);
            assert!(start > target + 1e-6, "{crit:?}: the start is not off the optimum");
            assert!(local.steps <= 12, "{crit:?} start {k}: {} LPs", local.steps);
            let slack = if crit == Criterion::MinZone { 1e-8 } else { 1e-10 };
            assert!(reached <= target + slack, "{crit:?} start {k}: {reached} vs {target}");
            if reached <= target + 1e-12 {
                assert!(local.axis.dir.cross(&opt).norm() < 1e-12);
                hits += 1;
            }
        }
        assert!(hits >= 1, "{crit:?}: no search reached the optimum");
    }
}

#[test]
fn projection_follows_the_errata() {
    let (t, f) = (0.4, -2.1);
    let a = axis(t, f);
    let q = project(&a, t, f);
    assert!(q[0].abs() < 1e-15 && q[1].abs() < 1e-15);
    let (t2, f2) = angles(&[-a[0], -a[1], -a[2]]);
    assert!((t2 - t).abs() < 1e-15 && (f2 - f).abs() < 1e-15);
}

/// A deterministic perturbation of every coordinate by up to `amp` (mm).
fn jitter(pts: &[f64], amp: f64, salt: usize) -> Vec<f64> {
    pts.iter()
        .enumerate()
        .map(|(i, x)| x + amp * (((i * 2654435761 + salt * 40503) % 1000) as f64 / 500.0 - 1.0))
        .collect()
}

/// Warm starts (a Monte Carlo trial of the measured points): from the unperturbed fit's
/// axis, the local method on perturbed copies gives the global search's value, on the
/// active subset (2050 points) and directly (24 points), for every criterion.
#[test]
fn warm_start_equals_the_global_search_on_perturbed_points() {
    for (pts, crits) in [
        (noisy(2050), vec![Criterion::MinCircumscribed, Criterion::MinZone]),
        (SET3.to_vec(), vec![Criterion::MinCircumscribed, Criterion::MaxInscribed, Criterion::MinZone]),
    ] {
        for crit in crits {
            let opts = Options { max_iterations: 60, ..Options::default() };
            let measured = fit(&pts, crit, &opts).unwrap();
            let warm = Warm { point: measured.point, direction: measured.direction };
            for salt in 0..3 {
                let trial = jitter(&pts, 5e-4, salt);
                let global = fit(&trial, crit, &opts).unwrap();
                let (near, fallback) = fit_near(&trial, crit, &opts, &warm).unwrap();
                assert!(!fallback, "{crit:?} trial {salt}: fell back");
                assert_foot_of_centroid(&trial, &near);
                assert_foot_of_centroid(&trial, &global);
                assert!(near.outside.is_none());
                assert!((near.size() - global.size()).abs() < 1e-9, "{crit:?} trial {salt}: {} vs {}", near.size(), global.size());
                let e = lsq::axis_extent(&trial, &near.point, &near.direction);
                assert!(crit == Criterion::MaxInscribed || e.max <= near.r_out + 1e-9, "{crit:?}: a point outside");
                assert!(crit == Criterion::MinCircumscribed || e.min >= near.r_in - 1e-9, "{crit:?}: a point inside");
            }
        }
    }
}

/// A warm start whose optimum lies on the boundary of the search cone falls back to the
/// global search (which walks the boundary ring); a bad warm start is refused.
#[test]
fn warm_start_on_the_cone_boundary_falls_back() {
    let pts = noisy(400);
    let lsq_dir = lsq::cylinder(&pts, None).unwrap().direction;
    // a cone of 1e-4 rad about an axis tilted 0.01 rad off: the optimum sits on its rim
    let a = Vector3::from(lsq_dir);
    let (u, _) = orthonormal_basis(&a);
    let off = (a + u * 0.01).normalize();
    let opts = Options { search: Search { axis: Some([off[0], off[1], off[2]]), max_tilt: 1e-4 }, ..Options::default() };
    let global = fit(&pts, Criterion::MinZone, &opts).unwrap();
    let warm = Warm { point: global.point, direction: global.direction };
    let (near, fallback) = fit_near(&pts, Criterion::MinZone, &opts, &warm).unwrap();
    assert!(fallback);
    assert_eq!(near.size(), global.size());
    let bad = Warm { point: [0.0; 3], direction: [0.0; 3] };
    assert!(fit_near(&pts, Criterion::MinZone, &Options::default(), &bad).is_err());
}

/// An axis on the search cone's own axis is not on its boundary, even when |a . w|
/// rounds to 1 + 1 ulp (its acos would be NaN): the tilt is clamped to 0.
#[test]
fn an_axis_on_the_cone_axis_has_tilt_zero() {
    use super::search::tilt_from;
    let w = Vector3::new(0.0004999999791666616, 3.531584452478655e-18, 0.9999998750000026);
    let a = Vector3::new(0.0004999999790808742, 3.5315844518727244e-18, 0.9999998750000026);
    assert!(a.dot(&w) > 1.0 || a.dot(&w) <= 1.0); // whichever way it rounds ...
    assert_eq!(tilt_from(&(w * (1.0 + f64::EPSILON)), &w), 0.0); // ... a dot above 1 gives 0, not NaN
    assert!(tilt_from(&a, &w) < 1e-9);
    assert!((tilt_from(&Vector3::x(), &Vector3::z()) - FRAC_PI_2).abs() < 1e-15);
}

#[test]
fn the_one_pass_checks_of_a_warm_fit_agree_with_the_complete_checks() {
    // spread points: the same validated axis, the same largest spread to rounding; bad or
    // degenerate points: the complete checks' typed errors
    let opts = Options::default();
    let pts: Vec<f64> = (0..400)
        .flat_map(|i| {
            let t = i as f64 * 0.37;
            [1e4 + 5.0 * t.cos(), -2e4 + 5.0 * t.sin(), 3e4 + (i % 37) as f64 * 0.8]
        })
        .collect();
    let (a, sa) = checked(&pts, &opts).unwrap();
    let (b, sb) = checked_near(&pts, &opts).unwrap();
    assert_eq!(a, b);
    assert!((sa - sb).abs() <= 1e-9 * sa, "{sa} {sb}");
    let line: Vec<f64> = (0..50).flat_map(|i| [1.0, 2.0, i as f64]).collect();
    let mut nan = pts.clone();
    nan[7] = f64::NAN;
    let mut huge = pts.clone();
    huge[7] = 1e151;
    for bad in [vec![1.0; 30], line, nan, huge, pts[..12].to_vec()] {
        let (e1, e2) = (checked(&bad, &opts).unwrap_err(), checked_near(&bad, &opts).unwrap_err());
        assert_eq!((e1.kind, e1.message), (e2.kind, e2.message));
    }
}
