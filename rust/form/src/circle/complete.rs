//! A complete 2-D circle fit of any criterion: the circle, its zone or certificate,
//! the control points, the arc the points cover and whether the fit is ill-posed
//! (Sec. 6.2; a maximum inscribed circle of an arc below 90 degrees, Sec. 6.2.2).

use super::{least_squares, max_angular_gap, max_inscribed, min_circumscribed, min_zone, Circle, Zone};
use crate::criterion::FitCriterion;
use gagekit_core::{GkError, Result};
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Below this arc (degrees) a maximum inscribed circle is ill-posed (Sec. 6.2.2) and
/// every other fit poorly determined.
pub const MIN_ARC_DEG: f64 = 90.0;

/// Below this arc (degrees) the arc of a maximum inscribed circle is judged about the
/// least-squares centre: its own centre can sit anywhere inside a short arc.
const MI_OWN_ARC_DEG: f64 = 270.0;

/// A fitted 2-D circle with everything a report needs.
#[derive(Debug, Clone, PartialEq)]
pub struct CircleFit {
    pub criterion: FitCriterion,
    pub center: [f64; 2],
    /// The fitted radius; for the minimum zone the mean of `r_in` and `r_out`.
    pub radius: f64,
    /// Minimum zone: the inner and outer zone circles. Other criteria: the certificate,
    /// the smallest and largest distance of the points from `center`.
    pub r_in: f64,
    pub r_out: f64,
    /// Input indices of the points that fix the fit (MZ: `control_in`, then the points
    /// of `control_out` not in it).
    pub control: Vec<usize>,
    /// Minimum zone only (empty otherwise): the points on the inner / outer circle.
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Arc (rad) the points cover, seen from `arc_center`.
    pub arc: f64,
    /// The centre the arc is judged about: `center`, or the least-squares centre for a
    /// maximum inscribed circle of an arc below 270 degrees.
    pub arc_center: [f64; 2],
    /// A maximum inscribed circle of an arc below [`MIN_ARC_DEG`].
    pub ill_posed: bool,
}

impl CircleFit {
    /// The roundness about `center`: `r_out - r_in`.
    pub fn form_error(&self) -> f64 {
        self.r_out - self.r_in
    }
}

/// Fit a circle of any criterion to 2-D points (flat, row-major) with the exact kernels.
pub fn fit(pts: &[f64], crit: FitCriterion) -> Result<CircleFit> {
    match crit {
        FitCriterion::MinZone => from_zone(pts, crit, min_zone(pts)?),
        FitCriterion::LeastSquares => from_circle(pts, crit, least_squares(pts)?),
        FitCriterion::MinCircumscribed => from_circle(pts, crit, min_circumscribed(pts)?),
        FitCriterion::MaxInscribed => from_circle(pts, crit, max_inscribed(pts)?),
    }
}

/// The complete fit of a zone found by any method (the exact kernels or the swarm): the
/// zone itself for the minimum zone, its outer (MC) or inner (MI) circle otherwise.
pub fn from_zone(pts: &[f64], crit: FitCriterion, z: Zone) -> Result<CircleFit> {
    match crit {
        FitCriterion::MinZone => {
            let control = z.control();
            let radius = 0.5 * (z.r_in + z.r_out);
            finish(pts, crit, z.center, radius, (z.r_in, z.r_out), control, z.control_in, z.control_out)
        }
        FitCriterion::MinCircumscribed => {
            from_circle(pts, crit, Circle { center: z.center, radius: z.r_out, control: z.control_out })
        }
        FitCriterion::MaxInscribed => {
            from_circle(pts, crit, Circle { center: z.center, radius: z.r_in, control: z.control_in })
        }
        FitCriterion::LeastSquares => Err(GkError::config("circle: a least-squares circle is not a zone")),
    }
}

/// The complete fit of a circle of one of the criteria MC, MI or least squares.
pub fn from_circle(pts: &[f64], crit: FitCriterion, c: Circle) -> Result<CircleFit> {
    let extent = center_distances(pts, c.center);
    finish(pts, crit, c.center, c.radius, extent, c.control, Vec::new(), Vec::new())
}

/// Smallest and largest distance of the points from `center` (hypot, as a caliper).
fn center_distances(pts: &[f64], center: [f64; 2]) -> (f64, f64) {
    pts.par_chunks_exact(2)
        .with_min_len(8192)
        .map(|p| (p[0] - center[0]).hypot(p[1] - center[1]))
        .fold(|| (f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)))
        .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The arc covered, judged about the centre that means something for the criterion.
pub(super) fn arc_of(pts: &[f64], crit: FitCriterion, center: [f64; 2]) -> Result<(f64, [f64; 2])> {
    let arc = TAU - max_angular_gap(pts, center);
    if crit == FitCriterion::MaxInscribed && arc.to_degrees() < MI_OWN_ARC_DEG {
        let reference = least_squares(pts)?.center;
        return Ok((TAU - max_angular_gap(pts, reference), reference));
    }
    Ok((arc, center))
}

#[allow(clippy::too_many_arguments)]
fn finish(
    pts: &[f64],
    crit: FitCriterion,
    center: [f64; 2],
    radius: f64,
    (r_in, r_out): (f64, f64),
    control: Vec<usize>,
    control_in: Vec<usize>,
    control_out: Vec<usize>,
) -> Result<CircleFit> {
    let (arc, arc_center) = arc_of(pts, crit, center)?;
    let ill_posed = crit == FitCriterion::MaxInscribed && arc.to_degrees() < MIN_ARC_DEG;
    Ok(CircleFit { criterion: crit, center, radius, r_in, r_out, control, control_in, control_out, arc, arc_center, ill_posed })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc_points(n: usize, span: f64) -> Vec<f64> {
        (0..n)
            .flat_map(|i| {
                let t = span * i as f64 / (n - 1) as f64;
                let r = 10.0 + 0.01 * (7.0 * t).sin();
                [3.0 + r * t.cos(), -2.0 + r * t.sin()]
            })
            .collect()
    }

    #[test]
    fn every_criterion_full_circle() {
        let pts = arc_points(200, TAU * 0.999);
        for crit in FitCriterion::ALL {
            let f = fit(&pts, crit).unwrap();
            assert!(f.arc.to_degrees() > 355.0 && !f.ill_posed, "{crit:?}");
            assert!(f.r_in <= f.radius + 1e-12 && f.radius <= f.r_out + 1e-12, "{crit:?}");
            assert!(f.form_error() >= 0.0 && f.form_error() < 0.03);
            assert!(!f.control.is_empty());
            assert_eq!(f.control_in.is_empty(), crit != FitCriterion::MinZone);
            assert_eq!(f.arc_center, f.center);
        }
        // the certificate of MC / MI / least squares is the spread of the distances
        let mc = fit(&pts, FitCriterion::MinCircumscribed).unwrap();
        assert!((mc.r_out - mc.radius).abs() < 1e-9);
    }

    #[test]
    fn short_arc_mi_is_ill_posed_and_judged_about_least_squares() {
        let pts = arc_points(50, 1.0);
        let mi = fit(&pts, FitCriterion::MaxInscribed).unwrap();
        let ls = least_squares(&pts).unwrap();
        assert!(mi.ill_posed);
        assert_eq!(mi.arc_center, ls.center);
        assert!((mi.arc - 1.0).abs() < 0.05, "{}", mi.arc);
        let mc = fit(&pts, FitCriterion::MinCircumscribed).unwrap();
        assert!(!mc.ill_posed && mc.arc_center == mc.center);
        assert!(from_zone(&pts, FitCriterion::LeastSquares, min_zone(&pts).unwrap()).is_err());
    }
}
