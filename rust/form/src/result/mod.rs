//! The public results of the fits: what `gagekit.fit_circle`, `fit_cylinder`, `fit_cone`,
//! `fit_line`, `fit_plane`, `fit_sphere` and `fit_circle_3d` return, complete (ASME
//! B89.4.10, dissertation Ch. 6). Each is assembled once here from a kernel's solution: the
//! reported radius and form error of the criterion, the control points (minimum zone: the
//! inner ones, then the outer ones not among them), the certificate (min / max distance of
//! the points to the reported feature, recomputed from its parameters), the arc covered and
//! the reader's warnings. The binding only converts these to Python objects.

mod axis;
mod words;

#[cfg(test)]
mod tests;

pub use axis::{axis_angles, cone, cylinder_least_squares, cylinder_minimax, ConeResult, CylinderResult};
pub use words::{fmt_g, outside_warning};

use crate::circle::in_plane::PlaneCircle;
use crate::circle::CircleFit;
use crate::criterion::FitCriterion;
use crate::lsq::Extent;
use crate::minzone::MinZone;
use crate::sphere::SphereZone;
use crate::straightness::Line3Zone;
use gagekit_core::{GkError, Result};

/// Minimum and maximum distance of the input points to the reported feature, recomputed
/// from the reported parameters (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Certificate {
    pub min_distance: f64,
    pub max_distance: f64,
}

impl From<Extent> for Certificate {
    fn from(e: Extent) -> Self {
        Self { min_distance: e.min, max_distance: e.max }
    }
}

impl Certificate {
    /// `max - min`.
    pub fn spread(&self) -> f64 {
        self.max_distance - self.min_distance
    }
}

/// The control points of a zone: `inner`, then those of `outer` not among them. Linear
/// time through a hash set of `inner` (a form error near zero makes every point a control
/// point on both sides: the membership scans took 15 s on the 280,500 points of a
/// generated sphere).
pub fn merge_control(inner: &[usize], outer: &[usize]) -> Vec<usize> {
    let mut c = inner.to_vec();
    if inner.len() <= 32 {
        c.extend(outer.iter().filter(|i| !inner.contains(i)));
    } else {
        let seen: rustc_hash::FxHashSet<usize> = inner.iter().copied().collect();
        c.extend(outer.iter().filter(|i| !seen.contains(i)));
    }
    c
}

/// A count setting of a search (particles, iterations, ...) checked to be at least `min`.
pub fn count(shape: &str, name: &str, value: i64, min: i64) -> Result<usize> {
    if value < min {
        return Err(GkError::config(format!("{shape}: {name} must be a positive integer, got {value}")));
    }
    Ok(value as usize)
}

/// A 2-D circle, or a circle in space fitted in its least-squares plane (Sec. 6.2).
#[derive(Debug, Clone, PartialEq)]
pub struct CircleResult {
    pub criterion: FitCriterion,
    /// "exact" (the computational-geometry kernels) or "pso" (the swarm cross-check).
    pub method: &'static str,
    pub n_points: usize,
    /// 2 coordinates, or 3 for a circle in space.
    pub center: Vec<f64>,
    /// The fitted radius; for the minimum zone the mean of `r_in` and `r_out`.
    pub radius: f64,
    /// Smallest / largest distance of the points from `center` (MZ: the zone circles).
    pub r_in: f64,
    pub r_out: f64,
    /// Roundness about `center`: `r_out - r_in`.
    pub form_error: f64,
    pub control_points: Vec<usize>,
    /// Minimum zone only (empty otherwise).
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    pub arc_deg: f64,
    pub ill_posed: bool,
    pub warnings: Vec<String>,
    /// A circle in space: the unit normal of its plane and the largest distance of a
    /// point from that plane.
    pub normal: Option<[f64; 3]>,
    pub out_of_plane: Option<f64>,
}

impl CircleResult {
    /// A complete 2-D fit of `n_points` points by `method`.
    pub fn planar(fit: CircleFit, method: &'static str, n_points: usize) -> Self {
        let arc_deg = fit.arc.to_degrees();
        Self {
            criterion: fit.criterion,
            method,
            n_points,
            center: fit.center.to_vec(),
            radius: fit.radius,
            r_in: fit.r_in,
            r_out: fit.r_out,
            form_error: fit.form_error(),
            control_points: fit.control,
            control_in: fit.control_in,
            control_out: fit.control_out,
            arc_deg,
            ill_posed: fit.ill_posed,
            warnings: words::circle_arc(fit.criterion, arc_deg),
            normal: None,
            out_of_plane: None,
        }
    }

    /// A circle in space fitted by `crit` in the least-squares plane of `n_points` points.
    pub fn in_plane(c: PlaneCircle, crit: FitCriterion, n_points: usize) -> Self {
        let arc_deg = c.arc.to_degrees();
        let mz = crit == FitCriterion::MinZone;
        Self {
            criterion: crit,
            method: "exact",
            n_points,
            center: c.center.to_vec(),
            radius: c.radius,
            r_in: c.extent.min,
            r_out: c.extent.max,
            form_error: c.extent.max - c.extent.min,
            control_points: c.zone.control(),
            control_in: if mz { c.zone.control_in } else { Vec::new() },
            control_out: if mz { c.zone.control_out } else { Vec::new() },
            arc_deg,
            ill_posed: c.ill_posed,
            warnings: words::circle_arc(crit, arc_deg),
            normal: Some(c.normal),
            out_of_plane: Some(c.out_of_plane),
        }
    }
}

/// A fitted line (2-D or 3-D). `certificate`: signed distances (2-D) or distances (3-D)
/// to the line; `form_error`: their spread (2-D), twice the largest (3-D).
#[derive(Debug, Clone, PartialEq)]
pub struct LineResult {
    pub criterion: FitCriterion,
    pub n_points: usize,
    pub point: Vec<f64>,
    pub direction: Vec<f64>,
    pub form_error: f64,
    pub certificate: Certificate,
    pub control_points: Vec<usize>,
    /// The minimum-zone line in space: the tilt (degrees) from the reference axis.
    pub tilt_deg: Option<f64>,
    pub warnings: Vec<String>,
}

impl LineResult {
    /// The least-squares line of `dim`-D points.
    pub fn least_squares(line: crate::lsq::Line, extent: Extent, dim: usize, n_points: usize) -> Self {
        Self {
            criterion: FitCriterion::LeastSquares,
            n_points,
            point: line.point,
            direction: line.direction,
            form_error: extent.line_form_error(dim),
            certificate: extent.into(),
            control_points: Vec::new(),
            tilt_deg: None,
            warnings: Vec::new(),
        }
    }

    /// The minimum-zone 2-D line (two parallel lines of least separation).
    pub fn min_zone_2d(z: MinZone, n_points: usize) -> Self {
        Self {
            criterion: FitCriterion::MinZone,
            n_points,
            control_points: flat_control(&z),
            point: z.point,
            direction: z.direction,
            form_error: z.form_error,
            certificate: z.extent.into(),
            tilt_deg: None,
            warnings: Vec::new(),
        }
    }

    /// The minimum-zone line in space (the thinnest enclosing cylinder), searched within
    /// `max_tilt_deg` of its reference axis.
    pub fn min_zone_3d(z: Line3Zone, max_tilt_deg: f64, n_points: usize) -> Self {
        let warnings = match &z.outside {
            // the zone of a line is the cylinder's diameter
            Some(o) => vec![outside_warning(FitCriterion::MinZone, 2.0 * o.value, o.tilt, max_tilt_deg)],
            None => Vec::new(),
        };
        Self {
            criterion: FitCriterion::MinZone,
            n_points,
            point: z.point.to_vec(),
            direction: z.direction.to_vec(),
            form_error: z.form_error(),
            certificate: z.extent.into(),
            control_points: z.control,
            tilt_deg: Some(z.tilt.to_degrees()),
            warnings,
        }
    }
}

/// The control points of a minimum-zone plane or 2-D line: both bounds, sorted, merged.
fn flat_control(z: &MinZone) -> Vec<usize> {
    let mut control: Vec<usize> = z.control_upper.iter().chain(&z.control_lower).copied().collect();
    control.sort_unstable();
    control.dedup();
    control
}

/// A fitted plane. `certificate`: signed distances to it; `form_error` = max - min.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneResult {
    pub criterion: FitCriterion,
    pub n_points: usize,
    pub point: [f64; 3],
    pub normal: [f64; 3],
    pub form_error: f64,
    pub certificate: Certificate,
    pub control_points: Vec<usize>,
}

impl PlaneResult {
    /// The least-squares plane.
    pub fn least_squares(plane: crate::lsq::Plane, extent: Extent, n_points: usize) -> Self {
        Self {
            criterion: FitCriterion::LeastSquares,
            n_points,
            point: plane.point,
            normal: plane.normal,
            form_error: extent.spread(),
            certificate: extent.into(),
            control_points: Vec::new(),
        }
    }

    /// The minimum-zone plane (flatness).
    pub fn min_zone(z: MinZone, n_points: usize) -> Self {
        let three = |v: &[f64]| [v[0], v[1], v[2]];
        Self {
            criterion: FitCriterion::MinZone,
            n_points,
            control_points: flat_control(&z),
            point: three(&z.point),
            normal: three(&z.normal),
            form_error: z.form_error,
            certificate: z.extent.into(),
        }
    }
}

/// A fitted sphere (3-D) or least-squares circle (2-D). `certificate`: distances to the
/// centre; `form_error` = max - min. The Chebyshev spheres also give the zone
/// (`inner_radius` / `outer_radius`, minimum zone only), `control_points` and
/// `global_bound`, the certificate of the global search (MI, MZ).
#[derive(Debug, Clone, PartialEq)]
pub struct SphereResult {
    pub criterion: FitCriterion,
    pub n_points: usize,
    /// "sphere", or "circle" for the least-squares circle of 2-D points.
    pub shape: &'static str,
    pub center: Vec<f64>,
    pub radius: f64,
    pub form_error: f64,
    pub certificate: Certificate,
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    pub control_points: Option<Vec<usize>>,
    pub global_bound: Option<f64>,
}

impl SphereResult {
    /// The least-squares sphere (circle) of `dim`-D points.
    pub fn least_squares(s: crate::lsq::Sphere, extent: Extent, dim: usize, n_points: usize) -> Self {
        Self {
            criterion: FitCriterion::LeastSquares,
            n_points,
            shape: if dim == 3 { "sphere" } else { "circle" },
            center: s.center,
            radius: s.radius,
            form_error: extent.spread(),
            certificate: extent.into(),
            inner_radius: None,
            outer_radius: None,
            control_points: None,
            global_bound: None,
        }
    }

    /// A Chebyshev sphere of `crit` with its certificate `extent` about its centre.
    pub fn chebyshev(z: SphereZone, crit: FitCriterion, extent: Extent, n_points: usize) -> Self {
        let mz = crit == FitCriterion::MinZone;
        let radius = match crit {
            FitCriterion::MinCircumscribed => z.r_out,
            FitCriterion::MaxInscribed => z.r_in,
            _ => 0.5 * (z.r_in + z.r_out),
        };
        let certificate = Certificate::from(extent);
        Self {
            criterion: crit,
            n_points,
            shape: "sphere",
            center: z.center.to_vec(),
            radius,
            form_error: certificate.spread(),
            certificate,
            inner_radius: mz.then_some(z.r_in),
            outer_radius: mz.then_some(z.r_out),
            control_points: Some(if mz { merge_control(&z.control_in, &z.control_out) } else { z.control_out }),
            global_bound: (crit != FitCriterion::MinCircumscribed).then_some(z.bound),
        }
    }
}

/// A least-squares circle in space (NIST: plane, projection, circle in the plane).
/// `certificate`: in-plane radial distances to the centre; `form_error` = max - min.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle3Result {
    pub n_points: usize,
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
    pub form_error: f64,
    pub certificate: Certificate,
}

impl Circle3Result {
    pub fn least_squares(c: crate::lsq::Circle3, extent: Extent, n_points: usize) -> Self {
        Self {
            n_points,
            center: c.center,
            normal: c.normal,
            radius: c.radius,
            form_error: extent.spread(),
            certificate: extent.into(),
        }
    }
}
