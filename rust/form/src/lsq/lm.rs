//! Levenberg-Marquardt on a small parameter vector, and the deterministic parallel sums
//! (fixed chunks, ordered reduction) that build its normal equations.

use gagekit_core::{GkError, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Levenberg–Marquardt on a small parameter vector. `eval(params)` returns
/// the sum of squared residuals, J^T J and J^T r (J = d residual / d step,
/// the step applied by `apply`). `scale` is the length scale of the data.
///
/// The cost cannot resolve the last digits of a flat minimum, so once steps
/// are tiny the plain Gauss–Newton step is taken as long as the cost does not
/// grow beyond rounding, until the step itself is at rounding level: the
/// result is then the stationary point to full double precision.
#[allow(clippy::too_many_arguments)]
pub(crate) fn levenberg_marquardt<P: Clone>(
    mut params: P,
    p: usize,
    scale: f64,
    max_iter: usize,
    eval: impl Fn(&P) -> (f64, DMatrix<f64>, DVector<f64>),
    cost: impl Fn(&P) -> f64,
    apply: impl Fn(&P, &DVector<f64>) -> P,
    what: &str,
) -> Result<(P, usize)> {
    let (mut f, mut jtj, mut jtr) = eval(&params);
    let scale = scale.max(1e-300);
    let mut lambda = 1e-6;
    let mut iters = 0;
    let mut polish = 0;
    while iters < max_iter {
        iters += 1;
        let mut a = jtj.clone();
        for k in 0..p {
            a[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
        }
        let step = match a.cholesky() {
            Some(ch) => ch.solve(&(-&jtr)),
            None => {
                lambda = (lambda * 10.0).max(1e-12);
                if lambda > 1e16 {
                    return Err(GkError::degenerate(format!(
                        "{what}: the fit is not determined by these points (singular Jacobian)"
                    )));
                }
                continue;
            }
        };
        if !step.iter().all(|v| v.is_finite()) {
            return Err(GkError::numerical(format!("{what}: the iteration diverged")));
        }
        let size = step.amax();
        if size <= 1e-15 * scale {
            break;
        }
        let trial = apply(&params, &step);
        let ft = cost(&trial);
        let tiny = size <= 1e-8 * scale;
        if ft < f || (tiny && ft <= f * (1.0 + 1e-12) + f64::MIN_POSITIVE && polish < 8) {
            if tiny {
                polish += 1;
            }
            params = trial;
            (f, jtj, jtr) = eval(&params);
            lambda = if tiny { 0.0 } else { (lambda / 10.0).max(1e-12) };
        } else {
            if tiny && polish > 0 {
                break; // a rejected step at rounding level after polishing: done
            }
            lambda = if lambda == 0.0 { 1e-12 } else { lambda * 10.0 };
            if lambda > 1e12 {
                break; // no descent direction left: at the minimum to rounding
            }
        }
    }
    Ok((params, iters))
}


/// Points per chunk of the parallel sums: the chunks are fixed, and their
/// partial sums are added in order, so the thread count never changes a result.
const CHUNK: usize = 8192;

/// Sum of `f` over the points, deterministic (fixed chunks, ordered reduction).
pub(crate) fn det_sum(q: &[[f64; 3]], f: impl Fn(&[f64; 3]) -> f64 + Sync) -> f64 {
    if q.len() <= CHUNK {
        return q.iter().map(&f).sum();
    }
    let parts: Vec<f64> = q.par_chunks(CHUNK).map(|c| c.iter().map(&f).sum::<f64>()).collect();
    parts.iter().sum()
}

/// Sum of squared residuals, J^T J and J^T r for residual rows `row(x) -> (r, J_row)`.
pub(crate) fn normal_equations<const P: usize>(
    q: &[[f64; 3]],
    row: impl Fn(&[f64; 3]) -> (f64, [f64; P]) + Sync,
) -> (f64, DMatrix<f64>, DVector<f64>) {
    type Acc<const P: usize> = (f64, [[f64; P]; P], [f64; P]);
    let part = |c: &[[f64; 3]]| -> Acc<P> {
        let mut acc = (0.0, [[0.0; P]; P], [0.0; P]);
        for x in c {
            let (r, j) = row(x);
            acc.0 += r * r;
            for a in 0..P {
                acc.2[a] += j[a] * r;
                for b in a..P {
                    acc.1[a][b] += j[a] * j[b];
                }
            }
        }
        acc
    };
    let parts: Vec<Acc<P>> =
        if q.len() <= CHUNK { vec![part(q)] } else { q.par_chunks(CHUNK).map(part).collect() };
    let mut jtj = DMatrix::zeros(P, P);
    let mut jtr = DVector::zeros(P);
    let mut f = 0.0;
    for (pf, pm, pv) in &parts {
        f += pf;
        for a in 0..P {
            jtr[a] += pv[a];
            for b in a..P {
                jtj[(a, b)] += pm[a][b];
            }
        }
    }
    for a in 0..P {
        for b in 0..a {
            jtj[(a, b)] = jtj[(b, a)];
        }
    }
    (f, jtj, jtr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lm_solves_a_small_problem_and_sums_are_chunk_independent() {
        // residuals x_i - (p0 + p1 t_i): a straight line, linear least squares
        let q: Vec<[f64; 3]> = (0..20_000).map(|i| [i as f64 * 1e-3, 3.0 - 0.5 * i as f64 * 1e-3, 0.0]).collect();
        let eval = |p: &[f64; 2]| normal_equations::<2>(&q, |x| (p[0] + p[1] * x[0] - x[1], [1.0, x[0]]));
        let cost = |p: &[f64; 2]| det_sum(&q, |x| (p[0] + p[1] * x[0] - x[1]).powi(2));
        let apply = |p: &[f64; 2], s: &DVector<f64>| [p[0] + s[0], p[1] + s[1]];
        let (p, iters) = levenberg_marquardt([0.0, 0.0], 2, 1.0, 100, eval, cost, apply, "line").unwrap();
        assert!((p[0] - 3.0).abs() < 1e-12 && (p[1] + 0.5).abs() < 1e-12, "{p:?}");
        assert!(iters < 100);
        // the parallel sum equals the sequential sum over the same fixed chunks
        let seq: f64 = q.chunks(CHUNK).map(|c| c.iter().map(|x| x[0]).sum::<f64>()).sum();
        assert_eq!(det_sum(&q, |x| x[0]), seq);
    }
}
