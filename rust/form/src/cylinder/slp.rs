//! Local search for a cylinder axis by sequential linear programming (SLP) with a
//! trust region on the 3-D minimax problem behind Eqs. 6.13-6.15.
//!
//! The unknowns are the axis (direction `a`, point `p` with `p . a = 0`) and the
//! radii. About the current axis, with `(u, v)` spanning the plane normal to `a`,
//! a point `q` has the coordinates `s_u, s_v, s_a` and the axis distance
//! `rho = |(s_u, s_v)|`. Moving the axis point by `x u + y v` and tilting the
//! direction to `a + alpha u + beta v` changes `rho` to first order by
//! `-(s_u (x + alpha s_a) + s_v (y + beta s_a)) / rho`. With these linearised
//! distances, each step solves the linear program
//!
//! - MCC: min r_out subject to rho_i + g_i . d <= r_out;
//! - MIC: max r_in subject to rho_i + g_i . d >= r_in;
//! - MZC: min r_out - r_in subject to both,
//!
//! in the box `|d|_inf <= delta` (tilts scaled by the part's half length `len`, so
//! every variable is in mm). A step is taken when it lowers the true value of the
//! criterion by a fair share of what the LP predicted; the box grows after good
//! steps at its edge and shrinks after poor ones. At a vertex solution (as many
//! active points as unknowns) the steps converge quadratically.

use crate::lp;
use super::Criterion;
use crate::lsq::orthonormal_basis;
use nalgebra::Vector3;

/// An axis: unit direction and the point of the axis nearest the origin.
#[derive(Debug, Clone, Copy)]
pub(super) struct Axis {
    pub dir: Vector3<f64>,
    pub point: Vector3<f64>,
}

impl Axis {
    pub fn new(dir: Vector3<f64>, point: Vector3<f64>) -> Self {
        let dir = dir.normalize();
        Self { dir, point: point - dir * point.dot(&dir) }
    }
}

/// Outcome of one local search.
#[derive(Debug, Clone, Copy)]
pub(super) struct Local {
    pub axis: Axis,
    /// Linear programs solved.
    pub steps: usize,
}

/// Most steps of one search.
const MAX_STEPS: usize = 200;

/// Largest and smallest axis distance of the points (flat, row-major).
fn extremes(q: &[f64], ax: &Axis) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for p in q.chunks_exact(3) {
        let w = Vector3::new(p[0], p[1], p[2]) - ax.point;
        let d = (w - ax.dir * w.dot(&ax.dir)).norm();
        lo = lo.min(d);
        hi = hi.max(d);
    }
    (lo, hi)
}

/// Value of the criterion about an axis, with the centre free only through the axis.
pub(super) fn value(q: &[f64], crit: Criterion, ax: &Axis) -> f64 {
    let (lo, hi) = extremes(q, ax);
    match crit {
        Criterion::MinCircumscribed => hi,
        Criterion::MaxInscribed => -lo,
        Criterion::MinZone => hi - lo,
    }
}

/// SLP from `start` with the initial box half-width `delta` (mm); `len` is the
/// part's half length along the axis, `size` its radius about the centroid;
/// `allowed` rejects axis directions outside the search region.
pub(super) fn descend(
    q: &[f64],
    crit: Criterion,
    start: Axis,
    delta: f64,
    len: f64,
    size: f64,
    allowed: &dyn Fn(&Vector3<f64>) -> bool,
) -> Local {
    let (outer, inner) = match crit {
        Criterion::MinCircumscribed => (true, false),
        Criterion::MaxInscribed => (false, true),
        Criterion::MinZone => (true, true),
    };
    let k = 4 + outer as usize + inner as usize;
    let c: Vec<f64> = match crit {
        Criterion::MinCircumscribed => vec![0.0, 0.0, 0.0, 0.0, 1.0],
        Criterion::MaxInscribed => vec![0.0, 0.0, 0.0, 0.0, -1.0],
        Criterion::MinZone => vec![0.0, 0.0, 0.0, 0.0, 1.0, -1.0],
    };
    // below these the model decrease and the box are rounding noise
    let ftol = 1e-15 * size;
    let delta_min = 1e-14 * size;
    let delta_max = 0.1 * size;
    let n = q.len() / 3;
    let mut ax = start;
    let mut f = value(q, crit, &ax);
    let mut delta = delta.clamp(delta_min, delta_max);
    let (mut grad, mut rho) = (vec![0.0; 4 * n], vec![0.0; n]);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut steps = 0;
    while steps < MAX_STEPS && f.is_finite() {
        // distances and their gradients about the current axis
        let (u, v) = orthonormal_basis(&ax.dir);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for (i, p) in q.chunks_exact(3).enumerate() {
            let w = Vector3::new(p[0], p[1], p[2]) - ax.point;
            let (su, sv, sa) = (w.dot(&u), w.dot(&v), w.dot(&ax.dir) / len);
            let r = su.hypot(sv);
            let (eu, ev) = if r > 0.0 { (su / r, sv / r) } else { (0.0, 0.0) };
            grad[4 * i..4 * i + 4].copy_from_slice(&[-eu, -ev, -eu * sa, -ev * sa]);
            rho[i] = r;
            lo = lo.min(r);
            hi = hi.max(r);
        }
        // the LP: box rows, then the points that can become active within the box
        // (a row whose slack exceeds (|g_i|_1 + max |g|_1) delta never binds)
        a.clear();
        b.clear();
        for j in 0..4 {
            for s in [1.0, -1.0] {
                let mut row = [0.0; 6];
                row[j] = s;
                a.extend_from_slice(&row[..k]);
                b.push(delta);
            }
        }
        let gmax = (0..n).map(|i| grad[4 * i..4 * i + 4].iter().map(|g| g.abs()).sum::<f64>()).fold(0.0, f64::max);
        for i in 0..n {
            let g = &grad[4 * i..4 * i + 4];
            let reach = (g.iter().map(|g| g.abs()).sum::<f64>() + gmax) * delta;
            if outer && hi - rho[i] <= reach {
                a.extend_from_slice(g);
                a.push(-1.0);
                if inner {
                    a.push(0.0);
                }
                b.push(hi - rho[i]);
            }
            if inner && rho[i] - lo <= reach {
                a.extend(g.iter().map(|g| -g));
                if outer {
                    a.push(0.0);
                }
                a.push(1.0);
                b.push(rho[i] - lo);
            }
        }
        steps += 1;
        let Some(z) = lp::minimize(&a, &b, &c) else { break };
        let predicted = -c.iter().zip(&z).map(|(c, z)| c * z).sum::<f64>();
        if predicted.is_nan() || predicted <= ftol {
            break;
        }
        let dir = ax.dir + (u * z[2] + v * z[3]) / len;
        let trial = Axis::new(dir, ax.point + u * z[0] + v * z[1]);
        let f_trial = if allowed(&trial.dir) { value(q, crit, &trial) } else { f64::INFINITY };
        let ratio = (f - f_trial) / predicted;
        if ratio > 1e-4 {
            ax = trial;
            f = f_trial;
        }
        let step = z[..4].iter().fold(0.0f64, |m, z| m.max(z.abs()));
        delta = lp::next_radius(delta, step, ratio, delta_max);
        if delta < delta_min {
            break;
        }
    }
    Local { axis: ax, steps }
}
