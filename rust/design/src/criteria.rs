//! Optimality criteria (Eqs. 4.3-4.5 plus E and I) and the exact figures of a design.

use crate::dense::{gram_add, sym_eig};
use gagekit_core::{GkError, Result};
use std::str::FromStr;

/// What a design minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Criterion {
    /// tr((M^T M)^-1), Eq. 4.4: average variance of the parameter estimates.
    A,
    /// log det((M^T M)^-1), Eq. 4.3: volume of the confidence ellipsoid.
    D,
    /// kappa(M) = s_max / s_min, Eq. 4.5 (singular values, ERRATA item 2).
    K,
    /// 1 / l_min(M^T M): the worst-determined direction (maximise the smallest eigenvalue).
    E,
    /// tr(W (M^T M)^-1): prediction variance averaged over the design space, W = mean f f^T.
    I,
}

impl FromStr for Criterion {
    type Err = GkError;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_uppercase().as_str() {
            "A" => Ok(Self::A),
            "D" => Ok(Self::D),
            "K" => Ok(Self::K),
            "E" => Ok(Self::E),
            "I" => Ok(Self::I),
            _ => Err(GkError::invalid(format!(
                "unknown design criterion {s:?}; choose one of A, D, K, E, I"
            ))),
        }
    }
}

impl Criterion {
    /// Whether the criterion is a spectral one searched with eigenvalue screening.
    pub fn is_spectral(self) -> bool {
        matches!(self, Self::K | Self::E)
    }
}

/// Exact figures of a design's information matrix F = M^T M.
#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    /// tr(F^-1) (infinite when F is singular).
    pub trace: f64,
    /// log det(F^-1) (infinite when F is singular).
    pub log_det: f64,
    /// sqrt(l_max / l_min) of F, i.e. the singular-value ratio of M.
    pub condition_number: f64,
    pub lambda_min: f64,
    pub lambda_max: f64,
    /// tr(W F^-1) when a weight matrix is given.
    pub i_value: Option<f64>,
    /// Numerical rank of F (eigenvalues above 1e-12 * l_max).
    pub rank: usize,
}

/// Relative threshold below which an eigenvalue of F counts as zero.
pub const RANK_TOL: f64 = 1e-12;

impl Metrics {
    /// The value a search minimises for `c`.
    pub fn objective(&self, c: Criterion) -> f64 {
        match c {
            Criterion::A => self.trace,
            Criterion::D => self.log_det,
            Criterion::K => self.condition_number,
            Criterion::E => {
                if self.lambda_min > 0.0 {
                    1.0 / self.lambda_min
                } else {
                    f64::INFINITY
                }
            }
            Criterion::I => self.i_value.unwrap_or(f64::INFINITY),
        }
    }
}

/// F = sum of B^T B over the chosen blocks (`blocks` is (N, r, k) row-major).
pub fn information(blocks: &[f64], design: &[usize], r: usize, k: usize) -> Vec<f64> {
    let mut f = vec![0.0; k * k];
    for &j in design {
        gram_add(&mut f, &blocks[j * r * k..(j + 1) * r * k], r, k, 1.0);
    }
    f
}

/// Exact figures of a k x k information matrix, from its eigen-decomposition.
pub fn metrics(f: &[f64], k: usize, weights: Option<&[f64]>) -> Metrics {
    let (vals, vecs) = sym_eig(f, k);
    from_eigen(&vals, &vecs, k, weights)
}

/// Exact figures of the design whose stacked rows are `rows` (n x k, row-major, any n >= 1),
/// validated: no empty matrix, finite rows, a k x k finite weight matrix.
pub fn design_metrics(rows: &[f64], k: usize, weights: Option<&[f64]>) -> Result<Metrics> {
    if k == 0 || rows.is_empty() {
        return Err(GkError::invalid("an empty design matrix has no figures"));
    }
    gagekit_core::check_finite(rows, k, "design-matrix rows")?;
    if let Some(w) = weights {
        if w.len() != k * k {
            return Err(GkError::invalid(format!("weight matrix: expected {k} x {k} values, got {}", w.len())));
        }
        gagekit_core::check_finite(w, k, "weight matrix")?;
    }
    let idx: Vec<usize> = (0..rows.len() / k).collect();
    Ok(metrics(&information(rows, &idx, 1, k), k, weights))
}

/// [`metrics`] from eigenvalues (ascending) and eigenvectors (columns).
pub fn from_eigen(vals: &[f64], vecs: &[f64], k: usize, weights: Option<&[f64]>) -> Metrics {
    let lmax = vals[k - 1].max(0.0);
    let lmin = vals[0].max(0.0);
    let rank = vals
        .iter()
        .filter(|&&l| l > RANK_TOL * lmax && l > 0.0)
        .count();
    let singular = rank < k;
    let inf = f64::INFINITY;
    let trace = if singular {
        inf
    } else {
        vals.iter().map(|l| 1.0 / l).sum()
    };
    let log_det = if singular {
        inf
    } else {
        -vals.iter().map(|l| l.ln()).sum::<f64>()
    };
    let condition_number = if singular { inf } else { (lmax / lmin).sqrt() };
    let i_value = weights.map(|w| {
        if singular {
            return inf;
        }
        (0..k)
            .map(|m| {
                let mut q = 0.0;
                for a in 0..k {
                    let va = vecs[a * k + m];
                    for b in 0..k {
                        q += va * w[a * k + b] * vecs[b * k + m];
                    }
                }
                q / vals[m]
            })
            .sum()
    });
    Metrics {
        trace,
        log_det,
        condition_number,
        lambda_min: lmin,
        lambda_max: lmax,
        i_value,
        rank,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line_blocks(xs: &[f64]) -> Vec<f64> {
        xs.iter().flat_map(|&x| [x, 1.0]).collect()
    }

    #[test]
    fn table_4_1_figures() {
        // Eq. 4.6 rows [x, 1]; Table 4.1 and ERRATA item 7.
        let cases = [
            (vec![0.0, 0.0, 1.0, 1.0], 1.5, 0.25, 2.618),
            (vec![0.0, 0.25, 0.75, 1.0], 2.25, 0.4, 3.25),
            (vec![0.0, 0.0, 0.0, 1.0], 1.667, 0.333, 2.484),
            (vec![0.0, 0.25, 0.25, 1.0], 2.278, 0.444, 3.093),
        ];
        for (xs, tr, det, kappa) in cases {
            let b = line_blocks(&xs);
            let f = information(&b, &[0, 1, 2, 3], 1, 2);
            let m = metrics(&f, 2, None);
            assert!((m.trace - tr).abs() < 1e-3, "{xs:?} {m:?}");
            assert!((m.log_det.exp() - det).abs() < 1e-3, "{xs:?} {m:?}");
            assert!((m.condition_number - kappa).abs() < 1e-3, "{xs:?} {m:?}");
        }
    }

    #[test]
    fn singular_is_infinite() {
        let b = line_blocks(&[0.5, 0.5]);
        let m = metrics(
            &information(&b, &[0, 1], 1, 2),
            2,
            Some(&[1.0, 0.0, 0.0, 1.0]),
        );
        assert_eq!(m.rank, 1);
        assert!(m.trace.is_infinite() && m.condition_number.is_infinite());
        assert!(m.objective(Criterion::I).is_infinite());
        assert!("x".parse::<Criterion>().is_err());
        assert_eq!("k".parse::<Criterion>().unwrap(), Criterion::K);
    }
}
