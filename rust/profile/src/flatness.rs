//! Flatness parameters of a surface (ISO 12781-1:2011): FLTt, FLTp, FLTv, FLTq of the
//! measured points against the least-squares (LSPL) or minimum-zone (MZPL, its mid-plane)
//! reference plane. Unfiltered: areal filters (ISO 16610-61) are not applied.

use crate::Params;
use gagekit_core::{GkError, Result};
use gagekit_form::criterion::FitCriterion;
use gagekit_form::{lsq, minzone};

/// The flatness of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Flatness {
    pub params: Params,
    pub reference: FitCriterion,
    pub point: [f64; 3],
    /// Unit normal of the reference plane; deviations are positive along it. Oriented
    /// along `up` when given, else with a non-negative z component.
    pub normal: [f64; 3],
    pub n_points: usize,
}

/// FLTt, FLTp, FLTv, FLTq of 3-D points (flat `[x0, y0, z0, ...]`).
pub fn flatness(pts: &[f64], reference: FitCriterion, up: Option<[f64; 3]>) -> Result<Flatness> {
    let (point, normal) = match reference {
        FitCriterion::LeastSquares => {
            let p = lsq::plane(pts)?;
            (p.point, p.normal)
        }
        FitCriterion::MinZone => {
            let z = minzone::plane(pts)?;
            ([z.point[0], z.point[1], z.point[2]], [z.normal[0], z.normal[1], z.normal[2]])
        }
        _ => return Err(GkError::config("flatness: the reference plane is LSPL (least squares) or MZPL (minimum zone)")),
    };
    let u = up.unwrap_or([0.0, 0.0, 1.0]);
    let s = if normal[0] * u[0] + normal[1] * u[1] + normal[2] * u[2] < 0.0 { -1.0 } else { 1.0 };
    let normal = normal.map(|v| s * v);
    let dev: Vec<f64> = pts
        .chunks_exact(3)
        .map(|p| (p[0] - point[0]) * normal[0] + (p[1] - point[1]) * normal[1] + (p[2] - point[2]) * normal[2])
        .collect();
    Ok(Flatness { params: Params::from_deviations(&dev), reference, point, normal, n_points: dev.len() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saddle() {
        let pts: Vec<f64> = (0..21)
            .flat_map(|i| (0..21).map(move |j| (i as f64 - 10.0, j as f64 - 10.0)))
            .flat_map(|(x, y)| [x, y, 1e-4 * x * y])
            .collect();
        let ls = flatness(&pts, FitCriterion::LeastSquares, None).unwrap();
        assert!((ls.params.t - 0.02).abs() < 1e-12 && (ls.params.p - 0.01).abs() < 1e-12);
        let mz = flatness(&pts, FitCriterion::MinZone, None).unwrap();
        assert!((mz.params.t - 0.02).abs() < 1e-9);
    }
}
