//! A small dense linear program for the local minimax searches (cylinders, spheres): few variables (at
//! most six), many inequality rows.
//!
//! `min c^T z` subject to `A z <= b` with `b >= 0` (so `z = 0` is feasible), solved
//! as its dual `min b^T l` subject to `A^T l = -c`, `l >= 0` by the two-phase tableau
//! simplex: the tableau has one row per variable, so a pivot costs O(k m). The
//! primal solution is read off the dual's simplex multipliers.

/// Pivot and ratio-test tolerance (the rows are scaled to O(1) coefficients).
const EPS: f64 = 1e-12;
/// Dantzig pivoting for this many pivots, then Bland's rule (which cannot cycle).
const DANTZIG_PIVOTS: usize = 60;
/// Give up after this many pivots in one phase.
const MAX_PIVOTS: usize = 2000;

/// Minimise `c^T z` subject to `a z <= b` (`a` row-major with `c.len()` columns,
/// every `b` non-negative). `None` if the problem is unbounded or the pivoting
/// did not finish.
pub(crate) fn minimize(a: &[f64], b: &[f64], c: &[f64]) -> Option<Vec<f64>> {
    let k = c.len();
    let m = b.len();
    debug_assert_eq!(a.len(), m * k);
    let w = m + k + 1; // dual columns, artificials, right-hand side
    let mut t = vec![0.0; k * w];
    let mut sign = vec![1.0; k];
    for r in 0..k {
        sign[r] = if -c[r] < 0.0 { -1.0 } else { 1.0 };
        let row = &mut t[r * w..(r + 1) * w];
        for j in 0..m {
            row[j] = sign[r] * a[j * k + r];
        }
        row[m + r] = 1.0;
        row[w - 1] = sign[r] * -c[r];
    }
    let mut basis: Vec<usize> = (m..m + k).collect();
    // phase I: minimise the sum of the artificials
    let mut d = vec![0.0; w];
    for r in 0..k {
        for j in 0..m {
            d[j] -= t[r * w + j];
        }
        d[w - 1] -= t[r * w + w - 1];
    }
    run(&mut t, &mut d, &mut basis, k, w, m)?;
    if -d[w - 1] > 1e-9 {
        return None; // the dual is infeasible: the primal is unbounded
    }
    // artificials left in the basis (at zero) are pivoted out where possible
    for r in 0..k {
        if basis[r] >= m {
            if let Some(j) = (0..m).find(|&j| t[r * w + j].abs() > 1e-9) {
                pivot(&mut t, &mut d, &mut basis, w, r, j);
            }
        }
    }
    // phase II: cost b on the dual columns, 0 on the artificials
    d.iter_mut().for_each(|v| *v = 0.0);
    d[..m].copy_from_slice(b);
    for r in 0..k {
        let cb = if basis[r] < m { b[basis[r]] } else { 0.0 };
        if cb != 0.0 {
            for j in 0..w {
                d[j] -= cb * t[r * w + j];
            }
        }
    }
    run(&mut t, &mut d, &mut basis, k, w, m)?;
    // the reduced cost of artificial r is minus the simplex multiplier of row r
    Some((0..k).map(|r| -sign[r] * d[m + r]).collect())
}

/// Trust-region radius of the SLP searches after a step of infinity norm `step` whose
/// true decrease was `ratio` times the LP's prediction: shrink after poor steps, grow
/// after good ones at the box edge (up to `delta_max`).
pub(crate) fn next_radius(delta: f64, step: f64, ratio: f64, delta_max: f64) -> f64 {
    if ratio < 0.25 {
        0.25 * step.min(delta)
    } else if ratio > 0.75 && step > 0.99 * delta {
        (2.0 * delta).min(delta_max)
    } else {
        delta
    }
}

/// Simplex iterations on the tableau until no dual column (index < m) has a
/// negative reduced cost.
fn run(t: &mut [f64], d: &mut [f64], basis: &mut [usize], k: usize, w: usize, m: usize) -> Option<()> {
    for it in 0..MAX_PIVOTS {
        let enter = if it < DANTZIG_PIVOTS {
            let mut best: Option<usize> = None;
            for j in 0..m {
                if d[j] < -EPS && best.is_none_or(|b| d[j] < d[b]) {
                    best = Some(j);
                }
            }
            best
        } else {
            (0..m).find(|&j| d[j] < -EPS)
        };
        let Some(j) = enter else { return Some(()) };
        let mut leave: Option<(usize, f64)> = None;
        for r in 0..k {
            let e = t[r * w + j];
            if e > EPS {
                let ratio = t[r * w + w - 1] / e;
                let better = match leave {
                    None => true,
                    Some((l, q)) => ratio < q || (ratio == q && basis[r] < basis[l]),
                };
                if better {
                    leave = Some((r, ratio));
                }
            }
        }
        let (r, _) = leave?; // unbounded dual
        pivot(t, d, basis, w, r, j);
    }
    None
}

fn pivot(t: &mut [f64], d: &mut [f64], basis: &mut [usize], w: usize, r: usize, j: usize) {
    let p = t[r * w + j];
    for v in &mut t[r * w..(r + 1) * w] {
        *v /= p;
    }
    let (before, rest) = t.split_at_mut(r * w);
    let (prow, after) = rest.split_at_mut(w);
    for row in before.chunks_exact_mut(w).chain(after.chunks_exact_mut(w)) {
        let f = row[j];
        if f != 0.0 {
            for (x, y) in row.iter_mut().zip(prow.iter()) {
                *x -= f * y;
            }
        }
    }
    let f = d[j];
    if f != 0.0 {
        for (x, y) in d.iter_mut().zip(prow.iter()) {
            *x -= f * y;
        }
    }
    basis[r] = j;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_minimax() {
        // min t s.t. |z0 - 1| <= t, |z0 + 3| <= t... written with b >= 0 after a shift:
        // variables (z0, t), rows: z0 - t <= 1, -z0 - t <= 3, z0 <= 10, -z0 <= 10
        let a = [1.0, -1.0, -1.0, -1.0, 1.0, 0.0, -1.0, 0.0];
        let b = [1.0, 3.0, 10.0, 10.0];
        let z = minimize(&a, &b, &[0.0, 1.0]).unwrap();
        assert!((z[0] + 1.0).abs() < 1e-12 && (z[1] + 2.0).abs() < 1e-12, "{z:?}");
    }

    #[test]
    fn box_bounded_linear_objective() {
        // min -z0 - 2 z1 in the box |z| <= 1 with z0 + z1 <= 1.5
        let a = [1.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 1.0];
        let b = [1.0, 1.0, 1.0, 1.0, 1.5];
        let z = minimize(&a, &b, &[-1.0, -2.0]).unwrap();
        assert!((z[0] - 0.5).abs() < 1e-12 && (z[1] - 1.0).abs() < 1e-12, "{z:?}");
    }

    #[test]
    fn degenerate_vertex_of_a_regular_polygon() {
        // MCC step at the centre of a regular 40-gon: every point row is active at
        // z = 0 (all slacks zero), the optimum is z = 0 with value 0
        let (k, n) = (3, 40);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for j in 0..2 {
            for s in [1.0, -1.0] {
                let mut row = vec![0.0; k];
                row[j] = s;
                a.extend(row);
                b.push(0.5);
            }
        }
        for i in 0..n {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            a.extend([-t.cos(), -t.sin(), -1.0]);
            b.push(0.0);
        }
        let z = minimize(&a, &b, &[0.0, 0.0, 1.0]).unwrap();
        assert!(z.iter().all(|v| v.abs() < 1e-12), "{z:?}");
    }
}
