//! Least-squares plane: the centroid and the direction of least spread.

use super::frame::{arr, centred3, centroid, check_points, principal_axes, DEGENERATE};
use gagekit_core::{GkError, Result};

/// A plane: a point on it (the centroid of the data) and a unit normal.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// Least-squares plane: centroid and the direction of least spread.
pub fn plane(pts: &[f64]) -> Result<Plane> {
    check_points(pts, 3, 3, "plane")?;
    let c = centroid(pts, 3);
    let q = centred3(pts, 3, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate("plane: all points coincide"));
    }
    if sv[1] <= DEGENERATE * sv[0] {
        return Err(GkError::degenerate("plane: the points are collinear; a plane through them is not determined"));
    }
    Ok(Plane { point: [c[0], c[1], c[2]], normal: arr(&axes[2]) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_normal_and_degenerate() {
        let p = plane(&[0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0]).unwrap();
        assert!(p.normal[2].abs() == 1.0 && (p.point[2] - 1.0).abs() < 1e-15);
        assert!(plane(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]).is_err());
        assert!(plane(&[0.0, f64::NAN, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 3.0]).is_err());
    }
}
