//! Best-fit alignment of a scan to a mesh: the rigid motion minimising the robust sum of
//! squared signed distances (point-to-plane ICP, Chen and Medioni 1992, with Tukey
//! biweights, Zhang 1994), from any initial pose.
//!
//! Start: the given pose and, unless degrees of freedom are locked, the 24 rotations that
//! put the scan's principal axes on the surface's (area-weighted, exact per triangle) in
//! every order and sign (the cube group), centroid on centroid. Each start is screened on
//! 256 points (the starts in parallel): 5 iterations, then the 8 best by their median
//! |distance| 5 more (a start in the right basin is near after 5, a wrong one stays far);
//! the 3 best are iterated (30) on 2000; the smallest median |distance| wins (ties: the first);
//! with a bound, the search runs under it and without it ([`best_fit`]). Then coarse to fine:
//! evenly spaced subsamples of 30 000, 100 000 and 300 000 points, each iterated until its
//! step is below 1e-7 rad and 1e-5 mm (a subsample's optimum differs from the whole
//! cloud's by more), and last every point, to the fixed point of the whole cloud's
//! iteration: until a step is below 1e-12 rad and 1e-10 mm, the level of rounding
//! ([`FIXED`]; the steps accelerated by Anderson mixing). The answer is thus a property
//! of the cloud, not of the way there: the subsamples, the point order, a rigid motion of
//! the scan, or clutter beyond the bound (which changes the subsamples) move it by about
//! 1e-10 mm (tested), where a stop at a 1e-6 mm step left up to 1e-6 mm. Each point keeps its nearest triangle and that triangle's margin (no
//! other triangle was nearer than it) from iteration to iteration and from stage to
//! stage: while the point has moved less than the margin allows, the triangle is certified
//! the nearest without a search ([`crate::distance::Cache`]; the same answer, to the bit,
//! as the search), so the late iterations, which move every point by microns, cost one
//! point-triangle distance per point.
//!
//! Iteration: linearise d_i(p) = d_i + J_i . delta over the free parameters (translations
//! and Rz Ry Rx angles, [`crate::rigid`]), J_i = [g_i, g_i . (dR/da x_i)] with g_i the
//! gradient of the distance (the face normal inside a face); weights w_i = (1 - (d_i /
//! c)^2)^2 for |d_i| < c = 4.685 sigma, sigma = 1.4826 median |d_i| (outliers -- clutter,
//! fixtures, the other side of a thin wall -- get no weight); solve the weighted normal
//! equations by SVD (minimum-norm: motions the surface does not constrain, e.g. sliding
//! along a plane, stay put).

use crate::distance::Cache;
use crate::mesh::TriMesh;
use crate::rigid::{apply, rotation_and_derivatives, Pose, M3};
use gagekit_core::{check_coordinates, interrupt, GkError, Result};
use gagekit_gdt::vec3::{dot, V3};
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector6};
use rayon::prelude::*;

/// Points per chunk of the parallel passes (fixed: results never depend on threads).
const CHUNK: usize = 256;
/// Sample sizes of the start search and of the refinement stages.
const SCREEN_SAMPLE: usize = 256;
const START_SAMPLE: usize = 2000;
/// The screening's rounds on [`SCREEN_SAMPLE`] points: (steps, starts kept after it):
/// every start a few steps, the best few more steps.
const SCREEN_ROUNDS: [(usize, usize); 2] = [(5, 8), (5, KEEP_STARTS)];
/// Starts iterated further after the screening.
const KEEP_STARTS: usize = 3;
const STAGES: [usize; 4] = [30_000, 100_000, 300_000, usize::MAX];
/// Most iterations on every point.
const MAX_FINAL: usize = 30;

/// The points, the mesh, the initial pose and the free parameters of a fit.
pub struct Frame<'a> {
    pub mesh: &'a TriMesh,
    pub points: &'a [f64],
    pub base: Pose,
    pub bound2: f64,
    pub free: Vec<usize>,
    /// subtracted from every distance: the zone's centre surface is the CAD surface
    /// offset by this (ISO 1101 UZ); 0 for the CAD surface itself
    pub offset: f64,
}

/// One point's distance after the motion, its gradient and the point before the step.
#[derive(Debug, Clone, Copy)]
pub struct Eval {
    pub index: u32,
    pub d: f64,
    pub g: V3,
    pub x: V3,
}

impl<'a> Frame<'a> {
    pub fn new(mesh: &'a TriMesh, points: &'a [f64], base: Pose, max_distance: Option<f64>, free: [bool; 6]) -> Result<Self> {
        check_coordinates(points, 3, "points")?;
        if points.is_empty() {
            return Err(GkError::invalid("points: no points to align"));
        }
        let bound2 = match max_distance {
            Some(m) if !(m >= 0.0) => return Err(GkError::invalid(format!("max_distance must be zero or positive, got {m}"))),
            Some(m) => m * m,
            None => f64::INFINITY,
        };
        let free: Vec<usize> = (0..6).filter(|&k| free[k]).collect();
        Ok(Self { mesh, points, base, bound2, free, offset: 0.0 })
    }

    pub fn n(&self) -> usize {
        self.points.len() / 3
    }

    #[inline]
    pub fn x(&self, i: usize) -> V3 {
        self.base.apply([self.points[3 * i], self.points[3 * i + 1], self.points[3 * i + 2]])
    }

    /// Distances of the points `idx` moved by the parameters `p` (after `base`), each query
    /// answered from its cache in `hints` (updated; [`TriMesh::hit_cached`]) or started
    /// from the chunk's previous point's; points beyond the bound are left out.
    pub fn eval(&self, idx: &[u32], p: &[f64; 6], hints: &mut [Cache]) -> Result<Vec<Option<Eval>>> {
        let mut out = empty_evals(idx.len());
        let mut ad = vec![0.0; idx.len()];
        self.eval_into(idx, p, hints, &mut out, &mut ad)?;
        Ok(out)
    }

    /// [`Frame::eval`] into `out` (one entry per point of `idx`, each overwritten): the
    /// iterations reuse one buffer instead of allocating and clearing one per pass. In
    /// the same pass, `ad` gets each point's |d| (+inf beyond the bound); returns the
    /// number of points within the bound (one parallel pass where there were three).
    pub fn eval_into(&self, idx: &[u32], p: &[f64; 6], hints: &mut [Cache], out: &mut [Option<Eval>], ad: &mut [f64]) -> Result<usize> {
        let pose = Pose::from_params(p);
        let signed = self.mesh.signed();
        assert_eq!(out.len(), idx.len());
        assert_eq!(ad.len(), idx.len());
        out.par_chunks_mut(CHUNK).zip(hints.par_chunks_mut(CHUNK)).zip(ad.par_chunks_mut(CHUNK)).enumerate().map(|(c, ((o, h), a))| -> Result<usize> {
            if c % 64 == 0 {
                interrupt::check()?;
            }
            let mut within = 0;
            let mut prev = Cache::EMPTY;
            for k in 0..o.len() {
                let i = idx[c * CHUNK + k];
                let x = self.x(i as usize);
                let q = pose.apply(x);
                // a point without a triangle yet starts from the chunk's previous point's
                // (its triangle, and its margin less the distance between them)
                let mut cache = h[k];
                if cache.slot == u32::MAX {
                    cache = prev;
                }
                let hit = self.mesh.hit_cached(q, self.bound2, &mut cache, signed);
                match hit {
                    Some(hit) => {
                        h[k] = cache;
                        prev = cache;
                        let d = hit.distance - self.offset;
                        o[k] = Some(Eval { index: i, d, g: hit.gradient, x });
                        a[k] = d.abs();
                        within += 1;
                    }
                    None => {
                        o[k] = None;
                        a[k] = f64::INFINITY;
                    }
                }
            }
            Ok(within)
        }).try_reduce(|| 0, |a, b| Ok(a + b))
    }

    /// The same points and bound from another initial pose (the points already checked).
    pub fn from_base(&self, base: Pose) -> Frame<'a> {
        Frame { mesh: self.mesh, points: self.points, base, bound2: self.bound2, free: self.free.clone(), offset: self.offset }
    }

    /// The row of the Jacobian of a point's distance over the six parameters at `p`.
    #[inline]
    pub fn jacobian(e: &Eval, dr: &[M3; 3]) -> [f64; 6] {
        [e.g[0], e.g[1], e.g[2], dot(e.g, apply(&dr[0], e.x)), dot(e.g, apply(&dr[1], e.x)), dot(e.g, apply(&dr[2], e.x))]
    }

    /// The pose of parameters `p`, after `base`.
    pub fn pose(&self, p: &[f64; 6]) -> Pose {
        Pose::from_params(p).after(&self.base)
    }
}

/// The result of [`best_fit`].
#[derive(Debug, Clone)]
pub struct BestFit {
    pub pose: Pose,
    pub iterations: usize,
    /// RMS of the distances within the bound before (on an evenly spaced sample of 2000
    /// points) and after (every point)
    pub rms_before: f64,
    pub rms_after: f64,
    pub n_used: usize,
    /// which start won (0: the given pose; 1-4: principal axes and flips)
    pub start: usize,
}

/// `n` empty evaluations, filled in parallel (no serial pass over a large buffer).
pub fn empty_evals(n: usize) -> Vec<Option<Eval>> {
    (0..n).into_par_iter().map(|_| None).collect()
}

/// Evenly spaced indices: `m` of `0..n` (all when m >= n).
pub fn sample(n: usize, m: usize) -> Vec<u32> {
    if m >= n {
        return (0..n as u32).into_par_iter().collect();
    }
    (0..m).into_par_iter().map(|k| ((k as u128 * n as u128) / m as u128) as u32).collect()
}

/// When to stop iterating: the last step below `rot` (rad) and `tr` (mm).
#[derive(Debug, Clone, Copy)]
pub struct Tol {
    pub rot: f64,
    pub tr: f64,
    /// to the fixed point: stop only on an evaluated step below the tolerance (an
    /// extrapolated step only shortens the way, [`FIXED`]); otherwise also when the
    /// predicted rest of the way is below it (the extrapolation then taken as the last step)
    pub exact: bool,
}

/// The start search's stop: steps below 1e-8 rad and 1e-6 mm, or, once two steps show
/// the linear contraction (same direction, ratio r < 1/2), the predicted rest of the way
/// (the step times r / (1 - r)) below them, taken as a last extrapolated step. Also the
/// level below which [`FIXED`] accepts a stop short of the fixed point.
pub const FINE: Tol = Tol { rot: 1e-8, tr: 1e-6, exact: false };
/// Subsample stages: their optimum differs from the whole cloud's by far more than this.
pub const COARSE: Tol = Tol { rot: 1e-7, tr: 1e-5, exact: false };
/// The last stage, on every point: to the fixed point of the whole cloud's iteration, a
/// step below 1e-12 rad and 1e-10 mm (the level of rounding is about 1e-14 mm), so that the
/// answer is a property of the cloud, not of the way there: any start in the basin (the
/// subsample stages, the point order, clutter that takes no part in the fit) ends at the
/// same pose to about 1e-10 mm. The pose kept is the last one evaluated, whose step is
/// below the tolerance (so within about the tolerance of the fixed point), with its
/// median, RMS and count (no pass more over the points). Each next pose is the Anderson mix of the last few
/// ([`anderson`]): the plain iteration contracts by 0.1-0.6 a step (the bracket's slowest
/// mode 0.58: 21 steps from 1e-6 mm), the mix lands in a few. With no fixed point after
/// [`MAX_FINAL`] steps (a cycle: a point at the bound switching in and out, or a motion
/// the surface hardly constrains, such as a patch of a tessellated sphere turning about
/// its centre, or a tessellated surface of revolution turning about its axis from facet to
/// facet) the last pose is kept when the last step is below [`FINE`] or changes the
/// distances by less than its 1e-6 mm or [`IMMATERIAL`] of their robust scale (weighted
/// RMS); otherwise the fit fails with a numerical error. In such a cycle the pose along
/// the free motion is the path's, not the cloud's (a 300 x 100 torus: distances within
/// about 2e-4 mm of each other).
pub const FIXED: Tol = Tol { rot: 1e-12, tr: 1e-10, exact: true };

/// The share of the distances' robust scale (sigma = 1.4826 median |d|) below which the
/// last step of a cycle at [`MAX_FINAL`] moves them immaterially ([`FIXED`]): 1 %.
pub const IMMATERIAL: f64 = 1e-2;

/// What [`iterate`] ends with: iterations done, and (when the last pose was evaluated)
/// the median |d|, the RMS of d and the number of points within the bound there.
#[derive(Debug, Clone, Copy)]
pub struct Iterated {
    pub iterations: usize,
    pub median: f64,
    pub rms: f64,
    pub used: usize,
}

/// Iterate the robust Gauss-Newton steps on the points `idx` from `p` until the step (or,
/// unless `tol.exact`, the predicted rest of the way, see [`FINE`]) is below `tol` or
/// `max_iter` steps are done ([`FIXED`]: what happens then). `last`: evaluate the final
/// pose too (the median, RMS and count of [`Iterated`]; NaN and 0 otherwise).
pub fn iterate(frame: &Frame, idx: &[u32], p: &mut [f64; 6], hints: &mut [Cache], max_iter: usize, tol: Tol, last: bool) -> Result<Iterated> {
    let nf = frame.free.len();
    let mut it = 0;
    // from the |d| buffer (+inf beyond the bound) and the count within
    let summary = |ad: &mut [f64], used: usize, it: usize| -> Iterated {
        let ss: f64 = ad.iter().filter(|d| d.is_finite()).map(|d| d * d).sum();
        let rms = if used > 0 { (ss / used as f64).sqrt() } else { 0.0 };
        let median = if used > 0 { *ad.select_nth_unstable_by(used / 2, |a, b| a.total_cmp(b)).1 } else { 0.0 };
        Iterated { iterations: it, median, rms, used }
    };
    let mut prev: Option<[f64; 6]> = None;
    // [`FIXED`]: the last poses before a step, the steps and their sizes (Anderson)
    let mut hist: Vec<([f64; 6], [f64; 6], f64)> = Vec::new();
    let mut ev = empty_evals(idx.len());
    let mut ad = vec![0.0; idx.len()];
    loop {
        // |d| per point into `ad` (+inf beyond the bound: the median of the `within`
        // finite values is then the (within / 2)-th smallest), counted in the same pass
        let within = frame.eval_into(idx, p, hints, &mut ev, &mut ad)?;
        if within < nf.max(3) {
            return Err(GkError::degenerate(format!(
                "best-fit: only {within} point(s) within reach of the model; check the units, --max-distance and the initial pose"
            )));
        }
        if it >= max_iter || nf == 0 {
            return Ok(summary(&mut ad, within, it));
        }
        let med = *ad.select_nth_unstable_by(within / 2, |a, b| a.total_cmp(b)).1;
        let sigma = (1.4826 * med).max(1e-12);
        let c = 4.685 * sigma;
        let (_, dr) = rotation_and_derivatives(p);
        // normal equations, summed per fixed chunk then in chunk order (deterministic);
        // the upper triangle only (the matrix is symmetric), mirrored after the sum
        // (and the sum of the weights, b's 7th entry)
        let parts: Vec<([f64; 21], [f64; 7])> = ev
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut a = [0.0f64; 21];
                let mut b = [0.0f64; 7];
                for e in chunk.iter().flatten() {
                    let u = e.d / c;
                    if u.abs() >= 1.0 {
                        continue;
                    }
                    let w = (1.0 - u * u) * (1.0 - u * u);
                    let j = Frame::jacobian(e, &dr);
                    b[6] += w;
                    let mut k = 0;
                    for r in 0..6 {
                        let wj = w * j[r];
                        b[r] += wj * e.d;
                        for s in r..6 {
                            a[k] += wj * j[s];
                            k += 1;
                        }
                    }
                }
                (a, b)
            })
            .collect();
        let mut a = Matrix6::<f64>::zeros();
        let mut b = Vector6::<f64>::zeros();
        let mut wsum = 0.0;
        for (pa, pb) in parts {
            wsum += pb[6];
            let mut k = 0;
            for r in 0..6 {
                b[r] += pb[r];
                for s in r..6 {
                    a[(r, s)] += pa[k];
                    k += 1;
                }
            }
        }
        for r in 0..6 {
            for s in 0..r {
                a[(r, s)] = a[(s, r)];
            }
        }
        let af = a.select_rows(&frame.free).select_columns(&frame.free);
        let bf = b.select_rows(&frame.free);
        let svd = af.clone().svd(true, true);
        let smax = svd.singular_values.max();
        if !(smax > 0.0) {
            return Ok(summary(&mut ad, within, it));
        }
        let delta = svd.solve(&(-bf), smax * 1e-12).map_err(|e| GkError::numerical(format!("best-fit: {e}")))?;
        let mut step = [0.0; 6];
        for (k, &m) in frame.free.iter().enumerate() {
            step[m] = delta[k];
        }
        let rot = (step[3] * step[3] + step[4] * step[4] + step[5] * step[5]).sqrt();
        let s = if rot > 0.3 { 0.3 / rot } else { 1.0 };
        let before = *p;
        for k in 0..6 {
            p[k] += s * step[k];
        }
        it += 1;
        let tr = (step[0] * step[0] + step[1] * step[1] + step[2] * step[2]).sqrt();
        // the iteration contracts linearly near its fixed point: when two full steps
        // point the same way and shrink by a ratio r < 1/2, the rest of the way is
        // about the last step times r / (1 - r) (a geometric series)
        let tail = if s == 1.0 { prev.and_then(|q| geometric_tail(&q, &step)) } else { None };
        prev = (s == 1.0).then_some(step);
        if !p.iter().all(|v| v.is_finite()) {
            return Err(GkError::numerical("best-fit: the iteration diverged"));
        }
        // the step's size in units of the tolerance
        let size = (rot / tol.rot).max(tr / tol.tr);
        let converged = if tol.exact {
            if size < 1.0 {
                true
            } else if it >= max_iter {
                // no fixed point: a documented stop when the last step is below FINE or
                // changes the distances (weighted RMS of J . step) by less than FINE's
                // 1e-6 mm or 1 % of their robust scale sigma: a motion the faceted surface
                // hardly constrains, such as a patch of a tessellated sphere turning about
                // its centre or a tessellated surface of revolution about its axis, where
                // the iteration steps from facet to facet; a numerical error otherwise
                let sv = Vector6::from_column_slice(&step);
                let change = ((sv.dot(&(a * sv))).max(0.0) / wsum).sqrt();
                if (rot < FINE.rot && tr < FINE.tr) || change < FINE.tr.max(IMMATERIAL * sigma) {
                    true
                } else {
                    return Err(GkError::numerical(format!(
                        "best-fit: no fixed point after {it} iterations on every point (the last step moves the distances by {change:.3e} mm rms)"
                    )));
                }
            } else {
                if s == 1.0 {
                    // Anderson: the next pose from the last few poses and their steps
                    if hist.last().is_some_and(|&(_, _, q)| size > q) {
                        // the step grew: start the history afresh
                        hist.clear();
                    }
                    hist.push((before, step, size));
                    if hist.len() > ANDERSON + 1 {
                        hist.remove(0);
                    }
                    if let Some(next) = anderson(&hist, &tol) {
                        *p = next;
                    }
                } else {
                    hist.clear();
                }
                false
            }
        } else {
            match tail {
                // the predicted rest of the way is below the tolerance: take it and stop
                Some(f) if f * rot < tol.rot && f * tr < tol.tr => {
                    for k in 0..6 {
                        p[k] += f * step[k];
                    }
                    true
                }
                _ => rot < tol.rot && tr < tol.tr,
            }
        };
        if converged && tol.exact {
            // the pose just evaluated: its step below the tolerance puts it within about
            // the tolerance of the fixed point, and its figures are at hand (no pass more)
            *p = before;
            return Ok(summary(&mut ad, within, it));
        }
        if converged {
            if !last {
                return Ok(Iterated { iterations: it, median: f64::NAN, rms: f64::NAN, used: 0 });
            }
            let used = frame.eval_into(idx, p, hints, &mut ev, &mut ad)?;
            return Ok(summary(&mut ad, used, it));
        }
    }
}

/// The factor r / (1 - r) of the rest of a linearly converging iteration after `step`
/// (the previous step `prev`): Some when the translation and the rotation parts each
/// either vanish or point the same way as before (cosine above 0.9) and shrank by a
/// ratio r below 1/2 (r the larger of the two parts' ratios).
fn geometric_tail(prev: &[f64; 6], step: &[f64; 6]) -> Option<f64> {
    let mut r: f64 = 0.0;
    for part in [0..3, 3..6] {
        let (a, b) = (&prev[part.clone()], &step[part]);
        let (na, nb) = (a.iter().map(|x| x * x).sum::<f64>().sqrt(), b.iter().map(|x| x * x).sum::<f64>().sqrt());
        if nb == 0.0 {
            continue;
        }
        let cos = a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() / (na * nb);
        if !(na > 0.0) || !(cos > 0.9) {
            return None;
        }
        r = r.max(nb / na);
    }
    (r < 0.5).then(|| r / (1.0 - r))
}

/// Steps of the history that [`FIXED`]'s Anderson acceleration combines.
const ANDERSON: usize = 3;

/// Anderson acceleration (type II; Walker and Ni, SIAM J. Numer. Anal. 49(4), 2011) of
/// the fixed-point iteration x -> x + f(x): from the poses x_i and their steps f_i (the
/// last `m + 1`), gamma minimising |f_k - sum gamma_j (f_{j+1} - f_j)| (each parameter in
/// units of the tolerance), the next pose x_k + f_k - sum gamma_j ((x_{j+1} - x_j) +
/// (f_{j+1} - f_j)). For a linear contraction and m at least the number of its slow
/// modes this lands on the fixed point; near it the iteration is nearly linear.
fn anderson(hist: &[([f64; 6], [f64; 6], f64)], tol: &Tol) -> Option<[f64; 6]> {
    let m = hist.len().checked_sub(1).filter(|&m| m > 0)?;
    let w = |k: usize| if k < 3 { 1.0 / tol.tr } else { 1.0 / tol.rot };
    let (xk, fk, _) = hist[m];
    let df = nalgebra::DMatrix::from_fn(6, m, |k, j| w(k) * (hist[j + 1].1[k] - hist[j].1[k]));
    let rhs = nalgebra::DVector::from_fn(6, |k, _| w(k) * fk[k]);
    let svd = df.svd(true, true);
    let smax = svd.singular_values.max();
    if !(smax > 0.0) {
        return None;
    }
    let gamma = svd.solve(&rhs, smax * 1e-10).ok()?;
    let next: [f64; 6] = std::array::from_fn(|k| {
        let c: f64 = (0..m).map(|j| gamma[j] * ((hist[j + 1].0[k] - hist[j].0[k]) + (hist[j + 1].1[k] - hist[j].1[k]))).sum();
        xk[k] + fk[k] - c
    });
    next.iter().all(|v| v.is_finite()).then_some(next)
}

fn principal_axes(mean: V3, cov: [[f64; 3]; 3]) -> (V3, M3) {
    let m = Matrix3::from_fn(|i, j| cov[i][j]);
    let eig = SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]).then(a.cmp(&b)));
    let mut axes = [[0.0; 3]; 3]; // columns: the axes, largest variance first
    for (c, &k) in order.iter().enumerate() {
        let v = eig.eigenvectors.column(k);
        // a deterministic sign: the largest component positive
        let big = (0..3).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()).then(b.cmp(&a))).unwrap_or(0);
        let s = if v[big] < 0.0 { -1.0 } else { 1.0 };
        for r in 0..3 {
            axes[r][c] = s * v[r];
        }
    }
    // right-handed: third = first x second
    let (a0, a1) = ([axes[0][0], axes[1][0], axes[2][0]], [axes[0][1], axes[1][1], axes[2][1]]);
    let a2 = gagekit_gdt::vec3::cross(a0, a1);
    for r in 0..3 {
        axes[r][2] = a2[r];
    }
    (mean, axes)
}

/// The mean and covariance of the points moved by `pose`: summed per fixed chunk, then
/// in chunk order (in parallel, deterministic; no moved copy of the cloud).
fn point_moments(points: &[f64], pose: &Pose) -> (V3, [[f64; 3]; 3]) {
    const PART: usize = 3 * 8192;
    let n = (points.len() / 3) as f64;
    let sums: Vec<V3> = points
        .par_chunks(PART)
        .map(|c| {
            let mut s = [0.0; 3];
            for p in c.chunks_exact(3) {
                let q = pose.apply([p[0], p[1], p[2]]);
                for k in 0..3 {
                    s[k] += q[k];
                }
            }
            s
        })
        .collect();
    let mut mean = [0.0; 3];
    for s in sums {
        for k in 0..3 {
            mean[k] += s[k];
        }
    }
    for v in mean.iter_mut() {
        *v /= n;
    }
    let parts: Vec<[[f64; 3]; 3]> = points
        .par_chunks(PART)
        .map(|c| {
            let mut cov = [[0.0; 3]; 3];
            for p in c.chunks_exact(3) {
                let q = pose.apply([p[0], p[1], p[2]]);
                let d = [q[0] - mean[0], q[1] - mean[1], q[2] - mean[2]];
                for i in 0..3 {
                    for j in 0..3 {
                        cov[i][j] += d[i] * d[j];
                    }
                }
            }
            cov
        })
        .collect();
    let mut cov = [[0.0; 3]; 3];
    for part in parts {
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += part[i][j];
            }
        }
    }
    for row in cov.iter_mut() {
        for v in row.iter_mut() {
            *v /= n;
        }
    }
    (mean, cov)
}

/// The principal-axes starts: the scan's axes onto the surface's, in each of the 24
/// rotations of the cube group (the axes' order and signs: a scan's point density can
/// reorder its principal axes), centroid on centroid.
pub fn principal_starts(mesh: &TriMesh, points: &[f64], initial: &Pose) -> Vec<Pose> {
    let (ms, cs) = point_moments(points, initial);
    let (mm, cm) = mesh.surface_moments();
    let (_, u) = principal_axes(ms, cs);
    let (_, v) = principal_axes(mm, cm);
    let mut out = Vec::new();
    for perm in [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]] {
        for signs in [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0],
                      [-1.0, -1.0, -1.0], [-1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, -1.0]] {
            // P e_k = signs[k] e_perm[k]; keep the proper ones (det R = det P = +1)
            let mut pm = [[0.0; 3]; 3];
            for k in 0..3 {
                pm[perm[k]][k] = signs[k];
            }
            let det = pm[0][0] * (pm[1][1] * pm[2][2] - pm[1][2] * pm[2][1]) - pm[0][1] * (pm[1][0] * pm[2][2] - pm[1][2] * pm[2][0])
                + pm[0][2] * (pm[1][0] * pm[2][1] - pm[1][1] * pm[2][0]);
            if det < 0.0 {
                continue;
            }
            // R = V P U^T
            let mut vp = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    vp[i][j] = (0..3).map(|k| v[i][k] * pm[k][j]).sum();
                }
            }
            let mut r = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    r[i][j] = (0..3).map(|k| vp[i][k] * u[j][k]).sum();
                }
            }
            let rm = apply(&r, ms);
            out.push(Pose { r, t: [mm[0] - rm[0], mm[1] - rm[1], mm[2] - rm[2]] }.after(initial));
        }
    }
    out
}

/// Options of [`best_fit`].
#[derive(Debug, Clone, Copy)]
pub struct FitOptions {
    pub initial: Pose,
    /// x, y, z, rx, ry, rz: free (true) or locked
    pub free: [bool; 6],
    pub max_distance: Option<f64>,
    /// also start from the principal axes and their flips (ignored when a parameter is locked)
    pub search: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { initial: Pose::IDENTITY, free: [true; 6], max_distance: None, search: true }
    }
}

/// Iterate from `p` on growing evenly spaced subsamples of the frame's points (`stages`,
/// ascending; the last should be `usize::MAX`, every point): each subsample stage until
/// its step is below [`COARSE`] (or 30 steps), then every point to the fixed point
/// ([`FIXED`], at most [`MAX_FINAL`] steps). The subsamples only bring the start near the whole cloud's
/// optimum; the answer is the fixed point of the iteration on all points. Returns the
/// last stage's summary (at the final pose) and the total iterations.
pub fn refine(frame: &Frame, p: &mut [f64; 6], stages: &[usize]) -> Result<(Iterated, usize)> {
    let n = frame.n();
    let mut iterations = 0;
    // every point's cache, kept from stage to stage (a point of several subsamples
    // starts each from where the last left it)
    let mut caches: Vec<Cache> = (0..n).into_par_iter().map(|_| Cache::EMPTY).collect();
    for &m in stages {
        let idx = sample(n, m);
        if m >= n {
            // every point: their caches as they are (no copy)
            let r = iterate(frame, &idx, p, &mut caches, MAX_FINAL, FIXED, true)?;
            return Ok((r, iterations + r.iterations));
        }
        let mut hints: Vec<Cache> = idx.par_iter().map(|&i| caches[i as usize]).collect();
        iterations += iterate(frame, &idx, p, &mut hints, 30, COARSE, false)?.iterations;
        for (&i, h) in idx.iter().zip(hints) {
            caches[i as usize] = h;
        }
    }
    Err(GkError::invalid("best-fit: the stages must end with every point"))
}

/// The start search in `search` (its bound) from `starts`: every start screened briefly
/// on [`SCREEN_SAMPLE`] points, the best few iterated further on `idx0`; the smallest
/// median |distance| wins (ties: the first). Returns the winner (its index and parameters,
/// None when no start brings points within reach) and the iterations done.
fn search_starts(search: &Frame, starts: &[Pose], idx0: &[u32]) -> Result<(Option<(usize, [f64; 6])>, usize)> {
    let screen = sample(search.n(), SCREEN_SAMPLE);
    let mut iterations = 0;
    // the starts in parallel (each on one chunk of points), their results taken in order;
    // two rounds: every start, then the best few of them further
    let many = starts.len() > 1;
    let mut round: Vec<(usize, [f64; 6], Vec<Cache>)> = (0..starts.len()).map(|k| (k, [0.0; 6], vec![Cache::EMPTY; screen.len()])).collect();
    let mut scored: Vec<(f64, usize, [f64; 6])> = Vec::new();
    for (steps, keep) in SCREEN_ROUNDS {
        let done: Vec<Result<(Iterated, usize, [f64; 6], Vec<Cache>)>> = round
            .into_par_iter()
            .map(|(k, mut p, mut hints)| {
                let frame = search.from_base(starts[k]);
                let r = iterate(&frame, &screen, &mut p, &mut hints, if many { steps } else { 0 }, FINE, true)?;
                Ok((r, k, p, hints))
            })
            .collect();
        let mut ok = Vec::new();
        for res in done {
            match res {
                Ok(v) => {
                    iterations += v.0.iterations;
                    ok.push(v);
                }
                Err(e) if e.kind == gagekit_core::ErrorKind::DegenerateGeometry && many => continue,
                Err(e) => return Err(e),
            }
        }
        ok.sort_by(|a, b| a.0.median.total_cmp(&b.0.median).then(a.1.cmp(&b.1)));
        ok.truncate(keep);
        scored = ok.iter().map(|(r, k, p, _)| (r.median, *k, *p)).collect();
        round = ok.into_iter().map(|(_, k, p, h)| (k, p, h)).collect();
        if !many {
            break;
        }
    }
    scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut best: Option<(f64, usize, [f64; 6])> = None;
    for &(_, k, p0) in scored.iter().take(KEEP_STARTS) {
        let frame = search.from_base(starts[k]);
        let mut p = p0;
        let mut hints = vec![Cache::EMPTY; idx0.len()];
        let r = match iterate(&frame, idx0, &mut p, &mut hints, 30, FINE, true) {
            Ok(v) => v,
            Err(e) if e.kind == gagekit_core::ErrorKind::DegenerateGeometry && starts.len() > 1 => continue,
            Err(e) => return Err(e),
        };
        iterations += r.iterations;
        if best.as_ref().map_or(true, |b| r.median < b.0) {
            best = Some((r.median, k, p));
        }
    }
    Ok((best.map(|(_, k, p)| (k, p)), iterations))
}

/// The robust best-fit alignment (module docs): the pose applied to the scan.
///
/// With a bound (`max_distance`) the start search runs twice: under the bound, and without
/// it. From an arbitrary pose few points are within the bound, and the median |distance|
/// of those few can favour a start that brings a few points near the model over the right
/// one; without the bound, clutter that is a large share of the points (more than about a
/// third: the median is then near it) pulls the fit off. Of the two winners, the one with
/// more points of the 2000-point sample within the bound goes on (ties: the smaller median
/// |distance| there, then the search under the bound).
pub fn best_fit(mesh: &TriMesh, points: &[f64], opt: &FitOptions) -> Result<BestFit> {
    let n = points.len() / 3;
    let before = Frame::new(mesh, points, opt.initial, opt.max_distance, opt.free)?;
    // the RMS before, on an evenly spaced sample (far points cost the most to query; the
    // caller measures the whole cloud at its initial pose when it needs it)
    let idx0 = sample(n, START_SAMPLE);
    let mut hints_before = vec![Cache::EMPTY; idx0.len()];
    let rms_before = iterate(&before, &idx0, &mut [0.0; 6], &mut hints_before, 0, FINE, true).map(|r| r.rms).unwrap_or(f64::NAN);
    let mut starts = vec![opt.initial];
    if opt.search && opt.free.iter().all(|&f| f) {
        starts.extend(principal_starts(mesh, points, &opt.initial));
    }
    let (mut best, mut iterations) = match search_starts(&before, &starts, &idx0) {
        Ok(v) => v,
        // too few points within the bound from the given pose: the search without it may find more
        Err(e) if e.kind == gagekit_core::ErrorKind::DegenerateGeometry && before.bound2.is_finite() => (None, 0),
        Err(e) => return Err(e),
    };
    if before.bound2.is_finite() {
        let unbounded = Frame { bound2: f64::INFINITY, ..before.from_base(opt.initial) };
        let (other, it) = search_starts(&unbounded, &starts, &idx0)?;
        iterations += it;
        // each winner's points within the bound and their median |distance|, on the sample
        let score = |w: &Option<(usize, [f64; 6])>| -> Result<(usize, f64)> {
            let Some((k, p)) = w else { return Ok((0, f64::INFINITY)) };
            let mut hints = vec![Cache::EMPTY; idx0.len()];
            match iterate(&before.from_base(starts[*k]), &idx0, &mut p.clone(), &mut hints, 0, FINE, true) {
                Ok(r) => Ok((r.used, r.median)),
                Err(e) if e.kind == gagekit_core::ErrorKind::DegenerateGeometry => Ok((0, f64::INFINITY)),
                Err(e) => Err(e),
            }
        };
        let (a, b) = (score(&best)?, score(&other)?);
        if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
            best = other;
        }
    }
    let (start, mut p) = best.ok_or_else(|| GkError::degenerate("best-fit: no start brings the points within reach of the model"))?;
    // the parameters keep accumulating on the winning start: a locked one stays exactly 0
    let frame = before.from_base(starts[start]);
    let (last, it) = refine(&frame, &mut p, &STAGES)?;
    iterations += it;
    Ok(BestFit { pose: frame.pose(&p), iterations, rms_before, rms_after: last.rms, n_used: last.used, start })
}

#[cfg(test)]
mod tests;
