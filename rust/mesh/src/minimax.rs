//! The minimax (Chebyshev) alignment: the rigid motion of the scan that minimises the
//! largest |signed distance| to the surface -- the narrowest zone symmetric about the CAD
//! surface holding every point (ISO 1101 profile of a surface, zone floating; the
//! virtual gage's LP of Eq. 5.11 with the gages replaced by the surface).
//!
//! Sequential linear programming: about the current pose each distance is linearised,
//! d_i + J_i . delta ([`crate::align::Frame::jacobian`]), and the LP
//!
//!   minimise u  subject to  -u <= d_i + J_i . delta <= u  (i in W),  |delta_k| <= radius
//!
//! is solved with clarabel (through `gagekit_gage::solve_lp`). The working set W starts
//! with the 512 largest |d_i| and grows by the points the step leaves above the LP's u
//! (constraint generation: every point is checked after every step, exactly). A step is
//! kept when it lowers the exact largest |d|, otherwise the trust radius shrinks.
//!
//! Certificate: at the final pose the LP over W within the last trust radius has the
//! optimum `lp_optimum`; δ = 0 is optimal for it exactly when `lp_optimum` equals the
//! exact largest |d| over all points (`max_abs`): no motion lowers the largest deviation
//! to first order (the Chebyshev optimality condition). Both are reported.

use crate::align::{sample, Eval, Frame};
use crate::mesh::TriMesh;
use crate::rigid::{rotation_and_derivatives, Pose};
use gagekit_core::{interrupt, GkError, Result};
use gagekit_gage::{solve_lp, LpData};

/// The result of [`minimax`].
#[derive(Debug, Clone)]
pub struct Minimax {
    pub pose: Pose,
    /// exact largest |distance| over every point within the bound, at `pose`
    pub max_abs: f64,
    /// optimum of the certificate LP at `pose`
    pub lp_optimum: f64,
    /// RMS of the distances at `pose`
    pub rms: f64,
    pub iterations: usize,
    /// size of the final working set
    pub active: usize,
    pub n_used: usize,
}

const START_SET: usize = 512;
const ADD: usize = 64;

fn max_abs(ev: &[Option<Eval>]) -> (f64, usize, f64) {
    let (mut m, mut k, mut s) = (0.0f64, 0usize, 0.0);
    for e in ev.iter().flatten() {
        m = m.max(e.d.abs());
        k += 1;
        s += e.d * e.d;
    }
    (m, k, if k > 0 { (s / k as f64).sqrt() } else { 0.0 })
}

/// Indices (positions in `ev`) of the `m` largest |d|, ties by position.
fn largest(ev: &[Option<Eval>], m: usize, above: f64) -> Vec<usize> {
    let mut v: Vec<(f64, usize)> =
        ev.iter().enumerate().filter_map(|(i, e)| e.as_ref().and_then(|e| (e.d.abs() > above).then_some((e.d.abs(), i)))).collect();
    if v.len() > m {
        v.select_nth_unstable_by(m, |a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        v.truncate(m);
    }
    v.into_iter().map(|x| x.1).collect()
}

/// The LP about `p` over the points `w` (positions in `ev`); returns (step, u).
fn solve_step(frame: &Frame, ev: &[Option<Eval>], w: &[usize], p: &[f64; 6], radius: f64, scale_rot: f64) -> Result<([f64; 6], f64)> {
    let free = &frame.free;
    let nf = free.len();
    let (_, dr) = rotation_and_derivatives(p);
    let m = w.len();
    let rows: Vec<(f64, [f64; 6])> = w.iter().map(|&i| {
        let e = ev[i].as_ref().expect("working-set points have a distance");
        (e.d, Frame::jacobian(e, &dr))
    }).collect();
    let col_scale = |k: usize| if k >= 3 { 1.0 / scale_rot } else { 1.0 };
    let nvars = nf + 1;
    let nrows = 2 * m + 2 * nf;
    let mut colptr = vec![0usize];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for (c, &k) in free.iter().enumerate() {
        for (j, (_, jac)) in rows.iter().enumerate() {
            let v = jac[k] * col_scale(k);
            rowval.push(2 * j);
            nzval.push(v);
            rowval.push(2 * j + 1);
            nzval.push(-v);
        }
        rowval.push(2 * m + 2 * c);
        nzval.push(1.0);
        rowval.push(2 * m + 2 * c + 1);
        nzval.push(-1.0);
        colptr.push(rowval.len());
    }
    for j in 0..m {
        rowval.push(2 * j);
        nzval.push(-1.0);
        rowval.push(2 * j + 1);
        nzval.push(-1.0);
    }
    colptr.push(rowval.len());
    let mut b = vec![radius; nrows];
    for (j, (d, _)) in rows.iter().enumerate() {
        b[2 * j] = -d;
        b[2 * j + 1] = *d;
    }
    let mut c = vec![0.0; nvars];
    c[nf] = 1.0;
    let lp = LpData { nvars, nrows, colptr, rowval, nzval, b, c, free: free.clone(), ngages: 0, bound_row: 2 * m };
    let sol = solve_lp(&lp)?;
    let mut step = [0.0; 6];
    for (c, &k) in free.iter().enumerate() {
        step[k] = sol.x[c] * col_scale(k);
    }
    Ok((step, sol.x[nf]))
}

/// The minimax alignment from `initial` (e.g. the best fit); see the module docs. With
/// `offset` the zone is centred on the surface offset outwards by it (ISO 1101 UZ): the
/// largest |d - offset| is minimised.
pub fn minimax(
    mesh: &TriMesh,
    points: &[f64],
    initial: Pose,
    free: [bool; 6],
    max_distance: Option<f64>,
    offset: f64,
) -> Result<Minimax> {
    if !offset.is_finite() {
        return Err(GkError::invalid(format!("minimax: offset must be finite, got {offset}")));
    }
    let mut frame = Frame::new(mesh, points, initial, max_distance, free)?;
    frame.offset = offset;
    let n = frame.n();
    let idx = sample(n, usize::MAX);
    let mut hints = vec![crate::distance::Cache::EMPTY; n];
    let mut p = [0.0; 6];
    let mut ev = frame.eval(&idx, &p, &mut hints)?;
    let (mut t, n_used, mut rms) = max_abs(&ev);
    if n_used == 0 {
        return Err(GkError::degenerate("minimax: no point within reach of the model; check the units and --max-distance"));
    }
    // the scan's size turns rotations into lengths (LP scaling, trust radius)
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for e in ev.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(e.x[k]);
            hi[k] = hi[k].max(e.x[k]);
        }
    }
    let size = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt().max(1e-9);
    let mut w = largest(&ev, START_SET, -1.0);
    w.sort_unstable();
    let mut radius = t.max(1e-9);
    let mut iterations = 0;
    let mut lp_opt = t;
    if frame.free.is_empty() {
        return Ok(Minimax { pose: frame.pose(&p), max_abs: t, lp_optimum: t, rms, iterations: 0, active: w.len(), n_used });
    }
    for _round in 0..400 {
        interrupt::check()?;
        let (step, u) = solve_step(&frame, &ev, &w, &p, radius, size)?;
        lp_opt = u;
        let mut q = p;
        for k in 0..6 {
            q[k] += step[k];
        }
        let mut hq = hints.clone();
        let evq = frame.eval(&idx, &q, &mut hq)?;
        let (tq, nq, rq) = max_abs(&evq);
        // points the step leaves above the LP's zone join the working set
        let tol = 1e-12 * (1.0 + t);
        let viol = largest(&evq, ADD, u + tol);
        let before = w.len();
        w.extend(viol);
        w.sort_unstable();
        w.dedup();
        let grew = w.len() > before;
        iterations += 1;
        let step_len = step[..3].iter().map(|v| v * v).sum::<f64>().sqrt() + size * step[3..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if tq < t && nq == n_used {
            p = q;
            ev = evq;
            hints = hq;
            t = tq;
            rms = rq;
            radius = (2.0 * step_len).max(1e-9 * (1.0 + t)).min(t.max(1e-9));
        } else if !grew {
            radius *= 0.25;
        }
        if step_len <= 1e-12 * (1.0 + size) || radius <= 1e-13 * (1.0 + size) {
            break;
        }
        if (t - u).abs() <= 1e-12 * (1.0 + t) && !grew {
            break;
        }
    }
    // certificate: the LP at the final pose over the working set and the points near the top
    let top = largest(&ev, ADD, -1.0);
    w.extend(top);
    w.sort_unstable();
    w.dedup();
    if let Ok((_, u)) = solve_step(&frame, &ev, &w, &p, radius.max(1e-6 * (1.0 + t)), size) {
        lp_opt = u;
    }
    Ok(Minimax { pose: frame.pose(&p), max_abs: t, lp_optimum: lp_opt, rms, iterations, active: w.len(), n_used })
}
