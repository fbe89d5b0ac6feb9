//! Least-squares cylinder: Levenberg-Marquardt on the orthogonal distances (Forbes 1989),
//! started from every principal axis of the data and from the best directions of a grid
//! over the half sphere ([`grid_axes`]).
//!
//! The principal axes alone miss the axis of a short partial bore: on a 141-degree arc
//! 19.8 mm long of radius 28.7 mm, the spreads along the axis and along the arc's depth
//! are nearly equal (19.8 and 19.1 mm), their principal directions mix, and every start
//! lay in the basin of a wrong cylinder (radius 7.8 mm across the patch, RMS residual
//! 2.75 mm against the true 0.1 um). The grid's directions are judged by the circle fit
//! of the points projected along them ([`circle_score`]), cheap on a subsample.
//!
//! Large inputs (more than [`SUBSAMPLE_ABOVE`] points) choose the start and converge on an
//! evenly spaced subsample of [`SUBSAMPLE`] points first, then finish on all points from
//! there: the last iterations (and the Gauss-Newton polish to rounding) run on all points,
//! so the result is the stationary point of the full problem, in a few passes over the
//! data instead of some sixty.

use super::frame::{
    arr, centred3, centred3_scatter, centroid, check_points, clearly_spread, grid_axes, orthonormal_basis, principal_axes, upper,
    vec3, DEGENERATE,
};
use super::lm::{levenberg_marquardt_fused, normal_equations_cost};
use super::sphere::algebraic_sphere;
use super::Vector3;
use gagekit_core::{GkError, Result};
use nalgebra::DVector;

/// A cylinder: a point on the axis (the foot of the data centroid), unit axis
/// direction, radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Cylinder {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub radius: f64,
}

/// Levenberg–Marquardt refinement of a cylinder from a starting axis, on
/// centred points. Returns the cylinder (in centred coordinates) and its cost.
fn refine_cylinder(
    q: &[[f64; 3]],
    l0: Vector3<f64>,
    a0: Vector3<f64>,
    r0: f64,
    max_iter: usize,
) -> Result<(Cylinder, f64)> {
    type S = (Vector3<f64>, Vector3<f64>, f64);
    // Step (x0, y0, alpha, beta, dr) in the frame (u, v, a) of the current axis:
    // point += x0 u + y0 v, direction = normalize(a + alpha u + beta v) (Forbes 1989).
    // A trial step is judged by the cost this pass sums beside the normal equations (the
    // squared distance to the axis by the cross product, as a separate cost pass had it,
    // bit for bit: one pass an accepted step instead of two, the same iterates).
    let eval = |s: &S| {
        let (u, v) = orthonormal_basis(&s.1);
        normal_equations_cost::<5>(q, |x| {
            let d = vec3(x) - s.0;
            let cost = (d.cross(&s.1).norm() - s.2).powi(2);
            let (xu, yv, z) = (d.dot(&u), d.dot(&v), d.dot(&s.1));
            let rho = xu.hypot(yv);
            let (cx, cy) = if rho > 0.0 { (xu / rho, yv / rho) } else { (0.0, 0.0) };
            (cost, rho - s.2, [-cx, -cy, -cx * z, -cy * z, -1.0])
        })
    };
    let apply = |s: &S, st: &DVector<f64>| {
        let (u, v) = orthonormal_basis(&s.1);
        let l = s.0 + u * st[0] + v * st[1];
        let a = (s.1 + u * st[2] + v * st[3]).normalize();
        // keep the axis point at the foot of the centroid (origin of the centred data)
        let l = l - a * l.dot(&a);
        (l, a, s.2 + st[4])
    };
    let l0 = l0 - a0 * l0.dot(&a0);
    let (s, _, f) = levenberg_marquardt_fused((l0, a0, r0), 5, r0, max_iter, eval, apply, "cylinder")?;
    Ok((Cylinder { point: arr(&s.0), direction: arr(&s.1), radius: s.2.abs() }, f))
}

/// The sum of squared radial residuals of the points `sub` projected along `a` about
/// their algebraic (Kasa) circle ([`algebraic_sphere`]): the cylinder cost of that direction
/// with the circle's centre and radius not yet optimised, the score of a grid start
/// ([`grid_axes`]). Two passes and a 3 x 3 solve, no allocation (it runs for 127 directions
/// a fit).
fn circle_score(sub: &[[f64; 3]], a: &Vector3<f64>) -> Option<f64> {
    let (u, v) = orthonormal_basis(a);
    let project = |p: &[f64; 3]| [vec3(p).dot(&u), vec3(p).dot(&v), 0.0];
    let (c, r) = algebraic_sphere(sub.iter().map(project), 2)?;
    Some(
        sub.iter()
            .map(|p| {
                let [x, y, _] = project(p);
                ((x - c[0]).hypot(y - c[1]) - r).powi(2)
            })
            .sum(),
    )
}

/// Inputs above this many points start on a subsample.
const SUBSAMPLE_ABOVE: usize = 40_000;
/// Points of that subsample (every k-th point).
const SUBSAMPLE: usize = 20_000;

/// Least-squares cylinder, minimising the sum of squared orthogonal distances.
///
/// Starts from each principal axis of the data (and from `start_axis` when
/// given): the projected points' least-squares circle gives the start
/// position and radius; the lowest-cost refinement wins.
pub fn cylinder(pts: &[f64], start_axis: Option<[f64; 3]>) -> Result<Cylinder> {
    cylinder_from(pts, start_axis, true)
}

/// [`cylinder`] from `axis` alone (no principal-axis starts): for points near those of a
/// fit whose axis is `axis` (a Monte Carlo trial of the measured points), whose minimum
/// lies in the basin of that axis.
pub fn cylinder_near(pts: &[f64], axis: [f64; 3]) -> Result<Cylinder> {
    cylinder_from(pts, Some(axis), false)
}

fn cylinder_from(pts: &[f64], start_axis: Option<[f64; 3]>, principal: bool) -> Result<Cylinder> {
    check_points(pts, 3, 5, "cylinder")?;
    let c = centroid(pts, 3);
    let spreads = |sv: [f64; 3]| {
        if sv[0] == 0.0 {
            return Err(GkError::degenerate("cylinder: all points coincide"));
        }
        if sv[1] <= DEGENERATE * sv[0] {
            return Err(GkError::degenerate("cylinder: the points are collinear; no cylinder is determined"));
        }
        Ok(())
    };
    // from a given axis alone the principal axes only check the spreads: from the scatter
    // summed with the centred copy when that decides them (`clearly_spread`), else as before
    let (q, mut starts) = if principal {
        let q = centred3(pts, 3, &c);
        let (sv, axes) = principal_axes(&q);
        spreads(sv)?;
        (q, axes.to_vec())
    } else {
        let (q, s) = centred3_scatter(pts, &c);
        if !clearly_spread(&s) {
            spreads(principal_axes(&q).0)?;
        }
        (q, Vec::new())
    };
    if let Some(a) = start_axis {
        let a = vec3(&a);
        if a.norm() > 0.0 && a.iter().all(|v| v.is_finite()) {
            starts.insert(0, a.normalize());
        }
    }
    // Phase 1: a few iterations from every start; phase 2: the best to convergence
    // (large inputs: both on the subsample, then to convergence on all points).
    let sub: Vec<[f64; 3]>;
    let first: &[[f64; 3]] = if q.len() > SUBSAMPLE_ABOVE {
        sub = q.iter().step_by(q.len().div_ceil(SUBSAMPLE)).copied().collect();
        &sub
    } else {
        &q
    };
    if principal {
        let grid = grid_axes(first, &starts[starts.len() - 3..], circle_score);
        starts.extend(grid);
    }
    let mut best: Option<(Cylinder, f64)> = None;
    let mut last_err = None;
    for a in starts {
        let (u, v) = orthonormal_basis(&a);
        let Some((off, r)) = algebraic_sphere(first.iter().map(|x| [vec3(x).dot(&u), vec3(x).dot(&v), 0.0]), 2) else { continue };
        let l0 = u * off[0] + v * off[1];
        match refine_cylinder(first, l0, a, r, 6) {
            Ok((cyl, f)) => {
                if best.as_ref().is_none_or(|b| f < b.1) {
                    best = Some((cyl, f));
                }
            }
            Err(e) => last_err = Some(e),
        }
    }
    if let Some((b, _)) = &best {
        let (l, a) = (vec3(&b.point), vec3(&b.direction));
        let mut b = refine_cylinder(first, l, a, b.radius, 500)?;
        if first.len() < q.len() {
            let (l, a) = (vec3(&b.0.point), vec3(&b.0.direction));
            b = refine_cylinder(&q, l, a, b.0.radius, 500)?;
        }
        best = Some(b);
    }
    let (cyl, _) = best.ok_or_else(|| {
        last_err.unwrap_or_else(|| GkError::degenerate("cylinder: the points do not determine a cylinder"))
    })?;
    let p = vec3(&cyl.point) + vec3(&c);
    Ok(Cylinder { point: arr(&p), direction: upper(cyl.direction), ..cyl })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::axis_extent;

    fn cyl_points(n: usize, l: [f64; 3], a: [f64; 3], r: f64, noise: f64) -> Vec<f64> {
        let a = vec3(&a).normalize();
        let (u, v) = orthonormal_basis(&a);
        let mut out = Vec::new();
        for i in 0..n {
            let t = i as f64 * 2.399963;
            let z = (i as f64 * 0.618034).fract() * 40.0 - 20.0;
            let rr = r + noise * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
            let p = vec3(&l) + a * z + (u * t.cos() + v * t.sin()) * rr;
            out.extend_from_slice(&[p[0], p[1], p[2]]);
        }
        out
    }

    #[test]
    fn exact_cylinder_far_from_origin() {
        let l = [1e6, -2e6, 5e5];
        let a = [0.3, -0.2, 0.9];
        let pts = cyl_points(50, l, a, 12.5, 0.0);
        let c = cylinder(&pts, None).unwrap();
        assert!((c.radius - 12.5).abs() < 1e-8, "{}", c.radius);
        let an = vec3(&a).normalize();
        assert!(vec3(&c.direction).cross(&an).norm() < 1e-10);
        let e = axis_extent(&pts, &c.point, &c.direction);
        assert!(e.max - e.min < 1e-7);
    }

    #[test]
    fn coincident_points() {
        assert!(cylinder(&[0.0; 15], None).is_err());
    }

    #[test]
    fn from_an_axis_the_spread_checks_and_input_errors_are_those_of_the_principal_path() {
        use gagekit_core::ErrorKind;
        let a = [0.0, 0.0, 1.0];
        // coincident, collinear, a NaN, a coordinate beyond MAX_COORD: the same errors
        let line: Vec<f64> = (0..50).flat_map(|i| [1.0, 2.0, i as f64]).collect();
        let mut nan = cyl_points(50, [0.0; 3], a, 3.0, 0.0);
        nan[7] = f64::NAN;
        let mut huge = cyl_points(50, [0.0; 3], a, 3.0, 0.0);
        huge[7] = 1e151;
        for pts in [vec![1.0; 30], line, nan, huge] {
            let (e1, e2) = (cylinder(&pts, None).unwrap_err(), cylinder_near(&pts, a).unwrap_err());
            assert_eq!((e1.kind, e1.message), (e2.kind, e2.message));
        }
        assert_eq!(cylinder_near(&[1.0; 30], a).unwrap_err().kind, ErrorKind::DegenerateGeometry);
        // the scatter's certificate never passes points the recomputed spreads would refuse,
        // and defers (recomputes) when barely spread
        for (w, want) in [(1e-7, false), (1e-12, false), (1e-1, true), (3.0, true)] {
            let pts: Vec<f64> = (0..60).flat_map(|i| [1.0 + w * ((i % 2) as f64), 2.0 + w * ((i % 3) as f64), i as f64]).collect();
            let c = centroid(&pts, 3);
            let (q, s) = centred3_scatter(&pts, &c);
            assert_eq!(q, centred3(&pts, 3, &c));
            assert_eq!(clearly_spread(&s), want, "width {w}");
            let (sv, _) = principal_axes(&q);
            assert!(!clearly_spread(&s) || sv[1] > 1e-4 * sv[0]);
        }
    }

    /// Points on an arc of `arc` rad of a cylinder (point `p`, axis `a`, radius `r`,
    /// length `len`) with noise of size `noise` (a sum of four uniforms).
    fn arc_points(seed: u64, n: usize, p: [f64; 3], a: [f64; 3], r: f64, len: f64, arc: f64, noise: f64) -> Vec<f64> {
        use rand::SeedableRng;
        super::super::warm::tests::cyl(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed), n, p, a, r, len, arc, noise)
    }

    /// The sum of squared orthogonal residuals of `pts` to `c`.
    fn cost(pts: &[f64], c: &Cylinder) -> f64 {
        let (p, a) = (vec3(&c.point), vec3(&c.direction));
        pts.chunks(3).map(|x| ((vec3(x) - p).cross(&a).norm() - c.radius).powi(2)).sum()
    }

    #[test]
    fn a_short_partial_bore_finds_its_axis() {
        // a 141-degree arc 19.8 mm long of radius 28.7 mm: its spreads along the axis and
        // the arc's depth are nearly equal, and from the principal axes alone the fit was a
        // cylinder of radius 7.8 mm across the patch (RMS residual 2.75 mm)
        let a = [0.0, 0.4, 1.0];
        let pts = arc_points(143, 3000, [0.0; 3], a, 28.697101712930213, 19.791287844194095, 2.4610161528973484, 1e-4);
        let c = cylinder(&pts, None).unwrap();
        assert!((c.radius - 28.6971).abs() < 1e-3, "{c:?}");
        assert!(vec3(&c.direction).cross(&vec3(&a).normalize()).norm() < 1e-5, "{c:?}");
        assert!((cost(&pts, &c) / 3000.0).sqrt() < 1e-4);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// On arcs of 60 to 360 degrees whose length makes the spread along the axis near
        /// (0.6 to 1.6 times) that across the arc's depth or along its chord (where the
        /// principal directions mix), the complete fit is no worse than the fit started from
        /// the true axis: it finds the global basin.
        #[test]
        fn the_complete_fit_is_no_worse_than_the_fit_from_the_true_axis(
            seed in 0u64..1000, far in 0.0f64..1e4, r in 2.0f64..80.0, arc in 1.05f64..6.3,
            chord in proptest::bool::ANY, ratio in 0.6f64..1.6, noise in 1e-4f64..0.01, tilt in -1.0f64..1.0,
        ) {
            let len = crate::lsq::warm::tests::mixing_length(r, arc, ratio, chord);
            let a = [tilt, 0.4, 1.0];
            let pts = arc_points(seed, 2000, [far, -0.5 * far, 0.3 * far], a, r, len, arc, noise);
            let c = cylinder(&pts, None).unwrap();
            let t = cylinder_near(&pts, a).unwrap();
            let (fc, ft) = (cost(&pts, &c), cost(&pts, &t));
            proptest::prop_assert!(fc <= ft * (1.0 + 1e-9) + 1e-20, "{fc:e} > {ft:e}: {c:?} against {t:?}");
        }
    }
}
