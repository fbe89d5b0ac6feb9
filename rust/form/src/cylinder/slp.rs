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
pub(crate) struct Axis {
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
pub(crate) struct Local {
    pub axis: Axis,
    /// Linear programs solved.
    pub steps: usize,
}

/// Most steps of one search.
pub(crate) const MAX_STEPS: usize = 200;

/// A cone's taper for the same local search (issue 25: cones). The residual of a point
/// is its distance to the cone of half angle `psi` through the reference section (the
/// section through the origin, i.e. through the foot of the points' centroid on the axis),
/// measured normal to the cone (`normal`: e = rho cos psi - z sin psi, the minimum zone)
/// or radially (e = rho - z tan psi: the radius at the reference section, the minimum
/// circumscribed and maximum inscribed cones). `free`: the half angle is a variable.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Taper {
    pub psi: f64,
    pub free: bool,
    pub normal: bool,
}

impl Taper {
    /// Residual of a point at axis distance `rho`, axial coordinate `z`.
    pub(crate) fn residual(&self, rho: f64, z: f64) -> f64 {
        if self.normal {
            rho * self.psi.cos() - z * self.psi.sin()
        } else {
            rho - z * self.psi.tan()
        }
    }
}

/// Residual of each point about an axis: its axis distance (cylinder) or its distance
/// to the cone `taper`.
fn residual(w: &Vector3<f64>, ax: &Axis, taper: Option<&Taper>) -> f64 {
    let z = w.dot(&ax.dir);
    let rho = (w - ax.dir * z).norm();
    taper.map_or(rho, |t| t.residual(rho, z))
}

/// Smallest and largest residual of the points (flat, row-major).
fn extremes(q: &[f64], ax: &Axis, taper: Option<&Taper>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in q.chunks_exact(3) {
        let d = residual(&(Vector3::new(p[0], p[1], p[2]) - ax.point), ax, taper);
        lo = lo.min(d);
        hi = hi.max(d);
    }
    (lo, hi.max(if taper.is_none() { 0.0 } else { f64::NEG_INFINITY }))
}

/// Value of the criterion about an axis (`taper` None) or a cone, with the centre free
/// only through the axis: the largest residual (MC), minus the smallest (MI), their range (MZ).
pub(crate) fn tapered_value(q: &[f64], crit: Criterion, ax: &Axis, taper: Option<&Taper>) -> f64 {
    let (lo, hi) = extremes(q, ax, taper);
    match crit {
        Criterion::MinCircumscribed => hi,
        Criterion::MaxInscribed => -lo,
        Criterion::MinZone => hi - lo,
    }
}

/// SLP from `start` with the initial box half-width `delta` (mm); `len` is the
/// part's half length along the axis, `size` its radius about the centroid;
/// `allowed` rejects axis directions outside the search region.
pub(crate) fn descend(
    q: &[f64],
    crit: Criterion,
    start: Axis,
    delta: f64,
    len: f64,
    size: f64,
    allowed: &dyn Fn(&Vector3<f64>) -> bool,
) -> Local {
    descend_tapered(q, crit, start, None, delta, len, size, &|a, _| allowed(a)).0
}

/// The LP of one step: its unknowns and costs for a criterion, and the scratch rows.
struct StepLp {
    outer: bool,
    inner: bool,
    /// Geometric unknowns: axis offset (2), tilt (2), the half angle of a free cone.
    kg: usize,
    c: Vec<f64>,
    grad: Vec<f64>,
    rho: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl StepLp {
    fn new(crit: Criterion, taper: Option<&Taper>, n: usize) -> Self {
        let (outer, inner) = match crit {
            Criterion::MinCircumscribed => (true, false),
            Criterion::MaxInscribed => (false, true),
            Criterion::MinZone => (true, true),
        };
        let kg = 4 + taper.is_some_and(|t| t.free) as usize;
        let mut c = vec![0.0; kg + outer as usize + inner as usize];
        match crit {
            Criterion::MinCircumscribed => c[kg] = 1.0,
            Criterion::MaxInscribed => c[kg] = -1.0,
            Criterion::MinZone => {
                c[kg] = 1.0;
                c[kg + 1] = -1.0;
            }
        }
        Self { outer, inner, kg, c, grad: vec![0.0; kg * n], rho: vec![0.0; n], a: Vec::new(), b: Vec::new() }
    }

    /// The step's LP about `ax` in the box `delta`: its solution, the decrease it predicts
    /// and the basis (u, v) normal to the axis its offsets and tilts are in.
    fn solve(&mut self, q: &[f64], ax: &Axis, taper: Option<&Taper>, delta: f64, len: f64) -> Option<(Vec<f64>, f64, Vector3<f64>, Vector3<f64>)> {
        let (kg, outer, inner) = (self.kg, self.outer, self.inner);
        let k = self.c.len();
        let n = q.len() / 3;
        // residuals and their gradients about the current axis
        let (u, v) = orthonormal_basis(&ax.dir);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (i, p) in q.chunks_exact(3).enumerate() {
            let w = Vector3::new(p[0], p[1], p[2]) - ax.point;
            let (su, sv, sa) = (w.dot(&u), w.dot(&v), w.dot(&ax.dir) / len);
            let r = su.hypot(sv);
            let (eu, ev) = if r > 0.0 { (su / r, sv / r) } else { (0.0, 0.0) };
            let g = &mut self.grad[kg * i..kg * (i + 1)];
            let e = match taper {
                None => {
                    g.copy_from_slice(&[-eu, -ev, -eu * sa, -ev * sa]);
                    r
                }
                Some(t) => {
                    // d rho as above; the tilt moves z by (alpha su + beta sv) / len
                    let z = sa * len;
                    let (m, k_z, k_psi) = if t.normal {
                        let (cp, sp) = (t.psi.cos(), t.psi.sin());
                        (cp, sp, -r * sp - z * cp)
                    } else {
                        let tp = t.psi.tan();
                        (1.0, tp, -z * (1.0 + tp * tp))
                    };
                    g[..4].copy_from_slice(&[-eu * m, -ev * m, -eu * sa * m - k_z * su / len, -ev * sa * m - k_z * sv / len]);
                    if t.free {
                        g[4] = k_psi / len;
                    }
                    t.residual(r, z)
                }
            };
            self.rho[i] = e;
            lo = lo.min(e);
            hi = hi.max(e);
        }
        if taper.is_none() {
            hi = hi.max(0.0);
        }
        // the LP: box rows, then the points that can become active within the box
        // (a row whose slack exceeds (|g_i|_1 + max |g|_1) delta never binds)
        let (a, b, grad, rho) = (&mut self.a, &mut self.b, &self.grad, &self.rho);
        a.clear();
        b.clear();
        for j in 0..kg {
            for s in [1.0, -1.0] {
                let mut row = [0.0; 7];
                row[j] = s;
                a.extend_from_slice(&row[..k]);
                b.push(delta);
            }
        }
        let gmax = (0..n).map(|i| grad[kg * i..kg * (i + 1)].iter().map(|g| g.abs()).sum::<f64>()).fold(0.0, f64::max);
        for i in 0..n {
            let g = &grad[kg * i..kg * (i + 1)];
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
        let z = lp::minimize(a, b, &self.c)?;
        let predicted = -self.c.iter().zip(&z).map(|(c, z)| c * z).sum::<f64>();
        Some((z, predicted, u, v))
    }
}

/// The decrease of the criterion one SLP step predicts from `ax` within the box `delta`
/// (mm): a first-order optimality gap (0 at a vertex optimum). `None` if the LP fails.
pub(crate) fn predicted_decrease(q: &[f64], crit: Criterion, ax: Axis, taper: Option<Taper>, delta: f64, len: f64) -> Option<f64> {
    let mut lp = StepLp::new(crit, taper.as_ref(), q.len() / 3);
    lp.solve(q, &ax, taper.as_ref(), delta, len).map(|s| s.1)
}

/// [`descend`] for a cylinder (`taper` None) or a cone: the cone's half angle is one more
/// variable when `taper.free` (scaled by `len`, so that it moves the points by mm), and
/// the residuals and their gradients are the cone's (see [`Taper`]). `allowed` sees the
/// axis direction and the half angle. Returns the search and the final half angle.
#[allow(clippy::too_many_arguments)]
pub(crate) fn descend_tapered(
    q: &[f64],
    crit: Criterion,
    start: Axis,
    mut taper: Option<Taper>,
    delta: f64,
    len: f64,
    size: f64,
    allowed: &dyn Fn(&Vector3<f64>, f64) -> bool,
) -> (Local, f64) {
    let mut lp = StepLp::new(crit, taper.as_ref(), q.len() / 3);
    let kg = lp.kg;
    // below these the model decrease and the box are rounding noise
    let ftol = 1e-15 * size;
    let delta_min = 1e-14 * size;
    let delta_max = 0.1 * size;
    let mut ax = start;
    let psi0 = taper.map_or(0.0, |t| t.psi);
    let mut f = tapered_value(q, crit, &ax, taper.as_ref());
    let mut delta = delta.clamp(delta_min, delta_max);
    let mut steps = 0;
    while steps < MAX_STEPS && f.is_finite() {
        steps += 1;
        let Some((z, predicted, u, v)) = lp.solve(q, &ax, taper.as_ref(), delta, len) else { break };
        if predicted.is_nan() || predicted <= ftol {
            break;
        }
        let dir = ax.dir + (u * z[2] + v * z[3]) / len;
        let trial = Axis::new(dir, ax.point + u * z[0] + v * z[1]);
        let trial_taper = taper.map(|t| if t.free { Taper { psi: t.psi + z[4] / len, ..t } } else { t });
        let psi = trial_taper.map_or(0.0, |t| t.psi);
        let f_trial = if allowed(&trial.dir, psi) { tapered_value(q, crit, &trial, trial_taper.as_ref()) } else { f64::INFINITY };
        let ratio = (f - f_trial) / predicted;
        if ratio > 1e-4 {
            ax = trial;
            taper = trial_taper;
            f = f_trial;
        }
        let step = z[..kg].iter().fold(0.0f64, |m, z| m.max(z.abs()));
        delta = lp::next_radius(delta, step, ratio, delta_max);
        if delta < delta_min {
            break;
        }
    }
    (Local { axis: ax, steps }, taper.map_or(psi0, |t| t.psi))
}
