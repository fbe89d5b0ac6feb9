//! Nelder–Mead simplex search, the local refinement after the swarm.
//!
//! Deterministic (no randomness). Restarts from the best vertex with a smaller
//! simplex until a restart no longer improves the value, which lets the search
//! settle into the kinks of min–max objectives (Eqs. 6.13–6.15).

/// Result of a simplex search.
#[derive(Debug, Clone)]
pub struct Simplex {
    pub position: Vec<f64>,
    pub value: f64,
    /// Objective evaluations spent.
    pub evaluations: usize,
    /// Restarts run.
    pub restarts: usize,
}

fn nm_once<F: Fn(&[f64]) -> f64>(
    f: &F,
    x0: &[f64],
    f0: f64,
    step: f64,
    xtol: f64,
    max_evals: usize,
) -> (Vec<f64>, f64, usize) {
    let n = x0.len();
    let evals = std::cell::Cell::new(0usize);
    let call = |x: &[f64]| {
        evals.set(evals.get() + 1);
        let v = f(x);
        if v.is_nan() {
            f64::INFINITY
        } else {
            v
        }
    };
    let mut pts: Vec<Vec<f64>> = vec![x0.to_vec()];
    let mut vals = vec![f0];
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step;
        vals.push(call(&x));
        pts.push(x);
    }
    loop {
        // order vertices (stable, ties by index -> deterministic)
        let mut idx: Vec<usize> = (0..=n).collect();
        idx.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = idx.iter().map(|&i| pts[i].clone()).collect();
        vals = idx.iter().map(|&i| vals[i]).collect();
        let diam = pts[1..]
            .iter()
            .map(|p| p.iter().zip(&pts[0]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        if diam <= xtol || evals.get() >= max_evals || vals[n] == vals[0] && diam <= 1e3 * xtol {
            break;
        }
        let centroid: Vec<f64> =
            (0..n).map(|d| pts[..n].iter().map(|p| p[d]).sum::<f64>() / n as f64).collect();
        let along = |t: f64| -> Vec<f64> {
            (0..n).map(|d| centroid[d] + t * (pts[n][d] - centroid[d])).collect()
        };
        let xr = along(-1.0);
        let fr = call(&xr);
        if fr < vals[0] {
            let xe = along(-2.0);
            let fe = call(&xe);
            if fe < fr {
                pts[n] = xe;
                vals[n] = fe;
            } else {
                pts[n] = xr;
                vals[n] = fr;
            }
        } else if fr < vals[n - 1] {
            pts[n] = xr;
            vals[n] = fr;
        } else {
            let (xc, fc) = if fr < vals[n] {
                let xc = along(-0.5);
                let fc = call(&xc);
                (xc, fc)
            } else {
                let xc = along(0.5);
                let fc = call(&xc);
                (xc, fc)
            };
            if fc < vals[n].min(fr) {
                pts[n] = xc;
                vals[n] = fc;
            } else {
                for i in 1..=n {
                    let x: Vec<f64> = (0..n).map(|d| pts[0][d] + 0.5 * (pts[i][d] - pts[0][d])).collect();
                    vals[i] = call(&x);
                    pts[i] = x;
                }
            }
        }
    }
    let k = (0..=n).fold(0, |k, i| if vals[i] < vals[k] { i } else { k });
    (pts[k].clone(), vals[k], evals.get())
}

/// Minimise `f` from `x0` with an initial simplex of edge `step`, restarting
/// with smaller simplices until the value stops improving or the simplex
/// edge falls below `xtol`.
pub fn nelder_mead<F: Fn(&[f64]) -> f64>(f: F, x0: &[f64], step: f64, xtol: f64) -> Simplex {
    let mut x = x0.to_vec();
    let mut fx = f(&x);
    if fx.is_nan() {
        fx = f64::INFINITY;
    }
    let mut evaluations = 1;
    let mut restarts = 0;
    let mut h = step;
    while h > xtol && restarts < 60 {
        let (y, fy, e) = nm_once(&f, &x, fx, h, xtol, 2000);
        evaluations += e;
        restarts += 1;
        let moved = y.iter().zip(&x).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let gain = fx - fy;
        if fy < fx {
            x = y;
            fx = fy;
        }
        if gain > 1e-12 * fx.abs() {
            // restart around the new point with a simplex the size of the last move
            h = (moved * 2.0).min(h).max(h * 0.01);
        } else {
            h *= 0.01;
        }
    }
    Simplex { position: x, value: fx, evaluations, restarts }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rosenbrock() {
        let f = |x: &[f64]| 100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2);
        let r = nelder_mead(f, &[-1.2, 1.0], 0.5, 1e-12);
        assert!((r.position[0] - 1.0).abs() < 1e-8 && (r.position[1] - 1.0).abs() < 1e-8, "{r:?}");
    }

    #[test]
    fn minimax_kink() {
        // max of three planes: a sharp vertex at (0.3, -0.2)
        let f = |x: &[f64]| {
            let (a, b) = (x[0] - 0.3, x[1] + 0.2);
            (a + b).max(-a + 2.0 * b).max(-0.5 * a - 3.0 * b)
        };
        let r = nelder_mead(f, &[1.0, 1.0], 0.1, 1e-14);
        assert!((r.position[0] - 0.3).abs() < 1e-10 && (r.position[1] + 0.2).abs() < 1e-10, "{r:?}");
    }
}
