//! The least-squares cylinder as a complete fit: the axis of [`crate::lsq::cylinder`]
//! with its certificate and the arc the points cover.

use super::arc;
use crate::lsq::{self, Extent};
use gagekit_core::Result;

/// A least-squares cylinder with its certificate and arc coverage.
#[derive(Debug, Clone, PartialEq)]
pub struct LeastSquaresCylinder {
    /// Point on the axis (the foot of the centroid) and unit direction (upper half sphere).
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub radius: f64,
    /// Certificate: min and max 3-D distance of the points to the axis.
    pub extent: Extent,
    /// Angle (rad) the points cover around the axis.
    pub arc: f64,
}

impl LeastSquaresCylinder {
    /// Cylindricity about this axis: max - min distance to it.
    pub fn form_error(&self) -> f64 {
        self.extent.max - self.extent.min
    }
}

/// Least-squares cylinder of 3-D points (flat, row-major), from the principal axes and
/// `start_axis` when given (see [`crate::lsq::cylinder`]).
pub fn least_squares(pts: &[f64], start_axis: Option<[f64; 3]>) -> Result<LeastSquaresCylinder> {
    complete(pts, lsq::cylinder(pts, start_axis)?)
}

/// [`least_squares`] from a nearby fit's `axis` alone ([`crate::lsq::cylinder_near`]; a
/// Monte Carlo trial starts from the measured axis).
pub fn least_squares_near(pts: &[f64], axis: [f64; 3]) -> Result<LeastSquaresCylinder> {
    complete(pts, lsq::cylinder_near(pts, axis)?)
}

fn complete(pts: &[f64], c: lsq::Cylinder) -> Result<LeastSquaresCylinder> {
    Ok(LeastSquaresCylinder {
        point: c.point,
        direction: c.direction,
        radius: c.radius,
        extent: lsq::axis_extent(pts, &c.point, &c.direction),
        arc: arc(pts, &c.point, &c.direction),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_cylinder_reports_its_arc() {
        // radius 5 about the z axis through (1, 2, 0), points on half the circumference
        let pts: Vec<f64> = (0..120)
            .flat_map(|i| {
                let t = std::f64::consts::PI * (i % 12) as f64 / 11.0;
                [1.0 + 5.0 * t.cos(), 2.0 + 5.0 * t.sin(), (i / 12) as f64]
            })
            .collect();
        let f = least_squares(&pts, None).unwrap();
        assert!((f.radius - 5.0).abs() < 1e-9 && f.form_error() < 1e-9);
        assert!((f.arc - std::f64::consts::PI).abs() < 1e-9, "{}", f.arc);
        assert!(f.direction[2] > 0.0 && (f.direction[2] - 1.0).abs() < 1e-12);
    }
}
