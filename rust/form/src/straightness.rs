//! Straightness of a line in space (ISO 1101 straightness of an axis or a line
//! element in 3-D): the thinnest cylinder enclosing all points. Its axis is the
//! minimum-zone line and its diameter the straightness. It is the minimum
//! circumscribed cylinder of Sec. 6.3 (Eq. 6.13), searched within `max_tilt` of the
//! least-squares direction (or a nominal one).

use crate::cylinder::{self, Criterion, Options, Outside};
use crate::lsq::{self, Extent};
use gagekit_core::{check_finite, GkError, Result};
use nalgebra::Vector3;

/// A minimum-zone 3-D line.
#[derive(Debug, Clone)]
pub struct Line3Zone {
    /// A point on the line (the foot of the centroid) and its unit direction.
    pub point: [f64; 3],
    pub direction: [f64; 3],
    /// Certificate: min and max distance of the points to the line; the
    /// straightness is `2 * extent.max`.
    pub extent: Extent,
    /// Points on the enclosing cylinder.
    pub control: Vec<usize>,
    /// Reference direction (nominal, else least squares) and the tilt (rad) of the
    /// line from it.
    pub reference: [f64; 3],
    pub tilt: f64,
    /// A better optimum the free search found outside the cone, if any.
    pub outside: Option<Outside>,
}

impl Line3Zone {
    /// The straightness: the diameter of the enclosing cylinder.
    pub fn form_error(&self) -> f64 {
        2.0 * self.extent.max
    }
}

/// The minimum-zone line of 3-D points (flat, row-major, at least 2 points).
///
/// Points that are collinear (the second principal spread below 1e-10 of the first)
/// give the least-squares line, with the (rounding-level) distances as certificate.
pub fn line3(pts: &[f64], opts: &Options) -> Result<Line3Zone> {
    check_finite(pts, 3, "points")?;
    lsq::check_magnitude(pts, 3)?;
    let nominal = opts.search.validate()?;
    let n = pts.len() / 3;
    if n < 2 {
        return Err(GkError::invalid(format!("line: needs at least 2 points, got {n}")));
    }
    let ls = lsq::line(pts, 3)?;
    let ls_dir = Vector3::new(ls.direction[0], ls.direction[1], ls.direction[2]);
    let reference = nominal.unwrap_or(ls_dir);
    let sv = lsq::principal_spread(pts);
    if lsq::negligible(sv[1], sv[0]) {
        let point = [ls.point[0], ls.point[1], ls.point[2]];
        let direction = lsq::upper([ls_dir[0], ls_dir[1], ls_dir[2]]);
        let reference = lsq::upper([reference[0], reference[1], reference[2]]);
        let extent = lsq::axis_extent(pts, &point, &direction);
        let mut control: Vec<usize> = Vec::new();
        let far = lsq::axis_distances(pts, &point, &direction)
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i);
        control.extend(far);
        return Ok(Line3Zone {
            point,
            direction,
            extent,
            control,
            tilt: cylinder::tilt(&direction, &reference),
            reference,
            outside: None,
        });
    }
    let mut o = opts.clone();
    o.search.axis = Some([reference[0], reference[1], reference[2]]);
    let c = cylinder::fit_spread(pts, Criterion::MinCircumscribed, &o, Some(reference), sv[0])?;
    Ok(Line3Zone {
        point: c.point,
        direction: c.direction,
        extent: c.extent,
        control: c.control_out,
        reference: c.reference,
        tilt: c.tilt,
        outside: c.outside,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exactly_collinear_points_have_zero_straightness() {
        let pts: Vec<f64> = (0..7).flat_map(|i| [i as f64, 2.0 * i as f64, 3.0 * i as f64]).collect();
        let z = line3(&pts, &Options::default()).unwrap();
        assert!(z.form_error() < 1e-12, "{}", z.form_error());
        let two = line3(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &Options::default()).unwrap();
        assert!(two.form_error() < 1e-12);
    }

    #[test]
    fn four_points_and_a_bent_line() {
        // a line bent by 0.1 mm in the middle: the enclosing cylinder has the bend as
        // its diameter's worth (points at the ends on one side, the middle on the other)
        let pts = [0.0, 0.0, 0.0, 10.0, 0.1, 0.0, 20.0, 0.0, 0.0, 30.0, 0.05, 0.0];
        let z = line3(&pts, &Options::default()).unwrap();
        let e = lsq::axis_extent(&pts, &z.point, &z.direction);
        assert!((z.form_error() - 2.0 * e.max).abs() < 1e-15);
        assert!(z.form_error() <= 0.1 + 1e-12 && z.form_error() > 0.05, "{}", z.form_error());
        assert!(z.tilt.to_degrees() < 10.0);
    }
}
