//! Geometric (orthogonal-distance) least-squares circle, as CMM software reports it.

use super::{dist, Centered, Circle};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Least-squares circle minimising the sum of squared orthogonal distances
/// `sum_i (|p_i - c| - r)^2`.
///
/// Start: the algebraic (Kasa) fit of the centred data; then Levenberg-Marquardt on the
/// orthogonal residuals until the step is at rounding level. `control` holds the point
/// farthest outside and the point farthest inside the fitted circle.
pub fn least_squares(pts: &[f64]) -> Result<Circle> {
    let data = Centered::new(pts, "least-squares circle", 3)?;
    data.require_not_collinear("least-squares circle")?;
    let p = &data.pts;
    let start = kasa(p).ok_or_else(|| {
        GkError::degenerate("least-squares circle: the points are (numerically) collinear")
    })?;
    let (c, r, ne) = levenberg_marquardt(p, start, data.scale)?;
    let (c, r) = gauss_newton_polish(p, c, r, data.scale, ne);
    let (mut imin, mut imax) = (0, 0);
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, q) in p.iter().enumerate() {
        let d = dist(*q, c) - r;
        if d < dmin {
            dmin = d;
            imin = i;
        }
        if d > dmax {
            dmax = d;
            imax = i;
        }
    }
    let mut control = vec![imax, imin];
    control.dedup();
    Ok(Circle {
        center: data.uncenter(c),
        radius: r,
        control,
    })
}

/// Algebraic fit: minimise sum (x^2 + y^2 + D x + E y + F)^2 (linear least squares),
/// on the points shifted to their centroid.
fn kasa(p: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    let n = p.len() as f64;
    let (mx, my) = p.iter().fold((0.0, 0.0), |(a, b), q| (a + q[0], b + q[1]));
    let (mx, my) = (mx / n, my / n);
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut zbar = 0.0;
    for q in p {
        let (x, y) = (q[0] - mx, q[1] - my);
        zbar += x * x + y * y;
    }
    zbar /= n;
    for q in p {
        let (x, y) = (q[0] - mx, q[1] - my);
        let z = x * x + y * y - zbar;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * z;
        syz += y * z;
    }
    // [sxx sxy; sxy syy] [a; b] = 0.5 [sxz; syz]  (centre offset from the centroid)
    let det = sxx * syy - sxy * sxy;
    if det.abs() <= 1e-300 || det.is_nan() {
        return None;
    }
    let a = 0.5 * (syy * sxz - sxy * syz) / det;
    let b = 0.5 * (sxx * syz - sxy * sxz) / det;
    let r2 = a * a + b * b + zbar;
    if r2.is_nan() || r2 <= 0.0 || !a.is_finite() || !b.is_finite() {
        return None;
    }
    Some(([mx + a, my + b], r2.sqrt()))
}

/// Points per chunk of the parallel sums; partial sums are added in chunk order, so the
/// result does not depend on the number of threads.
const CHUNK: usize = 8192;

#[cfg(test)]
fn cost(p: &[[f64; 2]], c: [f64; 2], r: f64) -> f64 {
    let parts: Vec<f64> = p
        .par_chunks(CHUNK)
        .map(|ch| ch.iter().map(|q| (dist(*q, c) - r).powi(2)).sum())
        .collect();
    parts.iter().sum()
}

/// J^T J and J^T e of the orthogonal residuals e_i = |p_i - c| - r.
type Normal = ([[f64; 3]; 3], [f64; 3]);

/// The normal equations (J^T J, J^T e) of the orthogonal residuals e_i = |p_i - c| - r.
fn normal_equations(p: &[[f64; 2]], c: [f64; 2], r: f64) -> Normal {
    cost_normal(p, c, r, false).1
}

/// The cost (the sum [`cost`] gives; 0 without `with_cost`) and the normal equations, summed in one pass: each the sum its own pass gives, bit for bit (the same
/// chunks, the same order a chunk, the chunks' sums added in order; a point at the centre
/// adds its cost and no row).
fn cost_normal(p: &[[f64; 2]], c: [f64; 2], r: f64, with_cost: bool) -> (f64, Normal) {
    let parts: Vec<(f64, [[f64; 3]; 3], [f64; 3])> = p
        .par_chunks(CHUNK)
        .map(|ch| {
            let mut jtj = [[0.0f64; 3]; 3];
            let mut jte = [0.0f64; 3];
            let mut f = 0.0f64;
            for q in ch {
                let d = dist(*q, c);
                if with_cost {
                    f += (d - r).powi(2);
                }
                if d == 0.0 {
                    continue;
                }
                let row = [(c[0] - q[0]) / d, (c[1] - q[1]) / d, -1.0];
                let e = d - r;
                for a in 0..3 {
                    jte[a] += row[a] * e;
                    for b in 0..3 {
                        jtj[a][b] += row[a] * row[b];
                    }
                }
            }
            (f, jtj, jte)
        })
        .collect();
    let mut jtj = [[0.0f64; 3]; 3];
    let mut jte = [0.0f64; 3];
    for (_, m, v) in &parts {
        for a in 0..3 {
            jte[a] += v[a];
            for b in 0..3 {
                jtj[a][b] += m[a][b];
            }
        }
    }
    (parts.iter().map(|x| x.0).sum(), (jtj, jte))
}

/// Levenberg-Marquardt from `start`; a trial step is judged by the cost summed in the pass
/// that builds its normal equations ([`cost_normal`]), so an accepted step reads the
/// points once. Returns the centre, the radius and the normal equations there.
fn levenberg_marquardt(
    p: &[[f64; 2]],
    start: ([f64; 2], f64),
    scale: f64,
) -> Result<([f64; 2], f64, Normal)> {
    let (mut c, mut r) = start;
    let (mut f, mut ne) = cost_normal(p, c, r, true);
    let mut lambda = 1e-6;
    for _ in 0..1000 {
        // normal equations J^T J dx = -J^T e
        let (jtj, jte) = ne;
        let mut improved = false;
        for _ in 0..30 {
            let mut m = jtj;
            for (a, row) in m.iter_mut().enumerate() {
                row[a] += lambda * jtj[a][a].max(1e-300);
            }
            let Some(dx) = solve3(m, [-jte[0], -jte[1], -jte[2]]) else {
                lambda *= 10.0;
                continue;
            };
            let (c1, r1) = ([c[0] + dx[0], c[1] + dx[1]], r + dx[2]);
            let (f1, ne1) = cost_normal(p, c1, r1, true);
            let step = dx[0].abs().max(dx[1].abs()).max(dx[2].abs());
            if f1 <= f + 1e-13 * f {
                c = c1;
                r = r1;
                f = f1;
                ne = ne1;
                lambda = (lambda * 0.1).max(1e-15);
                improved = true;
                if step <= 1e-14 * (scale + r.abs()) {
                    return finish(c, r).map(|(c, r)| (c, r, ne));
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            return finish(c, r).map(|(c, r)| (c, r, ne));
        }
    }
    finish(c, r).map(|(c, r)| (c, r, ne))
}

/// Plain Gauss-Newton steps from the LM solution while they contract: the cost cannot
/// resolve the last digits of a flat minimum (clustered points), the gradient can.
/// `ne`: the normal equations at (c, r).
fn gauss_newton_polish(p: &[[f64; 2]], mut c: [f64; 2], mut r: f64, scale: f64, ne: Normal) -> ([f64; 2], f64) {
    let mut last = f64::INFINITY;
    let mut ne = Some(ne);
    for _ in 0..20 {
        let (jtj, jte) = ne.take().unwrap_or_else(|| normal_equations(p, c, r));
        let Some(dx) = solve3(jtj, [-jte[0], -jte[1], -jte[2]]) else {
            break;
        };
        let step = dx[0].abs().max(dx[1].abs()).max(dx[2].abs());
        if step.is_nan() || step >= 0.5 * last || step > 1e-6 * (scale + r.abs()) {
            break; // not contracting, or not in the final (quadratic) phase
        }
        c = [c[0] + dx[0], c[1] + dx[1]];
        r += dx[2];
        last = step;
        if step <= 1e-16 * (scale + r.abs()) {
            break;
        }
    }
    (c, r)
}

fn finish(c: [f64; 2], r: f64) -> Result<([f64; 2], f64)> {
    if c[0].is_finite() && c[1].is_finite() && r.is_finite() && r > 0.0 {
        Ok((c, r))
    } else {
        Err(GkError::numerical(
            "least-squares circle: the iteration diverged (points nearly collinear?)",
        ))
    }
}

#[allow(clippy::needless_range_loop)]
fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    // Gaussian elimination with partial pivoting
    let mut a = [[0.0; 4]; 3];
    for i in 0..3 {
        a[i][..3].copy_from_slice(&m[i]);
        a[i][3] = b[i];
    }
    for col in 0..3 {
        let piv = (col..3).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        for row in 0..3 {
            if row != col {
                let f = a[row][col] / a[col][col];
                for k in col..4 {
                    a[row][k] -= f * a[col][k];
                }
            }
        }
    }
    let x = [a[0][3] / a[0][0], a[1][3] / a[1][1], a[2][3] / a[2][2]];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fused_pass_sums_the_cost_of_the_cost_pass_bit_for_bit() {
        // more than one chunk, a point at the centre (a cost, no row)
        let mut p: Vec<[f64; 2]> = (0..20_000)
            .map(|i| {
                let a = i as f64 * 0.7;
                let r = 5.0 + 1e-3 * ((i * 7919 % 13) as f64 - 6.0);
                [1.0 + r * a.cos(), -2.0 + r * a.sin()]
            })
            .collect();
        p[17] = [1.0, -2.0];
        for (c, r) in [([1.0, -2.0], 5.0), ([1.001, -1.999], 4.99), ([0.0, 0.0], 1.0)] {
            let (f, ne) = cost_normal(&p, c, r, true);
            assert_eq!(f.to_bits(), cost(&p, c, r).to_bits());
            assert_eq!(ne, normal_equations(&p, c, r));
        }
    }
}
