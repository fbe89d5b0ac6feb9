//! Circles in any pose (issue 13 part 4; the NIST convention for circles in space):
//! the least-squares plane of the points, their projection onto it, and the 2-D fit of
//! any criterion in that plane (least squares, MC, MI, MZ of Sec. 6.2), mapped back
//! to 3-D. Points with an exactly constant coordinate lie in a coordinate plane,
//! which is then used exactly (its 2-D fit is the fit of the other two coordinates).

use super::complete::{arc_of, MIN_ARC_DEG};
use super::{least_squares, max_inscribed, min_circumscribed, min_zone, Zone};
use crate::criterion::FitCriterion;
use crate::lsq::{self, Extent};
use gagekit_core::Result;
use nalgebra::Vector3;

/// A circle in space.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneCircle {
    pub center: [f64; 3],
    /// Unit normal of the circle's plane.
    pub normal: [f64; 3],
    /// The fitted radius (mean of `r_in` and `r_out` for MZ).
    pub radius: f64,
    /// The 2-D zone in the plane: inner and outer radius (both the radius for MC, MI
    /// and least squares) and the control points.
    pub zone: Zone,
    /// Certificate: min and max distance of the points, projected onto the plane, to
    /// the centre (recomputed in 3-D).
    pub extent: Extent,
    /// Largest distance of a point from the plane (how planar the points are).
    pub out_of_plane: f64,
    /// Arc (rad) the points cover seen from the centre (from the least-squares centre
    /// for a maximum inscribed circle of an arc below 270 degrees, as in 2-D).
    pub arc: f64,
    /// A maximum inscribed circle of an arc below [`MIN_ARC_DEG`] (Sec. 6.2.2).
    pub ill_posed: bool,
}

/// The plane: origin, in-plane unit vectors u, v and the normal.
fn frame(pts: &[f64]) -> Result<([f64; 3], Vector3<f64>, Vector3<f64>, Vector3<f64>)> {
    let n = pts.len() / 3;
    for k in (0..3).rev() {
        let v0 = pts.get(k).copied().unwrap_or(0.0);
        if n >= 3 && pts.chunks_exact(3).all(|p| p[k] == v0) {
            // a coordinate plane, exactly: the other two coordinates in their order
            let (a, b) = [(1, 2), (0, 2), (0, 1)][k];
            let mut origin = [0.0; 3];
            origin[k] = v0;
            let e = |i: usize| Vector3::from_fn(|r, _| if r == i { 1.0 } else { 0.0 });
            return Ok((origin, e(a), e(b), e(k)));
        }
    }
    let (c, axes) = lsq::plane_frame(pts, "circle")?;
    Ok(([c[0], c[1], c[2]], axes[0], axes[1], axes[2]))
}

/// Fit a circle of the given criterion to 3-D points (flat, row-major).
pub fn fit(pts: &[f64], crit: FitCriterion) -> Result<PlaneCircle> {
    gagekit_core::check_finite(pts, 3, "points")?;
    lsq::check_magnitude(pts, 3)?;
    let (o, u, v, nrm) = frame(pts)?;
    let o3 = Vector3::from(o);
    let flat: Vec<f64> = pts
        .chunks_exact(3)
        .flat_map(|p| {
            let d = Vector3::new(p[0], p[1], p[2]) - o3;
            [d.dot(&u), d.dot(&v)]
        })
        .collect();
    let zone = match crit {
        FitCriterion::MinZone => min_zone(&flat)?,
        _ => {
            let c = match crit {
                FitCriterion::LeastSquares => least_squares(&flat)?,
                FitCriterion::MinCircumscribed => min_circumscribed(&flat)?,
                _ => max_inscribed(&flat)?,
            };
            Zone { center: c.center, r_in: c.radius, r_out: c.radius, control_in: c.control.clone(), control_out: c.control }
        }
    };
    let radius = match crit {
        FitCriterion::MinZone => 0.5 * (zone.r_in + zone.r_out),
        _ => zone.r_out,
    };
    let c3 = o3 + u * zone.center[0] + v * zone.center[1];
    let center = [c3[0], c3[1], c3[2]];
    let normal = lsq::upper([nrm[0], nrm[1], nrm[2]]);
    let extent = lsq::circle3_extent(pts, &center, &normal);
    let out_of_plane = lsq::plane_extent(pts, &center, &normal);
    let (arc, _) = arc_of(&flat, crit, zone.center)?;
    let ill_posed = crit == FitCriterion::MaxInscribed && arc.to_degrees() < MIN_ARC_DEG;
    Ok(PlaneCircle {
        center,
        normal,
        radius,
        zone,
        extent,
        out_of_plane: out_of_plane.max.max(-out_of_plane.min),
        arc,
        ill_posed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted(n: usize, r: f64) -> (Vec<f64>, Vector3<f64>, Vector3<f64>) {
        let nrm = Vector3::new(0.3, -0.5, 0.8).normalize();
        let (u, v) = lsq::orthonormal_basis(&nrm);
        let c = Vector3::new(100.0, -40.0, 7.0);
        let pts = (0..n)
            .flat_map(|i| {
                let t = i as f64 * 0.7;
                let rr = r + 0.01 * (3.0 * t).sin();
                let p = c + (u * t.cos() + v * t.sin()) * rr;
                [p[0], p[1], p[2]]
            })
            .collect();
        (pts, c, nrm)
    }

    #[test]
    fn every_criterion_in_a_tilted_plane() {
        let (pts, c, nrm) = tilted(40, 12.0);
        for crit in FitCriterion::ALL {
            let f = fit(&pts, crit).unwrap();
            assert!((Vector3::from(f.center) - c).norm() < 0.02, "{crit:?}");
            assert!(Vector3::from(f.normal).cross(&nrm).norm() < 1e-12);
            assert!(f.extent.min <= f.zone.r_in + 1e-9 && f.extent.max >= f.zone.r_out - 1e-9);
            assert!(f.out_of_plane < 1e-9);
        }
        let mz = fit(&pts, FitCriterion::MinZone).unwrap();
        assert!((mz.extent.max - mz.extent.min - mz.zone.form_error()).abs() < 1e-9);
    }

    #[test]
    fn a_coordinate_plane_is_used_exactly() {
        let pts: Vec<f64> = (0..9).flat_map(|i| { let t = i as f64; [3.0 + t.cos(), 5.0, -2.0 + t.sin()] }).collect();
        let flat: Vec<f64> = pts.chunks_exact(3).flat_map(|p| [p[0], p[2]]).collect();
        let f = fit(&pts, FitCriterion::MinCircumscribed).unwrap();
        let g = min_circumscribed(&flat).unwrap();
        assert_eq!(f.center, [g.center[0], 5.0, g.center[1]]);
        assert_eq!(f.radius, g.radius);
        assert_eq!(f.normal, [0.0, 1.0, 0.0]);
    }
}
