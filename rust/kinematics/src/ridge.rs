//! Leave-one-cycle-out errors of the temperature ridge model of thermal tracking (Sec. 4.3.4,
//! Sec. 7.2 item 4), for every ridge strength at once.
//!
//! Cycle c has cycle-mean temperatures t_c (S), identified groups p_c (G) and residual vectors
//! r_c (3n: the errors left after the tracker placement, table frame). For the training set
//! K = all cycles but i (k - 1 of them) and strength lambda, the ridge model standardises the
//! temperatures of K (mean tm, population standard deviation sd, 1 where below 1e-9), X =
//! (T_K - tm) / sd, and predicts g = pm + Y^T X (X^T X + mu I)^-1 x_i with Y = P_K - pm,
//! x_i = (t_i - tm) / sd and mu = lambda * trace(X^T X) / (k - 1). The error of cycle i is the
//! mean over its n points of |r_i - M g| (M the reduced design matrix, 3n x G).
//!
//! Everything of K comes from sums over all k cycles minus cycle i (S x S and S x G), and
//! M Y^T X = (A0 - t_i (M p_i)^T - (k-1) tm (M pm)^T)^T / sd with A0 = (sum_c t_c p_c^T) M^T
//! shared by every K: one S x S eigendecomposition per training set, then per strength an
//! S-vector z = (X^T X + mu I)^-1 x_i / sd and a combination of S + 3 vectors of length 3n.
//! That is the direct computation (one ridge solve per training set and strength) rearranged,
//! equal to rounding.

use gagekit_core::{interrupt, GkError, Result};
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

/// Sum over the held-out cycles of the mean residual length, per strength (see the module).
/// `t` (k, s), `p` (k, g), `r` (k, 3n), `m` (3n, g) row-major; k >= 3.
#[allow(clippy::too_many_arguments)]
pub fn loo_errors(t: &[f64], p: &[f64], r: &[f64], m: &[f64], k: usize, s: usize, g: usize, lambdas: &[f64]) -> Result<Vec<f64>> {
    if k < 3 || s == 0 || g == 0 || t.len() != k * s || p.len() != k * g || r.len() % k != 0 {
        return Err(GkError::invalid("ridge leave-one-out: inconsistent array sizes"));
    }
    let d = r.len() / k;
    if d % 3 != 0 || m.len() != d * g {
        return Err(GkError::invalid("ridge leave-one-out: residuals must be 3n long and the design matrix 3n x G"));
    }
    let kk = (k - 1) as f64;
    // temperatures shifted by their mean (the model does not depend on a shift)
    let mut mean = vec![0.0; s];
    for c in 0..k {
        for j in 0..s {
            mean[j] += t[c * s + j];
        }
    }
    mean.iter_mut().for_each(|v| *v /= k as f64);
    let ts: Vec<f64> = (0..k * s).map(|i| t[i] - mean[i % s]).collect();
    // sums over all cycles: sum t, sum t t^T, M p_c per cycle, their sum, A0 = (sum t p^T) M^T
    let mut st = vec![0.0; s];
    let mut stt = vec![0.0; s * s];
    let mut stp = vec![0.0; s * g];
    for c in 0..k {
        let tc = &ts[c * s..(c + 1) * s];
        for a in 0..s {
            st[a] += tc[a];
            for b in 0..s {
                stt[a * s + b] += tc[a] * tc[b];
            }
            for q in 0..g {
                stp[a * g + q] += tc[a] * p[c * g + q];
            }
        }
    }
    // M p_c of every cycle (k x 3n) and A0 = (sum t p^T) M^T (s x 3n): matrix products
    let mmat = DMatrix::from_row_slice(d, g, m);
    let mpm_all = DMatrix::from_row_slice(k, g, p) * mmat.transpose();
    let mp: Vec<f64> = (0..k * d).map(|i| mpm_all[(i / d, i % d)]).collect();
    let mut smp = vec![0.0; d];
    for c in 0..k {
        for e in 0..d {
            smp[e] += mp[c * d + e];
        }
    }
    let a0t = &mmat * DMatrix::from_row_slice(s, g, &stp).transpose(); // A0^T: 3n x s
    interrupt::check()?;
    let per_fold: Vec<Vec<f64>> = (0..k)
        .into_par_iter()
        .map(|i| {
            let ti = &ts[i * s..(i + 1) * s];
            let tm: Vec<f64> = (0..s).map(|a| (st[a] - ti[a]) / kk).collect();
            let mut scat = DMatrix::<f64>::zeros(s, s);
            for a in 0..s {
                for b in 0..s {
                    scat[(a, b)] = stt[a * s + b] - ti[a] * ti[b] - kk * tm[a] * tm[b];
                }
            }
            let sd: Vec<f64> = (0..s).map(|a| {
                let v = (scat[(a, a)] / kk).max(0.0).sqrt();
                if v > 1e-9 { v } else { 1.0 }
            }).collect();
            let xtx = DMatrix::from_fn(s, s, |a, b| scat[(a, b)] / sd[a] / sd[b]);
            let scale = (xtx.trace() / kk).max(1e-12);
            let eig = SymmetricEigen::new(xtx);
            let x: Vec<f64> = (0..s).map(|a| (ti[a] - tm[a]) / sd[a]).collect();
            // x in the eigenbasis
            let vx: Vec<f64> = (0..s).map(|j| (0..s).map(|a| eig.eigenvectors[(a, j)] * x[a]).sum()).collect();
            let mpm: Vec<f64> = (0..d).map(|e| (smp[e] - mp[i * d + e]) / kk).collect();
            let ri = &r[i * d..(i + 1) * d];
            let mpi = &mp[i * d..(i + 1) * d];
            // residuals of every strength: r_i + alpha M p_i + ((k-1) beta - 1) M pm - A0^T z,
            // the A0 part as one product (3n x s) (s x L)
            let nl = lambdas.len();
            let mut zc = DMatrix::<f64>::zeros(nl, s);
            let mut rank3 = vec![(0.0, 0.0); nl];
            let mut w = vec![0.0; s];
            for (l, &lam) in lambdas.iter().enumerate() {
                let mu = lam * scale;
                // z = D^-1 V diag(1 / (e + mu)) V^T x
                for j in 0..s {
                    w[j] = vx[j] / (eig.eigenvalues[j].max(0.0) + mu);
                }
                let (mut alpha, mut beta) = (0.0, 0.0);
                for a in 0..s {
                    let za = (0..s).map(|j| eig.eigenvectors[(a, j)] * w[j]).sum::<f64>() / sd[a];
                    zc[(l, a)] = za;
                    alpha += ti[a] * za;
                    beta += tm[a] * za;
                }
                rank3[l] = (alpha, kk * beta - 1.0);
            }
            let shared = &a0t * zc.transpose(); // 3n x L: A0^T z per strength, contiguous
            (0..nl)
                .map(|l| {
                    let (alpha, cm) = rank3[l];
                    let total: f64 = (0..d / 3)
                        .map(|pt| {
                            let mut sq = 0.0;
                            for e in 3 * pt..3 * pt + 3 {
                                let v = ri[e] + alpha * mpi[e] + cm * mpm[e] - shared[(e, l)];
                                sq += v * v;
                            }
                            sq.sqrt()
                        })
                        .sum();
                    total / (d / 3) as f64
                })
                .collect::<Vec<f64>>()
        })
        .collect();
    interrupt::check()?;
    let mut err = vec![0.0; lambdas.len()];
    for f in &per_fold {
        for (e, v) in err.iter_mut().zip(f) {
            *e += v;
        }
    }
    Ok(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct computation for one training set and strength (dual form, as first written).
    #[allow(clippy::too_many_arguments)]
    fn direct(t: &[f64], p: &[f64], r: &[f64], m: &[f64], k: usize, s: usize, g: usize, lam: f64) -> f64 {
        let d = r.len() / k;
        let mut total = 0.0;
        for i in 0..k {
            let keep: Vec<usize> = (0..k).filter(|&c| c != i).collect();
            let n = keep.len();
            let tm: Vec<f64> = (0..s).map(|a| keep.iter().map(|&c| t[c * s + a]).sum::<f64>() / n as f64).collect();
            let pm: Vec<f64> = (0..g).map(|q| keep.iter().map(|&c| p[c * g + q]).sum::<f64>() / n as f64).collect();
            let sd: Vec<f64> = (0..s).map(|a| {
                let v = (keep.iter().map(|&c| (t[c * s + a] - tm[a]).powi(2)).sum::<f64>() / n as f64).sqrt();
                if v > 1e-9 { v } else { 1.0 }
            }).collect();
            let x = DMatrix::from_fn(n, s, |row, a| (t[keep[row] * s + a] - tm[a]) / sd[a]);
            let y = DMatrix::from_fn(n, g, |row, q| p[keep[row] * g + q] - pm[q]);
            let kmat = &x * x.transpose();
            let scale = (kmat.trace() / n as f64).max(1e-12);
            let sol = (kmat + DMatrix::identity(n, n) * (lam * scale)).lu().solve(&y).unwrap();
            let b = x.transpose() * sol;
            let xi = DMatrix::from_fn(1, s, |_, a| (t[i * s + a] - tm[a]) / sd[a]);
            let gi = DMatrix::from_fn(1, g, |_, q| pm[q]) + xi * b;
            let mut mean = 0.0;
            for pt in 0..d / 3 {
                let mut sq = 0.0;
                for c in 0..3 {
                    let e = pt * 3 + c;
                    let v = r[i * d + e] - (0..g).map(|q| m[e * g + q] * gi[(0, q)]).sum::<f64>();
                    sq += v * v;
                }
                mean += sq.sqrt();
            }
            total += mean / (d / 3) as f64;
        }
        total
    }

    #[test]
    fn equals_the_direct_computation() {
        let (k, s, g, d) = (9, 3, 4, 12);
        let mut state = 7u64;
        let mut rnd = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut t: Vec<f64> = (0..k * s).map(|_| 20.0 + rnd()).collect();
        for c in 0..k {
            t[c * s + 2] = 21.5; // a constant sensor
        }
        let p: Vec<f64> = (0..k * g).map(|_| rnd() * 1e-3).collect();
        let r: Vec<f64> = (0..k * d).map(|_| rnd() * 1e-3).collect();
        let m: Vec<f64> = (0..d * g).map(|_| rnd()).collect();
        let lambdas = [1e-3, 0.1, 1.0, 10.0, 1e3];
        let got = loo_errors(&t, &p, &r, &m, k, s, g, &lambdas).unwrap();
        for (lam, v) in lambdas.iter().zip(&got) {
            let want = direct(&t, &p, &r, &m, k, s, g, *lam);
            assert!((v - want).abs() <= 1e-10 * want.abs(), "{lam}: {v} vs {want}");
        }
    }
}

