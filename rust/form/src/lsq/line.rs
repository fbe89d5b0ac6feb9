//! Least-squares line (total least squares: the principal axis through the centroid).

use super::frame::{arr, centred3, centroid, check_points, principal_axes};
use gagekit_core::{GkError, Result};

/// A line: a point on it (the centroid of the data) and a unit direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    pub point: Vec<f64>,
    pub direction: Vec<f64>,
}

/// Least-squares line through 2-D or 3-D points (total least squares: the
/// principal axis through the centroid).
pub fn line(pts: &[f64], dim: usize) -> Result<Line> {
    let n = check_points(pts, dim, 2, "line")?;
    let c = centroid(pts, dim);
    let q = centred3(pts, dim, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] <= f64::MIN_POSITIVE * n as f64 || sv[0] == 0.0 {
        return Err(GkError::degenerate("line: all points coincide"));
    }
    let mut dir: Vec<f64> = arr(&axes[0])[..dim].to_vec();
    let norm = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
    dir.iter_mut().for_each(|v| *v /= norm);
    Ok(Line { point: c, direction: dir })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_through_points_and_degenerate() {
        let l = line(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0], 2).unwrap();
        assert!((l.direction[0] - l.direction[1]).abs() < 1e-15);
        assert!((l.point[0] - 2.0).abs() < 1e-15 && (l.point[1] - 3.0).abs() < 1e-15);
        assert!(line(&[1.0, 1.0, 1.0, 1.0], 2).is_err());
    }
}
