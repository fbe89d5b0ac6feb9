//! Levenberg-Marquardt on a small parameter vector, and the deterministic parallel sums
//! (fixed chunks, ordered reduction) that build its normal equations.

use gagekit_core::{GkError, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// The sum of squared residuals, J^T J and J^T r of a parameter vector.
pub(crate) type Normal = (f64, DMatrix<f64>, DVector<f64>);

/// Levenberg–Marquardt on a small parameter vector. `eval(params)` returns
/// the sum of squared residuals, J^T J and J^T r (J = d residual / d step,
/// the step applied by `apply`). `scale` is the length scale of the data.
/// Each trial step is judged by `cost` (one pass over the data), and an accepted
/// one then evaluated (a second pass); [`levenberg_marquardt_fused`] judges it by
/// `eval` itself (one pass for an accepted step).
///
/// The cost cannot resolve the last digits of a flat minimum, so once steps
/// are tiny the plain Gauss–Newton step is taken as long as the cost does not
/// grow beyond rounding, until the step itself is at rounding level: the
/// result is then the stationary point to full double precision.
#[allow(clippy::too_many_arguments)]
pub(crate) fn levenberg_marquardt<P: Clone>(
    params: P,
    p: usize,
    scale: f64,
    max_iter: usize,
    eval: impl Fn(&P) -> Normal,
    cost: impl Fn(&P) -> f64,
    apply: impl Fn(&P, &DVector<f64>) -> P,
    what: &str,
) -> Result<(P, usize)> {
    let start = (f64::NAN, eval(&params));
    let (s, iters, _) = lm_core(params, start, p, scale, max_iter, &eval, |t: &P| (cost(t), None), apply, what)?;
    Ok((s, iters))
}

/// [`levenberg_marquardt`] whose `eval(params)` returns the cost beside the normal
/// equations, summed in the same pass: `(cost, (sum of squared residuals, J^T J, J^T r))`,
/// the cost the sum a separate cost pass would give, bit for bit (see
/// [`normal_equations_cost`]). A trial step is judged by that cost and, accepted (most of
/// them), its normal equations are already there: one pass over the data instead of two,
/// the same iterates. Returns the parameters, the iterations and the cost there.
pub(crate) fn levenberg_marquardt_fused<P: Clone>(
    params: P,
    p: usize,
    scale: f64,
    max_iter: usize,
    eval: impl Fn(&P) -> (f64, Normal),
    apply: impl Fn(&P, &DVector<f64>) -> P,
    what: &str,
) -> Result<(P, usize, f64)> {
    let start = eval(&params);
    let plain = |t: &P| eval(t).1;
    lm_core(params, start, p, scale, max_iter, &plain, |t: &P| {
        let (c, e) = eval(t);
        (c, Some(e))
    }, apply, what)
}

/// The iteration: `start` the cost and normal equations of `params`; `probe(trial)` the
/// trial's cost and, when it has them, its normal equations (else `eval` builds them once
/// the step is accepted). Returns the parameters, the iterations and the probed cost there
/// (`start`'s when no step was accepted).
#[allow(clippy::too_many_arguments)]
fn lm_core<P: Clone>(
    mut params: P,
    start: (f64, Normal),
    p: usize,
    scale: f64,
    max_iter: usize,
    eval: &impl Fn(&P) -> Normal,
    probe: impl Fn(&P) -> (f64, Option<Normal>),
    apply: impl Fn(&P, &DVector<f64>) -> P,
    what: &str,
) -> Result<(P, usize, f64)> {
    let (mut cost_here, (mut f, mut jtj, mut jtr)) = start;
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
        let (ft, evaluated) = probe(&trial);
        let tiny = size <= 1e-8 * scale;
        if ft < f || (tiny && ft <= f * (1.0 + 1e-12) + f64::MIN_POSITIVE && polish < 8) {
            if tiny {
                polish += 1;
            }
            params = trial;
            cost_here = ft;
            (f, jtj, jtr) = match evaluated {
                Some(e) => e,
                None => eval(&params),
            };
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
    Ok((params, iters, cost_here))
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
    normal_equations_cost(q, |x| {
        let (r, j) = row(x);
        (0.0, r, j)
    })
    .1
}

/// [`normal_equations`] with a cost summed in the same pass: rows `row(x) -> (c, r, J_row)`,
/// returns (sum of `c`, the normal equations). The sum of `c` is the one [`det_sum`] of
/// `c` gives, bit for bit (the same fixed chunks, the same order).
pub(crate) fn normal_equations_cost<const P: usize>(
    q: &[[f64; 3]],
    row: impl Fn(&[f64; 3]) -> (f64, f64, [f64; P]) + Sync,
) -> (f64, Normal) {
    type Acc<const P: usize> = (f64, [[f64; P]; P], [f64; P], f64);
    let part = |c: &[[f64; 3]]| -> Acc<P> {
        let mut acc = (0.0, [[0.0; P]; P], [0.0; P], 0.0);
        for x in c {
            let (cost, r, j) = row(x);
            acc.0 += r * r;
            acc.3 += cost;
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
    let mut cost = 0.0;
    for (pf, pm, pv, pc) in &parts {
        f += pf;
        cost += pc;
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
    (cost, (f, jtj, jtr))
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

    #[test]
    fn the_fused_pass_gives_the_iterates_of_the_cost_pass_bit_for_bit() {
        // a circle's radial residuals (non-linear): the cost in the normal equations' pass
        // judges each step as the separate cost pass did
        let q: Vec<[f64; 3]> = (0..30_000)
            .map(|i| {
                let t = i as f64 * 0.001;
                let r = 5.0 + 1e-3 * (7.0 * t).sin();
                [1.0 + r * t.cos(), -2.0 + r * t.sin(), 0.0]
            })
            .collect();
        let res = |p: &[f64; 3], x: &[f64; 3]| ((x[0] - p[0]).hypot(x[1] - p[1]) - p[2], [x[0] - p[0], x[1] - p[1]]);
        let row = |p: &[f64; 3], x: &[f64; 3]| {
            let (r, d) = res(p, x);
            let rho = (r + p[2]).max(1e-300);
            (r, [-d[0] / rho, -d[1] / rho, -1.0])
        };
        let eval = |p: &[f64; 3]| normal_equations::<3>(&q, |x| row(p, x));
        let cost = |p: &[f64; 3]| det_sum(&q, |x| res(p, x).0.powi(2));
        let fused = |p: &[f64; 3]| normal_equations_cost::<3>(&q, |x| {
            let (r, j) = row(p, x);
            (res(p, x).0.powi(2), r, j)
        });
        let apply = |p: &[f64; 3], s: &DVector<f64>| [p[0] + s[0], p[1] + s[1], p[2] + s[2]];
        let start = [0.5, -1.5, 4.0];
        let (a, ia) = levenberg_marquardt(start, 3, 5.0, 500, eval, cost, apply, "circle").unwrap();
        let (b, ib, fb) = levenberg_marquardt_fused(start, 3, 5.0, 500, fused, apply, "circle").unwrap();
        assert_eq!((a, ia), (b, ib));
        assert_eq!(fb, cost(&b));
        assert!((a[2] - 5.0).abs() < 1e-3, "{a:?}");
    }
}
