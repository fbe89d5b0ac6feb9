//! Least-squares circle in space (the NIST convention).

use gagekit_core::Result;

/// A circle in 3-D space: centre, unit normal of its plane, radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle3 {
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
}

/// Least-squares circle in 3-D (the NIST convention): least-squares plane,
/// projection of the points onto it, least-squares circle in that plane
/// ([`crate::circle::in_plane`]).
pub fn circle3(pts: &[f64]) -> Result<Circle3> {
    let c = crate::circle::in_plane::fit(pts, crate::criterion::FitCriterion::LeastSquares)?;
    Ok(Circle3 { center: c.center, normal: c.normal, radius: c.radius })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilted_circle() {
        // a circle of radius 3 about (1, 2, 3) in the plane normal to (0, 0.6, 0.8)
        let (u, v) = ([1.0, 0.0, 0.0], [0.0, 0.8, -0.6]);
        let pts: Vec<f64> = (0..9)
            .flat_map(|i| {
                let t = i as f64 * 0.7;
                let (c, s) = (3.0 * t.cos(), 3.0 * t.sin());
                [1.0 + c * u[0] + s * v[0], 2.0 + c * u[1] + s * v[1], 3.0 + c * u[2] + s * v[2]]
            })
            .collect();
        let c = circle3(&pts).unwrap();
        assert!((c.radius - 3.0).abs() < 1e-12, "{}", c.radius);
        assert!((c.center[1] - 2.0).abs() < 1e-12 && (c.normal[1] - 0.6).abs() < 1e-12);
    }
}
