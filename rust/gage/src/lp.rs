//! Assembly of the linearised Eq. 5.11 about a current transform, and its solve
//! with clarabel.
//!
//! Variables x = [delta (the free motions, in parameter order), q_1..q_n,
//! s_1..s_n, u]. Rows, all of the form A x <= b (clarabel's nonnegative cone):
//!
//! * per point r_ij, the two rows of Eq. 5.12 linearised about the current
//!   parameters p0: `J delta - q_i <= -e0` and `-J delta - s_i <= e0`, where
//!   e0 = n_i . (R(p0) r + t0) + d_i is the exact distance (the h_ij of Eq. 5.12
//!   at p0) and J its gradient in the free motions;
//! * per gage, `-s_i <= 0` and `s_i - u <= 0` (Eq. 5.11: 0 <= s_i <= u);
//! * per free motion, the bounds of Omega on p0 + delta (upper row, then lower row);
//! * optionally `s_k <= 0` (Eq. 5.10, the gage k is not released).
//!
//! The objective is sum f_i q_i + sum g_i s_i + u.

use crate::problem::{GageSet, Motion};
use crate::transform::{pull_back, rotation_and_derivatives};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};
use gagekit_core::{GkError, Result};

/// The linearised LP in CSC form (A x <= b, minimise c . x).
#[derive(Debug, Clone)]
pub struct LpData {
    pub nvars: usize,
    pub nrows: usize,
    pub colptr: Vec<usize>,
    pub rowval: Vec<usize>,
    pub nzval: Vec<f64>,
    pub b: Vec<f64>,
    pub c: Vec<f64>,
    /// indices (in parameter order 0..6) of the free motions, one per delta column
    pub free: Vec<usize>,
    /// number of gages
    pub ngages: usize,
    /// first bound row; bound rows come in (upper, lower) pairs per free motion
    pub bound_row: usize,
}

impl LpData {
    pub fn q_col(&self, i: usize) -> usize {
        self.free.len() + i
    }
    pub fn s_col(&self, i: usize) -> usize {
        self.free.len() + self.ngages + i
    }
    pub fn u_col(&self) -> usize {
        self.free.len() + 2 * self.ngages
    }
}

/// Exact distances e0 and their gradients J (in the free motions) at `p0`, per point.
#[derive(Debug, Clone)]
pub struct Linearisation {
    pub e0: Vec<f64>,
    /// row-major, `free.len()` values per point
    pub jac: Vec<f64>,
    pub free: Vec<usize>,
}

impl Linearisation {
    /// Linearise the distances of every gage point about the exact transform at `p0`.
    pub fn new(set: &GageSet, motion: &Motion, p0: &[f64; 6]) -> Self {
        let k = set.len();
        let free = motion.free_indices();
        let nf = free.len();
        let npts = set.offsets[k];
        let (r0, dr) = rotation_and_derivatives(p0);
        let mut e0 = vec![0.0; npts];
        let mut jac = vec![0.0; npts * nf];
        for i in 0..k {
            let n = set.normal(i);
            let m0 = pull_back(&r0, &n);
            let dm: Vec<[f64; 3]> = (0..3).map(|a| pull_back(&dr[a], &n)).collect();
            let c0 = n[0] * p0[3] + n[1] * p0[4] + n[2] * p0[5] + set.offset(i);
            for j in set.offsets[i]..set.offsets[i + 1] {
                let x = &set.points[3 * j..3 * j + 3];
                e0[j] = m0[0] * x[0] + m0[1] * x[1] + m0[2] * x[2] + c0;
                for (col, &m) in free.iter().enumerate() {
                    jac[j * nf + col] =
                        if m < 3 { dm[m][0] * x[0] + dm[m][1] * x[1] + dm[m][2] * x[2] } else { n[m - 3] };
                }
            }
        }
        Self { e0, jac, free }
    }

    /// Linearised distance of point `j` after the step `delta`.
    pub fn distance(&self, j: usize, delta: &[f64]) -> f64 {
        let nf = self.free.len();
        self.e0[j] + self.jac[j * nf..(j + 1) * nf].iter().zip(delta).map(|(a, b)| a * b).sum::<f64>()
    }
}

/// Assemble the LP of Eq. 5.11 linearised about `p0` (exact transform), all points.
pub fn assemble(set: &GageSet, motion: &Motion, p0: &[f64; 6], forced_zero: Option<usize>) -> LpData {
    let lin = Linearisation::new(set, motion, p0);
    let sel: Vec<Vec<usize>> = (0..set.len()).map(|i| (set.offsets[i]..set.offsets[i + 1]).collect()).collect();
    build(motion, p0, &lin, &sel, set.f, set.g, forced_zero)
}

/// The LP on the points `sel[i]` of each gage i (row pairs in that order).
fn build(
    motion: &Motion,
    p0: &[f64; 6],
    lin: &Linearisation,
    sel: &[Vec<usize>],
    f: &[f64],
    g: &[f64],
    forced_zero: Option<usize>,
) -> LpData {
    let k = sel.len();
    let free = lin.free.clone();
    let nf = free.len();
    let npts: usize = sel.iter().map(|v| v.len()).sum();
    let nvars = nf + 2 * k + 1;
    let bound_row = 2 * npts + 2 * k;
    let nrows = bound_row + 2 * nf + usize::from(forced_zero.is_some());
    // local point t of gage i: first[i] <= t < first[i + 1]
    let mut first = vec![0usize; k + 1];
    for i in 0..k {
        first[i + 1] = first[i] + sel[i].len();
    }

    let nnz = 2 * npts * nf + 2 * nf + 2 * npts + 3 * k + 1;
    let mut colptr = Vec::with_capacity(nvars + 1);
    let mut rowval = Vec::with_capacity(nnz);
    let mut nzval = Vec::with_capacity(nnz);
    colptr.push(0);
    for col in 0..nf {
        for (t, &j) in sel.iter().flatten().enumerate() {
            let v = lin.jac[j * nf + col];
            rowval.push(2 * t);
            nzval.push(v);
            rowval.push(2 * t + 1);
            nzval.push(-v);
        }
        rowval.push(bound_row + 2 * col);
        nzval.push(1.0);
        rowval.push(bound_row + 2 * col + 1);
        nzval.push(-1.0);
        colptr.push(rowval.len());
    }
    for i in 0..k {
        for t in first[i]..first[i + 1] {
            rowval.push(2 * t);
            nzval.push(-1.0);
        }
        colptr.push(rowval.len());
    }
    for i in 0..k {
        for t in first[i]..first[i + 1] {
            rowval.push(2 * t + 1);
            nzval.push(-1.0);
        }
        rowval.push(2 * npts + 2 * i);
        nzval.push(-1.0);
        rowval.push(2 * npts + 2 * i + 1);
        nzval.push(1.0);
        if forced_zero == Some(i) {
            rowval.push(nrows - 1);
            nzval.push(1.0);
        }
        colptr.push(rowval.len());
    }
    for i in 0..k {
        rowval.push(2 * npts + 2 * i + 1);
        nzval.push(-1.0);
    }
    colptr.push(rowval.len());

    let mut b = vec![0.0; nrows];
    for (t, &j) in sel.iter().flatten().enumerate() {
        b[2 * t] = -lin.e0[j];
        b[2 * t + 1] = lin.e0[j];
    }
    for (col, &m) in free.iter().enumerate() {
        let bound = motion.bound(m);
        b[bound_row + 2 * col] = bound - p0[m];
        b[bound_row + 2 * col + 1] = bound + p0[m];
    }
    let mut c = vec![0.0; nvars];
    c[nf..nf + k].copy_from_slice(f);
    c[nf + k..nf + 2 * k].copy_from_slice(g);
    c[nvars - 1] = 1.0;
    LpData { nvars, nrows, colptr, rowval, nzval, b, c, free, ngages: k, bound_row }
}

/// Problems with more points than this are solved by constraint generation.
pub const DIRECT_LIMIT: usize = 4000;

/// Solve the LP of Eq. 5.11 linearised about `p0`.
///
/// Small problems are assembled whole. Larger ones (unfiltered point-sets) are
/// solved by constraint generation: start from the extreme points of every gage
/// in e0 and in each gradient direction, solve, add the points whose rows are
/// violated, until none is. The final LP is a relaxation of the whole one whose
/// solution is feasible for it, hence optimal for it. With `polish`, every
/// solution is moved to the exact point of its optimal face (see [`polish`]).
/// Returns the LP actually solved (a subset of the rows) and its solution.
pub fn solve_linearised(
    set: &GageSet,
    motion: &Motion,
    p0: &[f64; 6],
    forced_zero: Option<usize>,
    radius: f64,
    polish_face: bool,
) -> Result<(LpData, LpSolution)> {
    let lin = Linearisation::new(set, motion, p0);
    let k = set.len();
    let nf = lin.free.len();
    let npts = set.offsets[k];
    let finish = |lp: &LpData, mut sol: LpSolution| -> LpSolution {
        if polish_face {
            if let Some(x) = polish(lp, &sol, p0, radius) {
                sol.objective = lp.c.iter().zip(&x).map(|(c, v)| c * v).sum();
                sol.x = x;
            } else {
                sol.status = "unpolished";
            }
        }
        sol
    };
    let all: Vec<Vec<usize>> = (0..k).map(|i| (set.offsets[i]..set.offsets[i + 1]).collect()).collect();
    if npts <= DIRECT_LIMIT {
        let lp = build(motion, p0, &lin, &all, set.f, set.g, forced_zero);
        let sol = solve_lp(&lp)?;
        let sol = finish(&lp, sol);
        return Ok((lp, sol));
    }
    // initial working set: extremes of e0 and of each gradient column, per gage
    let mut sel: Vec<Vec<usize>> = all
        .iter()
        .map(|pts| {
            let mut w = Vec::new();
            let mut extremes = |key: &dyn Fn(usize) -> f64| {
                let lo = pts.iter().copied().min_by(|&a, &b| key(a).total_cmp(&key(b)));
                let hi = pts.iter().copied().max_by(|&a, &b| key(a).total_cmp(&key(b)));
                w.extend(lo);
                w.extend(hi);
            };
            extremes(&|j| lin.e0[j]);
            for col in 0..nf {
                extremes(&|j| lin.jac[j * nf + col]);
            }
            w.sort_unstable();
            w.dedup();
            w
        })
        .collect();
    let scale = lin.e0.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for _round in 0..200 {
        gagekit_core::interrupt::check()?;
        let lp = build(motion, p0, &lin, &sel, set.f, set.g, forced_zero);
        let sol = solve_lp(&lp)?;
        let sol = finish(&lp, sol);
        let delta = &sol.x[..nf];
        let mut added = false;
        for i in 0..k {
            let (q, s) = (sol.x[nf + i], sol.x[nf + k + i]);
            let tol = 1e-9 * scale;
            let mut viol: Vec<(f64, usize)> = all[i]
                .iter()
                .filter_map(|&j| {
                    let e = lin.distance(j, delta);
                    let v = (e - q).max(-e - s);
                    (v > tol).then_some((v, j))
                })
                .collect();
            if viol.is_empty() {
                continue;
            }
            viol.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
            let mut grown = sel[i].clone();
            grown.extend(viol.iter().take(32).map(|v| v.1));
            grown.sort_unstable();
            grown.dedup();
            if grown.len() > sel[i].len() {
                sel[i] = grown;
                added = true;
            }
        }
        if !added {
            return Ok((lp, sol));
        }
    }
    Err(GkError::numerical("constraint generation for the gage LP did not settle after 200 rounds"))
}

/// A solved LP: primal x, duals z (one per row), objective.
#[derive(Debug, Clone)]
pub struct LpSolution {
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    pub objective: f64,
    /// "solved" or "almost solved" (clarabel's reduced-accuracy success)
    pub status: &'static str,
    pub iterations: u32,
}

/// The single LP of Eq. 5.11 linearised about `p0`, validated and solved once (no
/// re-linearisation, no polish): by constraint generation above the direct size limit when
/// `generate` is true, else assembled whole. For comparisons with other LP solvers.
pub fn solve_single(set: &GageSet, motion: &Motion, p0: &[f64; 6], generate: bool) -> Result<(LpData, LpSolution)> {
    set.validate(motion)?;
    if generate {
        solve_linearised(set, motion, p0, None, set.radius(), false)
    } else {
        let lp = assemble(set, motion, p0, None);
        let sol = solve_lp(&lp)?;
        Ok((lp, sol))
    }
}

/// The LP of Eq. 5.11 linearised about `p0`, validated and assembled whole.
pub fn assemble_checked(set: &GageSet, motion: &Motion, p0: &[f64; 6]) -> Result<LpData> {
    set.validate(motion)?;
    Ok(assemble(set, motion, p0, None))
}

/// Solve an assembled LP with clarabel; every non-success status is an error.
pub fn solve_lp(lp: &LpData) -> Result<LpSolution> {
    let p = CscMatrix::<f64>::zeros((lp.nvars, lp.nvars));
    let a = CscMatrix::new(lp.nrows, lp.nvars, lp.colptr.clone(), lp.rowval.clone(), lp.nzval.clone());
    let cones: [SupportedConeT<f64>; 1] = [NonnegativeConeT(lp.nrows)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(200)
        .tol_gap_abs(1e-11)
        .tol_gap_rel(1e-11)
        .tol_feas(1e-11)
        .tol_ktratio(1e-9)
        .build()
        .map_err(|e| GkError::numerical(format!("LP solver settings rejected: {e:?}")))?;
    let mut solver = DefaultSolver::new(&p, &lp.c, &a, &lp.b, &cones, settings)
        .map_err(|e| GkError::numerical(format!("LP solver could not be set up: {e}")))?;
    solver.solve();
    let sol = &solver.solution;
    let status = match sol.status {
        SolverStatus::Solved => "solved",
        SolverStatus::AlmostSolved => "almost solved",
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            return Err(GkError::infeasible(
                "the gage constraints cannot all be met by any motion within the motion bounds (LP primal infeasible)",
            ))
        }
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
            return Err(GkError::numerical(
                "the gage LP was reported unbounded (dual infeasible), which a bounded motion set rules out: the data are numerically ill-posed",
            ))
        }
        other => {
            return Err(GkError::numerical(format!(
                "the gage LP was not solved: clarabel stopped with status {other:?} after {} iterations",
                sol.iterations
            )))
        }
    };
    if sol.x.iter().any(|v| !v.is_finite()) {
        return Err(GkError::numerical("the gage LP returned a non-finite solution"));
    }
    Ok(LpSolution { x: sol.x.clone(), z: sol.z.clone(), objective: sol.obj_val, status, iterations: sol.iterations })
}

/// Minimum-norm solution of the consistent system `rows * y = rhs` by modified
/// Gram-Schmidt on the rows (twice, for stability). Returns the solution and the
/// largest inconsistency met on a dependent row.
fn min_norm_solve(rows: &[Vec<f64>], rhs: &[f64], n: usize) -> (Vec<f64>, f64) {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut coef: Vec<f64> = Vec::new();
    let mut worst: f64 = 0.0;
    for (a, &r) in rows.iter().zip(rhs) {
        let norm0 = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm0 == 0.0 {
            worst = worst.max(r.abs());
            continue;
        }
        let mut v: Vec<f64> = a.iter().map(|x| x / norm0).collect();
        let mut rr = r / norm0;
        for _ in 0..2 {
            for (q, &c) in basis.iter().zip(&coef) {
                let d: f64 = v.iter().zip(q).map(|(x, y)| x * y).sum();
                for (x, y) in v.iter_mut().zip(q) {
                    *x -= d * y;
                }
                rr -= d * c;
            }
        }
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if nv > 1e-9 {
            for x in v.iter_mut() {
                *x /= nv;
            }
            basis.push(v);
            coef.push(rr / nv);
        } else {
            worst = worst.max(rr.abs() * norm0);
        }
    }
    let mut y = vec![0.0; n];
    for (q, &c) in basis.iter().zip(&coef) {
        for (yi, qi) in y.iter_mut().zip(q) {
            *yi += c * qi;
        }
    }
    (y, worst)
}

/// A x for the CSC matrix of `lp`.
fn mat_vec(lp: &LpData, x: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; lp.nrows];
    for (col, &xv) in x.iter().enumerate() {
        if xv == 0.0 {
            continue;
        }
        for k in lp.colptr[col]..lp.colptr[col + 1] {
            out[lp.rowval[k]] += lp.nzval[k] * xv;
        }
    }
    out
}

/// Polish an interior-point solution to an exact point of the optimal face.
///
/// The rows with a clearly positive dual define the optimal face
/// (complementary slackness); on it we take the point nearest to the identity
/// transform, `min |W (p0 + delta)|^2` (W: the lever arm `radius` for angles,
/// 1 for shifts, a tiny weight on q, s, u), adding violated rows to the
/// equalities until the point is feasible. This fixes both the accuracy of the
/// interior point and the choice among equally good transforms, so that the
/// re-linearisation has a well-defined fixed point. Returns `None` when no
/// consistent face is found (the caller keeps the interior-point solution).
pub fn polish(lp: &LpData, sol: &LpSolution, p0: &[f64; 6], radius: f64) -> Option<Vec<f64>> {
    let zmax = sol.z.iter().cloned().fold(0.0, f64::max).max(1.0);
    let ax = mat_vec(lp, &sol.x);
    let bscale = lp.b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    // the optimal face: rows whose dual dominates their slack (strict
    // complementarity); failing that, rows with a clearly positive dual
    let dominant: Vec<usize> =
        (0..lp.nrows).filter(|&i| sol.z[i] > 1e-7 * zmax && sol.z[i] > (lp.b[i] - ax[i])).collect();
    let positive: Vec<usize> = (0..lp.nrows).filter(|&i| sol.z[i] > 1e-5 * zmax).collect();
    polish_from(lp, sol, p0, radius, dominant, bscale).or_else(|| polish_from(lp, sol, p0, radius, positive, bscale))
}

fn polish_from(
    lp: &LpData,
    sol: &LpSolution,
    p0: &[f64; 6],
    radius: f64,
    mut eq: Vec<usize>,
    bscale: f64,
) -> Option<Vec<f64>> {
    let n = lp.nvars;
    let feas_tol = 1e-10 * bscale;
    // weights and reference point: y = D (x - x_ref)
    let mut d = vec![1e-3; n];
    let mut x_ref = vec![0.0; n];
    for (col, &m) in lp.free.iter().enumerate() {
        d[col] = if m < 3 { radius.max(1.0) } else { 1.0 };
        x_ref[col] = -p0[m];
    }
    // rows of A by row index, built on demand
    let row_of = |i: usize| -> Vec<f64> {
        let mut r = vec![0.0; n];
        for (col, rc) in r.iter_mut().enumerate() {
            let (lo, hi) = (lp.colptr[col], lp.colptr[col + 1]);
            if let Ok(k) = lp.rowval[lo..hi].binary_search(&i) {
                *rc = lp.nzval[lo + k];
            }
        }
        r
    };
    // a dense row cache (the equality set stays small)
    let mut cache: std::collections::HashMap<usize, Vec<f64>> = std::collections::HashMap::new();
    for _round in 0..64 {
        let mut rows = Vec::with_capacity(eq.len());
        let mut rhs = Vec::with_capacity(eq.len());
        for &i in &eq {
            let a = cache.entry(i).or_insert_with(|| row_of(i)).clone();
            let ax_ref: f64 = a.iter().zip(&x_ref).map(|(u, v)| u * v).sum();
            rhs.push(lp.b[i] - ax_ref);
            rows.push(a.iter().zip(&d).map(|(u, w)| u / w).collect::<Vec<f64>>());
        }
        let (y, inconsistency) = min_norm_solve(&rows, &rhs, n);
        if inconsistency > feas_tol {
            return None;
        }
        let x: Vec<f64> = y.iter().zip(&d).zip(&x_ref).map(|((y, w), r)| y / w + r).collect();
        let ax = mat_vec(lp, &x);
        let mut in_eq = vec![false; lp.nrows];
        for &i in &eq {
            in_eq[i] = true;
        }
        let worst = (0..lp.nrows)
            .filter(|&i| !in_eq[i])
            .map(|i| (i, ax[i] - lp.b[i]))
            .fold((usize::MAX, feas_tol), |m, v| if v.1 > m.1 { v } else { m });
        if worst.0 == usize::MAX {
            let obj: f64 = lp.c.iter().zip(&x).map(|(c, v)| c * v).sum();
            let ok = obj <= sol.objective + 1e-9 * (1.0 + sol.objective.abs());
            return if ok { Some(x) } else { None };
        }
        eq.push(worst.0);
    }
    None
}
