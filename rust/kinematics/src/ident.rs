//! Identifiability (Eq. 3.14), least squares with covariance (Eq. 3.18) and the closed-form
//! rigid fit of a measurement frame (Step 1 of Sec. 3.1.5).

use gagekit_core::{check_coordinates, check_finite, interrupt, GkError, Result};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// What a design matrix over a rich set of commands reveals about the parameters.
#[derive(Clone, Debug)]
pub struct Identifiability {
    /// Numerical rank of the design matrix.
    pub rank: usize,
    /// Singular values of the column-equilibrated matrix (no-effect columns left out), descending.
    pub singular_values: Vec<f64>,
    /// Parameters without any effect (column zero at working precision).
    pub no_effect: Vec<usize>,
    /// One leader parameter per group, in chain order: the first columns that are independent
    /// of those before them (clearly, not by round-off). The reduced design matrix is M[:, leaders].
    pub leaders: Vec<usize>,
    /// Group coefficients, rank x P row-major, in the parameters' own units: group k is
    /// g_k = sum_j C[k, j] p_j with C[k, leaders[k]] = 1, and M = M[:, leaders] C exactly.
    pub coefficients: Vec<f64>,
    /// Largest |M - M[:, leaders] C| relative to the column norms (a check; ~1e-12).
    pub reconstruction_error: f64,
}

/// Find which parameters and combinations of parameters the design matrix `m` (n x p,
/// row-major) can reveal.
///
/// `length_scale` is a characteristic length of the workspace and `length_power[j]` the power
/// of length by which parameter j's effect scales; column j divided by length_scale^power is a
/// dimensionless column, and a column whose dimensionless norm per row is below `no_effect_tol`
/// has no effect. The rank is that of the SVD of the column-equilibrated matrix at relative
/// tolerance `rtol`; the leaders are chosen in the row space of that SVD by a Gram-Schmidt pass
/// in column order (a QR whose pivots prefer the chain's order), so rank and groups always agree.
pub fn identifiability(
    m: &[f64],
    nrows: usize,
    ncols: usize,
    length_scale: f64,
    length_power: &[u8],
    rtol: f64,
    no_effect_tol: f64,
) -> Result<Identifiability> {
    if ncols == 0 || m.len() != nrows * ncols || length_power.len() != ncols {
        return Err(GkError::invalid(format!(
            "identifiability: inconsistent sizes ({} values for {nrows} x {ncols}, {} length powers)",
            m.len(),
            length_power.len()
        )));
    }
    if nrows == 0 {
        return Err(GkError::invalid("identifiability: no commands given"));
    }
    check_finite(m, ncols, "design matrix")?;
    if !(length_scale.is_finite() && length_scale > 0.0) {
        return Err(GkError::invalid(format!("identifiability: length scale must be positive, got {length_scale}")));
    }
    let full = DMatrix::from_row_slice(nrows, ncols, m);
    let norms: Vec<f64> = (0..ncols).map(|j| full.column(j).norm()).collect();
    let no_effect: Vec<usize> = (0..ncols)
        .filter(|&j| norms[j] / length_scale.powi(length_power[j] as i32) <= no_effect_tol * (nrows as f64).sqrt())
        .collect();
    let active: Vec<usize> = (0..ncols).filter(|j| !no_effect.contains(j)).collect();
    if active.is_empty() {
        return Err(GkError::degenerate("no parameter has any effect on the target position: the chain is singular"));
    }
    let mut eq = DMatrix::zeros(nrows, active.len());
    for (c, &j) in active.iter().enumerate() {
        eq.set_column(c, &(full.column(j) / norms[j]));
    }
    let svd = svd_interruptible(eq.clone(), false)?
        .ok_or_else(|| GkError::numerical("identifiability: the SVD did not converge"))?;
    let singular_values: Vec<f64> = svd.singular_values.iter().copied().collect();
    let smax = singular_values[0];
    let rank = singular_values.iter().filter(|&&s| s > rtol * smax).count();
    // Row space of the equilibrated matrix: W = V_r^T (rank x active). Column c of W is what
    // parameter active[c] contributes to the identifiable directions.
    let vt = svd.v_t.as_ref().ok_or_else(|| GkError::numerical("identifiability: the SVD returned no right singular vectors"))?;
    let w = vt.rows(0, rank).into_owned();
    let picked = pick_leaders(&w);
    let leaders: Vec<usize> = picked.iter().map(|&c| active[c]).collect();
    // Coefficients in equilibrated units: W = W_L C_s, so A_r = A_r[:, L] C_s.
    let mut wl = DMatrix::zeros(rank, rank);
    for (k, &c) in picked.iter().enumerate() {
        wl.set_column(k, &w.column(c));
    }
    let cs = wl.clone().lu().solve(&w).ok_or_else(|| GkError::numerical("identifiability: singular leader block"))?;
    let mut coefficients = vec![0.0; rank * ncols];
    for k in 0..rank {
        for (c, &j) in active.iter().enumerate() {
            let v = if picked[k] == c {
                1.0
            } else if picked.contains(&c) || cs[(k, c)].abs() < 1e-9 {
                0.0
            } else {
                cs[(k, c)]
            };
            // back to the parameters' own units: M_j = n_j a_j = sum_k (n_j / n_Lk) C_s[k, j] M_Lk
            coefficients[k * ncols + j] = v * norms[j] / norms[leaders[k]];
        }
    }
    let mut lead = DMatrix::zeros(nrows, rank);
    for (k, &j) in leaders.iter().enumerate() {
        lead.set_column(k, &full.column(j));
    }
    let cm = DMatrix::from_row_slice(rank, ncols, &coefficients);
    let recon = &lead * &cm - &full;
    let mut reconstruction_error: f64 = 0.0;
    for j in 0..ncols {
        let scale = if no_effect.contains(&j) { length_scale.powi(length_power[j] as i32) } else { norms[j] };
        reconstruction_error = reconstruction_error.max(recon.column(j).norm() / scale);
    }
    if reconstruction_error > 1e-6 {
        return Err(GkError::numerical(format!(
            "identifiability: the groups do not reproduce the design matrix (relative error {reconstruction_error:.1e}); \
             some effects are barely distinguishable (nearly parallel axes?)"
        )));
    }
    Ok(Identifiability { rank, singular_values, no_effect, leaders, coefficients, reconstruction_error })
}

/// Leaders: columns of W (rank x a, rank <= a, full row rank) forming a well-conditioned basis,
/// preferring earlier columns. An ordered Gram-Schmidt pass takes each column whose part
/// outside the span of those before it exceeds `ORDERED_TOL` of the largest remaining; if that
/// leaves the basis incomplete, column pivoting (largest residual first) completes it.
fn pick_leaders(w: &DMatrix<f64>) -> Vec<usize> {
    const ORDERED_TOL: f64 = 1e-3;
    let (r, a) = w.shape();
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut picked: Vec<usize> = Vec::new();
    let residual = |basis: &Vec<DVector<f64>>, c: usize| {
        let mut v = w.column(c).into_owned();
        for _ in 0..2 {
            for q in basis {
                let d = q.dot(&v);
                v.axpy(-d, q, 1.0);
            }
        }
        v
    };
    let scale = (0..a).map(|c| w.column(c).norm()).fold(0.0, f64::max);
    for c in 0..a {
        if picked.len() == r {
            break;
        }
        let v = residual(&basis, c);
        let nv = v.norm();
        if nv > ORDERED_TOL * scale {
            basis.push(v / nv);
            picked.push(c);
        }
    }
    while picked.len() < r {
        // r <= a columns, so a column is left while fewer than r are picked
        let Some((c, v)) = (0..a)
            .filter(|c| !picked.contains(c))
            .map(|c| (c, residual(&basis, c)))
            .max_by(|x, y| x.1.norm().total_cmp(&y.1.norm()))
        else {
            break;
        };
        let nv = v.norm();
        basis.push(v / nv);
        picked.push(c);
    }
    picked.sort_unstable();
    picked
}

/// nalgebra's SVD (`try_svd(compute_u, true, EPSILON, 0)`), which cannot check for an
/// interrupt while it runs: on a tall matrix (an identification over 10^5 observations takes
/// seconds) it runs on a thread of its own so that Ctrl-C is answered at once
/// ([`gagekit_core::interrupt::run_detached`]); the same computation either way.
fn svd_interruptible(a: DMatrix<f64>, compute_u: bool) -> Result<Option<nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>>> {
    let big = a.nrows() * a.ncols() >= 1 << 18; // ~ 40 ms and more
    let svd = move || a.try_svd(compute_u, true, f64::EPSILON, 0);
    if big {
        gagekit_core::interrupt::run_detached(svd)
    } else {
        Ok(svd())
    }
}

/// A least-squares solution with what is needed for its uncertainty.
#[derive(Clone, Debug)]
pub struct Lstsq {
    pub x: Vec<f64>,
    /// (A^T A)^-1, k x k row-major; multiply by sigma^2 for the covariance (Eq. 3.18).
    pub cov_unscaled: Vec<f64>,
    /// Residual sum of squares |b - A x|^2.
    pub rss: f64,
    /// Singular values of the column-equilibrated A, descending.
    pub singular_values: Vec<f64>,
    /// kappa = s_max / s_min of the column-equilibrated A (ERRATA item 2).
    pub condition_number: f64,
    /// Right singular vector of s_min in equilibrated columns: the weakest combination.
    pub weakest: Vec<f64>,
}

/// Least squares min |A x - b| (A n x k row-major), by SVD of the column-equilibrated A.
/// Fails (DegenerateGeometry) if A is rank deficient at relative tolerance 1e-12; `weakest`
/// is then in the message's place: the caller names the columns.
pub fn lstsq(a: &[f64], nrows: usize, ncols: usize, b: &[f64]) -> Result<Lstsq> {
    if ncols == 0 || a.len() != nrows * ncols || b.len() != nrows {
        return Err(GkError::invalid(format!(
            "least squares: inconsistent sizes ({} values for {nrows} x {ncols}, right side {})",
            a.len(),
            b.len()
        )));
    }
    if nrows < ncols {
        return Err(GkError::degenerate(format!(
            "least squares: {nrows} equations for {ncols} unknowns; more observations are needed"
        )));
    }
    check_finite(a, ncols, "design matrix")?;
    check_finite(b, 1, "observations")?;
    interrupt::check()?;
    let am = DMatrix::from_row_slice(nrows, ncols, a);
    interrupt::check()?;
    let norms: Vec<f64> = (0..ncols).map(|j| am.column(j).norm()).collect();
    if let Some(j) = norms.iter().position(|&n| n == 0.0) {
        return Err(GkError::degenerate(format!("least squares: column {j} is zero")));
    }
    let mut eq = am.clone();
    for (j, nj) in norms.iter().enumerate() {
        eq.column_mut(j).scale_mut(1.0 / nj);
    }
    interrupt::check()?;
    let svd = svd_interruptible(eq, true)?.ok_or_else(|| GkError::numerical("least squares: SVD failed"))?;
    let s = &svd.singular_values;
    let smax = s.max();
    let (imin, smin) = s.iter().enumerate().fold((0, f64::INFINITY), |acc, (i, &v)| if v < acc.1 { (i, v) } else { acc });
    let vt = svd.v_t.as_ref().ok_or_else(|| GkError::numerical("least squares: the SVD returned no right singular vectors"))?;
    let weakest: Vec<f64> = vt.row(imin).iter().copied().collect();
    let mut singular_values: Vec<f64> = s.iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let condition_number = smax / smin;
    if smin.is_nan() || smin <= 1e-12 * smax {
        return Err(GkError::degenerate(format!(
            "least squares: the design matrix is rank deficient (condition number {condition_number:.3e})"
        )));
    }
    let u = svd.u.as_ref().ok_or_else(|| GkError::numerical("least squares: the SVD returned no left singular vectors"))?;
    let bv = DVector::from_column_slice(b);
    let utb = u.transpose() * &bv;
    let k = ncols;
    let mut xs = DVector::zeros(k);
    for i in 0..s.len() {
        xs += vt.row(i).transpose() * (utb[i] / s[i]);
    }
    let x: Vec<f64> = (0..k).map(|j| xs[j] / norms[j]).collect();
    let resid = &am * DVector::from_column_slice(&x) - &bv;
    let rss = resid.norm_squared();
    let mut cov = vec![0.0; k * k];
    for i in 0..k {
        for j in 0..k {
            let mut acc = 0.0;
            for l in 0..s.len() {
                acc += vt[(l, i)] * vt[(l, j)] / (s[l] * s[l]);
            }
            cov[i * k + j] = acc / (norms[i] * norms[j]);
        }
    }
    Ok(Lstsq { x, cov_unscaled: cov, rss, singular_values, condition_number, weakest })
}

/// A rigid transform dst ~ R src + t.
#[derive(Clone, Debug)]
pub struct RigidFit {
    /// Rotation, row-major 3 x 3.
    pub rotation: [f64; 9],
    pub translation: [f64; 3],
    /// Root mean square of |R src + t - dst|.
    pub rms: f64,
}

/// The least-squares rigid transform taking `src` onto `dst` (both (n, 3) row-major), in
/// closed form (Kabsch / Horn: SVD of the cross-covariance, reflection excluded). No small-
/// angle assumption: the frames may be turned by any angle.
pub fn rigid_fit(src: &[f64], dst: &[f64]) -> Result<RigidFit> {
    if src.len() != dst.len() || src.len() % 3 != 0 {
        return Err(GkError::invalid(format!(
            "rigid fit: point sets of different sizes ({} and {} values)",
            src.len(),
            dst.len()
        )));
    }
    check_coordinates(src, 3, "nominal positions")?;
    check_coordinates(dst, 3, "measured positions")?;
    let n = src.len() / 3;
    if n < 3 {
        return Err(GkError::degenerate(format!("rigid fit: needs at least 3 points, got {n}")));
    }
    let pt = |s: &[f64], i: usize| Vector3::new(s[3 * i], s[3 * i + 1], s[3 * i + 2]);
    let (mut cs, mut cd) = (Vector3::zeros(), Vector3::zeros());
    for i in 0..n {
        cs += pt(src, i);
        cd += pt(dst, i);
    }
    cs /= n as f64;
    cd /= n as f64;
    let mut h = Matrix3::zeros();
    let mut spread = 0.0;
    for i in 0..n {
        let a = pt(src, i) - cs;
        h += (pt(dst, i) - cd) * a.transpose();
        spread += a.norm_squared();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(GkError::numerical("rigid fit: the SVD returned no singular vectors"));
    };
    let mut sv: Vec<f64> = svd.singular_values.iter().copied().collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    if sv.iter().any(|v| !v.is_finite()) {
        return Err(GkError::numerical("rigid fit: the SVD of the cross-covariance is not finite"));
    }
    if spread == 0.0 || sv[1] <= 1e-10 * sv[0] {
        return Err(GkError::degenerate(
            "rigid fit: the commanded positions are collinear (or coincide), so the measurement frame is undetermined",
        ));
    }
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt;
    let t = cd - r * cs;
    let mut ss = 0.0;
    for i in 0..n {
        ss += (r * pt(src, i) + t - pt(dst, i)).norm_squared();
    }
    let mut rotation = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            rotation[3 * i + j] = r[(i, j)];
        }
    }
    Ok(RigidFit { rotation, translation: [t[0], t[1], t[2]], rms: (ss / n as f64).sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::chain::tests::example;

    /// Halton-like low-discrepancy commands over the example's ranges (Table 3.1).
    fn rich(n: usize) -> Vec<f64> {
        let lo = [0.0, -1250.0, 900.0, 350.0, -800.0];
        let hi = [2.0 * std::f64::consts::PI, 1250.0, 2200.0, 2500.0, -200.0];
        let primes = [2u64, 3, 5, 7, 11];
        let mut out = Vec::new();
        for i in 1..=n as u64 {
            for j in 0..5 {
                let (mut f, mut r, mut k) = (1.0, 0.0, i);
                while k > 0 {
                    f /= primes[j] as f64;
                    r += f * (k % primes[j]) as f64;
                    k /= primes[j];
                }
                out.push(lo[j] + r * (hi[j] - lo[j]));
            }
        }
        out
    }

    #[test]
    fn example_rank_32_and_groups_of_eq_3_14() {
        let m = example();
        let cmds = rich(400);
        let dm = m.design_matrix(&cmds).unwrap();
        let labels = m.param_labels();
        let names: Vec<String> = labels
            .iter()
            .map(|l| format!("{}.{}", ["B", "T1", "X", "T2", "Z", "T3", "Y", "T4", "W", "T5"][l.element], l.name))
            .collect();
        let pw: Vec<u8> = labels.iter().map(|l| l.length_power).collect();
        let id = identifiability(&dm, 1200, 52, 2000.0, &pw, 1e-9, 1e-12).unwrap();
        assert_eq!(id.rank, 32);
        let ne: Vec<&str> = id.no_effect.iter().map(|&j| names[j].as_str()).collect();
        assert_eq!(ne, vec!["T4.alpha", "W.dalpha", "T5.alpha"]);
        // the group led by T1.dx: the five dx and -312.035 T5.beta (Eq. 3.14)
        let k = id.leaders.iter().position(|&j| names[j] == "T1.dx").unwrap();
        let row = &id.coefficients[k * 52..(k + 1) * 52];
        for (j, n) in names.iter().enumerate() {
            let want = match n.as_str() {
                "T1.dx" | "T2.dx" | "T3.dx" | "T4.dx" | "T5.dx" => 1.0,
                "T5.beta" => -312.035,
                // T4's offset (0, 0, -450) of this example: T4.beta = T3.beta + 450 dx
                "T4.beta" => 450.0,
                _ => 0.0,
            };
            assert!((row[j] - want).abs() < 1e-8 * (1.0 + want.abs()), "{n}: {}", row[j]);
        }
        let k = id.leaders.iter().position(|&j| names[j] == "T2.alpha").unwrap();
        let t3a = names.iter().position(|n| n == "T3.alpha").unwrap();
        assert!((id.coefficients[k * 52 + t3a] - 1.0).abs() < 1e-9);
        assert!(id.reconstruction_error < 1e-10);
    }

    #[test]
    fn lstsq_recovers_and_reports_rank_deficiency() {
        // y = 2 + 3 t exactly
        let a: Vec<f64> = (0..10).flat_map(|i| [1.0, i as f64]).collect();
        let b: Vec<f64> = (0..10).map(|i| 2.0 + 3.0 * i as f64).collect();
        let r = lstsq(&a, 10, 2, &b).unwrap();
        assert!((r.x[0] - 2.0).abs() < 1e-12 && (r.x[1] - 3.0).abs() < 1e-12);
        assert!(r.rss < 1e-20);
        // (A^T A)^-1 of [1 t]: var(slope) = 1 / sum (t - tbar)^2 = 1/82.5
        assert!((r.cov_unscaled[3] - 1.0 / 82.5).abs() < 1e-12);
        let bad: Vec<f64> = (0..10).flat_map(|i| [i as f64, 2.0 * i as f64]).collect();
        assert!(lstsq(&bad, 10, 2, &b).is_err());
        assert!(lstsq(&a[..2], 1, 2, &b[..1]).is_err());
    }

    #[test]
    fn rigid_fit_any_rotation() {
        let src = [0.0, 0.0, 0.0, 1000.0, 0.0, 0.0, 0.0, 800.0, 0.0, 0.0, 0.0, 600.0, 300.0, 200.0, 100.0];
        // 170 degrees about (1, 2, 3)/|.|, plus a shift
        let axis = nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0));
        let r = nalgebra::Rotation3::from_axis_angle(&axis, 170f64.to_radians());
        let t = Vector3::new(-2500.0, 1200.0, 40.0);
        let dst: Vec<f64> = src
            .chunks(3)
            .flat_map(|p| {
                let q = r * Vector3::new(p[0], p[1], p[2]) + t;
                [q[0], q[1], q[2]]
            })
            .collect();
        let f = rigid_fit(&src, &dst).unwrap();
        assert!(f.rms < 1e-9);
        for i in 0..3 {
            assert!((f.translation[i] - t[i]).abs() < 1e-8);
            for j in 0..3 {
                assert!((f.rotation[3 * i + j] - r[(i, j)]).abs() < 1e-12);
            }
        }
        let line = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0];
        assert!(rigid_fit(&line, &line).is_err());
    }
}
