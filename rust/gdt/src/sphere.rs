//! Minimum-zone sphere (sphericity): two concentric spheres of least radial
//! separation enclosing the points, min over c of max_i |p_i - c| - min_i |p_i - c|.
//!
//! Sequential linear programming from the least-squares centre: with u_i the unit
//! vector from c to p_i, |p_i - c - s| = d_i - u_i.s + O(|s|^2 / d_i), so a step s
//! solves the LP  min R - r  s.t.  r <= d_i - u_i.s <= R,  |s_k| <= rho  (clarabel),
//! on the points of largest and smallest distance (a working set that grows by the
//! points that turn out extreme). A step is taken when the width recomputed over all
//! points decreases, otherwise the trust radius rho shrinks; the iteration stops when
//! rho falls below 1e-12 of the sphere's size. At a vertex solution (4 + 1, 3 + 2,
//! 2 + 3 ... control points, the Chebyshev alternation) the steps converge quadratically.
//! The reported width is recomputed from the reported centre.

use crate::vec3::{self, check_points, V3};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use gagekit_core::{GkError, Result};

/// A minimum-zone sphere: centre and the inner / outer radius.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereZone {
    pub center: V3,
    pub r_in: f64,
    pub r_out: f64,
}

const WORKING: usize = 48;

fn extremes(pts: &[f64], c: V3) -> (Vec<f64>, f64, f64) {
    let d: Vec<f64> = pts.chunks_exact(3).map(|p| vec3::norm(vec3::sub([p[0], p[1], p[2]], c))).collect();
    let lo = d.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = d.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    (d, lo, hi)
}

/// The step s (and predicted width) of the LP on the working set.
fn lp_step(pts: &[f64], c: V3, d: &[f64], set: &[usize], rho: f64, scale: f64) -> Result<V3> {
    // variables x = (s0, s1, s2, R, r) scaled by `scale`; rows: d_i - u.s - R <= 0 -> -u.s - R <= -d_i;
    // r - d_i + u.s <= 0 -> u.s + r <= d_i; box |s_k| <= rho
    let m = 2 * set.len() + 6;
    let mut dense = vec![vec![0.0; 5]; m];
    let mut b = vec![0.0; m];
    for (k, &i) in set.iter().enumerate() {
        let p = vec3::at(pts, i);
        let u = vec3::scale(vec3::sub(p, c), 1.0 / d[i].max(f64::MIN_POSITIVE));
        for j in 0..3 {
            dense[2 * k][j] = -u[j];
            dense[2 * k + 1][j] = u[j];
        }
        dense[2 * k][3] = -1.0;
        dense[2 * k + 1][4] = 1.0;
        b[2 * k] = -d[i] / scale;
        b[2 * k + 1] = d[i] / scale;
    }
    for j in 0..3 {
        let r0 = 2 * set.len() + 2 * j;
        dense[r0][j] = 1.0;
        dense[r0 + 1][j] = -1.0;
        b[r0] = rho / scale;
        b[r0 + 1] = rho / scale;
    }
    let (mut colptr, mut rowval, mut nzval) = (vec![0usize], Vec::new(), Vec::new());
    for j in 0..5 {
        for (i, row) in dense.iter().enumerate() {
            if row[j] != 0.0 {
                rowval.push(i);
                nzval.push(row[j]);
            }
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(m, 5, colptr, rowval, nzval);
    let p = CscMatrix::zeros((5, 5));
    let q = [0.0, 0.0, 0.0, 1.0, -1.0];
    let cones = [SupportedConeT::NonnegativeConeT(m)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-13)
        .tol_gap_rel(1e-13)
        .tol_feas(1e-13)
        .build()
        .map_err(|e| GkError::numerical(format!("minimum-zone sphere: LP settings: {e:?}")))?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| GkError::numerical(format!("minimum-zone sphere: LP setup failed: {e:?}")))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        s => return Err(GkError::numerical(format!("minimum-zone sphere: the LP solver stopped with status {s:?}"))),
    }
    let x = &solver.solution.x;
    Ok([x[0] * scale, x[1] * scale, x[2] * scale])
}

/// Minimum-zone sphere of (n, 3) points, n >= 4, not coplanar.
pub fn min_zone(pts: &[f64]) -> Result<SphereZone> {
    const WHAT: &str = "minimum-zone sphere";
    let n = check_points(pts, 4, WHAT)?;
    let ls = gagekit_form::lsq::sphere(pts, 3)?;
    let mut c: V3 = [ls.center[0], ls.center[1], ls.center[2]];
    let (mut d, mut lo, mut hi) = extremes(pts, c);
    let scale = hi.max(f64::MIN_POSITIVE);
    let mut rho = 0.1 * (hi - lo).max(1e-9 * scale);
    let mut set: Vec<usize> = Vec::new();
    for _ in 0..400 {
        // working set: the previous one plus the current extremes
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| d[j].total_cmp(&d[i]).then(i.cmp(&j)));
        let k = WORKING.min(n / 2).max(1);
        set.extend(order[..k].iter().copied());
        set.extend(order[n - k..].iter().copied());
        set.sort_unstable();
        set.dedup();
        let s = lp_step(pts, c, &d, &set, rho, scale)?;
        let cand = vec3::add(c, s);
        let (d2, lo2, hi2) = extremes(pts, cand);
        if hi2 - lo2 < hi - lo {
            c = cand;
            d = d2;
            lo = lo2;
            hi = hi2;
            rho = (2.0 * vec3::norm(s)).max(1e-3 * rho);
        } else {
            rho *= 0.25;
        }
        if rho < 1e-12 * scale {
            break;
        }
        if set.len() > 4 * WORKING * 8 {
            set.truncate(0);
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(GkError::numerical(format!("{WHAT}: the iteration lost the centre")));
    }
    Ok(SphereZone { center: c, r_in: lo, r_out: hi })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_spheres_of_known_radii() {
        // points on two concentric spheres (radius 10 and 10.02) about (1, 2, 3): width 0.02
        let mut pts = Vec::new();
        for i in 0..20 {
            for j in 1..10 {
                let (t, f) = (std::f64::consts::TAU * i as f64 / 20.0, std::f64::consts::PI * j as f64 / 10.0);
                let r = if (i + j) % 2 == 0 { 10.0 } else { 10.02 };
                pts.extend([1.0 + r * f.sin() * t.cos(), 2.0 + r * f.sin() * t.sin(), 3.0 + r * f.cos()]);
            }
        }
        let z = min_zone(&pts).unwrap();
        assert!((z.r_out - z.r_in - 0.02).abs() < 1e-10, "{:?}", z);
        assert!(vec3::norm(vec3::sub(z.center, [1.0, 2.0, 3.0])) < 1e-8);
    }

    #[test]
    fn beats_least_squares_on_a_bumpy_sphere() {
        let mut pts = Vec::new();
        for i in 0..30 {
            for j in 1..15 {
                let (t, f) = (std::f64::consts::TAU * i as f64 / 30.0, std::f64::consts::PI * j as f64 / 15.0);
                let r = 5.0 + 0.01 * (3.0 * t).cos() * f.sin() + if i == 3 && j == 4 { 0.05 } else { 0.0 };
                pts.extend([r * f.sin() * t.cos(), r * f.sin() * t.sin(), r * f.cos()]);
            }
        }
        let z = min_zone(&pts).unwrap();
        let ls = gagekit_form::lsq::sphere(&pts, 3).unwrap();
        let (_, lo, hi) = extremes(&pts, [ls.center[0], ls.center[1], ls.center[2]]);
        assert!(z.r_out - z.r_in <= hi - lo + 1e-15);
        // no small move of the centre narrows the zone
        for s in [[1e-6, 0.0, 0.0], [0.0, -1e-6, 0.0], [0.0, 0.0, 1e-6], [-1e-7, 1e-7, 1e-7]] {
            let (_, l2, h2) = extremes(&pts, vec3::add(z.center, s));
            assert!(h2 - l2 >= z.r_out - z.r_in - 1e-12);
        }
    }
}
