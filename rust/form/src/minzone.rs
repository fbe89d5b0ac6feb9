//! Minimum-zone planes (flatness) and 2-D lines (straightness): the two
//! parallel planes (lines) of least separation enclosing all points.
//!
//! In a frame whose height axis is the current normal, the zone is the linear
//! program  min w  s.t.  0 <= h_i - s.t_i - c <= w  (slopes s, offset c), solved
//! with clarabel. Its active constraints are then solved exactly (d + 1 linear
//! equations), the frame is turned to the new normal and the LP solved again
//! until the slopes vanish: at that fixed point the vertical zone is the
//! orthogonal one. The reported width is always recomputed from the reported
//! normal, max - min of the signed distances, so it is a valid zone whatever
//! the solver's accuracy. The least-squares plane (line) is the first frame.
//! Large point sets are reduced to their convex-hull vertices first (exact:
//! a set and its hull have the same width).

use crate::lsq;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use gagekit_core::{GkError, Result};
use nalgebra::{DMatrix, DVector};

/// Planes of more points are fitted on their convex-hull vertices.
const HULL_ABOVE: usize = 1000;

/// A minimum zone: the mid-plane (mid-line) and the zone width.
#[derive(Debug, Clone, PartialEq)]
pub struct MinZone {
    /// A point on the mid-plane (mid-line), the foot of the centroid.
    pub point: Vec<f64>,
    /// Unit normal (a plane's normal, a 2-D line's normal).
    pub normal: Vec<f64>,
    /// Unit direction of a 2-D line (empty for planes).
    pub direction: Vec<f64>,
    /// Separation of the two bounding planes (lines): the flatness (straightness).
    pub form_error: f64,
    /// Points touching the upper / lower bound (indices into the input).
    pub control_upper: Vec<usize>,
    pub control_lower: Vec<usize>,
    /// LP solves used.
    pub iterations: usize,
    /// Certificate: min and max signed distance of the points to the mid-plane
    /// (mid-line), recomputed from `point` and `normal` (`direction` for a line).
    pub extent: lsq::Extent,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve min w s.t. 0 <= h_i - s.t_i - c <= w on frame coordinates
/// (`tan[i]` has d-1 entries). Returns the slopes.
fn lp_slopes(tan: &[Vec<f64>], h: &[f64], scale: f64) -> Result<Vec<f64>> {
    let n = h.len();
    let k = tan[0].len(); // number of slopes
    let nv = k + 2; // slopes, c, w
    // columns of A (CSC): rows 0..n upper constraints, n..2n lower constraints
    let mut colptr = vec![0usize];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for j in 0..nv {
        let start = rowval.len(); // this column's first entry
        for (i, t) in tan.iter().enumerate() {
            let (up, lo) = if j < k {
                (-t[j] / scale, t[j] / scale)
            } else if j == k {
                (-1.0, 1.0)
            } else {
                (-1.0, 0.0)
            };
            if up != 0.0 {
                rowval.push(i);
                nzval.push(up);
            }
            if lo != 0.0 {
                rowval.push(n + i);
                nzval.push(lo);
            }
        }
        // row indices must be sorted within a column
        let mut pairs: Vec<(usize, f64)> =
            rowval[start..].iter().copied().zip(nzval[start..].iter().copied()).collect();
        pairs.sort_by_key(|p| p.0);
        for (o, (r, v)) in pairs.into_iter().enumerate() {
            rowval[start + o] = r;
            nzval[start + o] = v;
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(2 * n, nv, colptr, rowval, nzval);
    let b: Vec<f64> = h.iter().map(|v| -v / scale).chain(h.iter().map(|v| v / scale)).collect();
    let p = CscMatrix::zeros((nv, nv));
    let mut q = vec![0.0; nv];
    q[k + 1] = 1.0;
    let cones = [SupportedConeT::NonnegativeConeT(2 * n)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .build()
        .map_err(|e| GkError::numerical(format!("minimum zone: LP settings: {e:?}")))?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| GkError::numerical(format!("minimum zone: LP setup failed: {e:?}")))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        s => return Err(GkError::numerical(format!("minimum zone: the LP solver stopped with status {s:?}"))),
    }
    let x = &solver.solution.x;
    let z = &solver.solution.z;
    let mut slopes: Vec<f64> = x[..k].to_vec();
    // Exact polish: the k+2 constraints of largest dual value, solved as equations.
    let mut order: Vec<usize> = (0..2 * n).collect();
    order.sort_by(|&i, &j| z[j].total_cmp(&z[i]).then(i.cmp(&j)));
    let act = &order[..nv.min(2 * n)];
    let mut m = DMatrix::<f64>::zeros(nv, nv);
    let mut rhs = DVector::<f64>::zeros(nv);
    for (r, &ci) in act.iter().enumerate() {
        let (i, upper) = if ci < n { (ci, true) } else { (ci - n, false) };
        // h_i - s.t_i - c - (w if upper) = 0
        for j in 0..k {
            m[(r, j)] = tan[i][j] / scale;
        }
        m[(r, k)] = 1.0;
        m[(r, k + 1)] = if upper { 1.0 } else { 0.0 };
        rhs[r] = h[i] / scale;
    }
    let width = |s: &[f64]| {
        let r = tan.iter().zip(h).map(|(t, hv)| hv - dot(s, t));
        let (lo, hi) = r.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        hi - lo
    };
    if let Some(sol) = m.lu().solve(&rhs) {
        let exact: Vec<f64> = sol.iter().take(k).copied().collect();
        if exact.iter().all(|v| v.is_finite()) && width(&exact) <= width(&slopes) {
            slopes = exact;
        }
    }
    Ok(slopes)
}

/// Minimum zone of points (dim 2: a line; dim 3: a plane).
fn min_zone(pts: &[f64], dim: usize) -> Result<MinZone> {
    let what = if dim == 2 { "minimum-zone line" } else { "minimum-zone plane" };
    // the least-squares fit validates the input and gives the first frame
    let (mut normal, c) = if dim == 2 {
        let l = lsq::line(pts, 2)?;
        (vec![-l.direction[1], l.direction[0]], l.point)
    } else {
        let p = lsq::plane(pts)?;
        (p.normal.to_vec(), p.point.to_vec())
    };
    let all: Vec<Vec<f64>> = pts.chunks_exact(dim).map(|p| p.iter().zip(&c).map(|(a, b)| a - b).collect()).collect();
    // the width of a set is that of its convex hull (Eq. 5.21): the LP needs the hull vertices only
    let q: Vec<Vec<f64>> = if dim == 3 && all.len() > HULL_ABOVE {
        gagekit_geometry::convex_hull_indices(pts)?.into_iter().map(|i| all[i].clone()).collect()
    } else {
        all.clone()
    };
    let scale = all.iter().map(|p| dot(p, p).sqrt()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let mut iterations = 0;
    for _ in 0..8 {
        // tangent basis of the current normal
        let tb: Vec<Vec<f64>> = if dim == 2 {
            vec![vec![normal[1], -normal[0]]]
        } else {
            let nv = nalgebra::Vector3::new(normal[0], normal[1], normal[2]);
            let (u, v) = lsq::orthonormal_basis(&nv);
            vec![u.iter().copied().collect(), v.iter().copied().collect()]
        };
        let tan: Vec<Vec<f64>> = q.iter().map(|p| tb.iter().map(|b| dot(p, b)).collect()).collect();
        let h: Vec<f64> = q.iter().map(|p| dot(p, &normal)).collect();
        let s = lp_slopes(&tan, &h, scale)?;
        iterations += 1;
        // new normal: n - sum s_j b_j, normalised (height h = s.t + c on the zone)
        let mut nn = normal.clone();
        for (sj, b) in s.iter().zip(&tb) {
            for d in 0..dim {
                nn[d] -= sj * b[d];
            }
        }
        let norm = dot(&nn, &nn).sqrt();
        nn.iter_mut().for_each(|v| *v /= norm);
        let moved = s.iter().map(|v| v.abs()).fold(0.0, f64::max);
        normal = nn;
        if moved < 1e-15 {
            break;
        }
    }
    if !normal.iter().all(|v| v.is_finite()) {
        return Err(GkError::numerical(format!("{what}: the iteration lost the normal")));
    }
    let dist: Vec<f64> = all.iter().map(|p| dot(p, &normal)).collect();
    let (lo, hi) = dist.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let width = hi - lo;
    let tol = 1e-9 * scale.max(width);
    let control_upper = (0..dist.len()).filter(|&i| hi - dist[i] <= tol).collect();
    let control_lower = (0..dist.len()).filter(|&i| dist[i] - lo <= tol).collect();
    let mid = 0.5 * (lo + hi);
    let point: Vec<f64> = (0..dim).map(|d| c[d] + mid * normal[d]).collect();
    let direction = if dim == 2 { vec![normal[1], -normal[0]] } else { Vec::new() };
    let extent = if dim == 3 {
        lsq::plane_extent(pts, &[point[0], point[1], point[2]], &[normal[0], normal[1], normal[2]])
    } else {
        lsq::line_extent(pts, 2, &point, &direction)
    };
    Ok(MinZone { point, normal, direction, form_error: width, control_upper, control_lower, iterations, extent })
}

/// Minimum-zone plane of 3-D points (flatness).
pub fn plane(pts: &[f64]) -> Result<MinZone> {
    min_zone(pts, 3)
}

/// Minimum-zone line of 2-D points (straightness).
pub fn line2(pts: &[f64]) -> Result<MinZone> {
    min_zone(pts, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_plate_flatness() {
        // corners at heights +-0.01 in a checker pattern: the LS plane is z = 0,
        // the minimum zone tilts nothing and has width 0.02
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let z = if (i + j) % 2 == 0 { 0.01 } else { -0.01 };
                pts.extend_from_slice(&[i as f64 * 10.0 + 1e6, j as f64 * 10.0, z]);
            }
        }
        let z = plane(&pts).unwrap();
        assert!((z.form_error - 0.02).abs() < 1e-12, "{}", z.form_error);
        assert!((z.extent.max - z.extent.min - z.form_error).abs() < 1e-15 && (z.extent.max - 0.01).abs() < 1e-12);
    }

    #[test]
    fn zone_beats_least_squares() {
        // a line with one outlier: the LS line is pulled, the zone is not
        let mut pts = Vec::new();
        for i in 0..20 {
            let x = i as f64;
            let y = 0.5 * x + if i == 19 { 1.0 } else { 0.01 * ((i * 37 % 7) as f64 - 3.0) };
            pts.extend_from_slice(&[x, y]);
        }
        let z = line2(&pts).unwrap();
        let l = lsq::line(&pts, 2).unwrap();
        let e = lsq::line_extent(&pts, 2, &l.point, &l.direction);
        assert!(z.form_error < e.max - e.min);
        // no small rotation improves the width
        let w = |ang: f64| {
            let (c, s) = (ang.cos(), ang.sin());
            let nn = [z.normal[0] * c - z.normal[1] * s, z.normal[0] * s + z.normal[1] * c];
            let d: Vec<f64> = pts.chunks(2).map(|p| p[0] * nn[0] + p[1] * nn[1]).collect();
            d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min)
        };
        for k in [-1e-4, -1e-7, 1e-7, 1e-4] {
            assert!(w(k) >= z.form_error - 1e-13, "{k}: {} < {}", w(k), z.form_error);
        }
    }
}
