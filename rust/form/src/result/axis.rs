//! The public results of the axis fits: cylinders (Sec. 6.3) and cones (Sec. 7.2 item 6).

use super::{merge_control, words, Certificate};
use crate::cone::ConeFit;
use crate::criterion::FitCriterion;
use crate::cylinder::{CylinderFit, LeastSquaresCylinder};

/// A fitted cylinder. `radius`: least squares, circumscribed, inscribed; for the minimum
/// zone the mean of `inner_radius` and `outer_radius`. `form_error`: the cylindricity
/// about this axis (the zone width for the minimum zone). `arc_deg`: the angle the points
/// cover around the axis; `warnings`: a short arc, an axis on the search cone's boundary,
/// a better optimum outside it.
#[derive(Debug, Clone, PartialEq)]
pub struct CylinderResult {
    pub criterion: FitCriterion,
    pub n_points: usize,
    pub point: [f64; 3],
    pub direction: [f64; 3],
    /// Polar and azimuthal angle (rad) of `direction` (Tables 6.2, 6.4).
    pub theta: f64,
    pub phi: f64,
    pub radius: f64,
    pub form_error: f64,
    pub certificate: Certificate,
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    pub control_points: Vec<usize>,
    pub iterations: usize,
    pub evaluations: usize,
    pub arc_deg: f64,
    pub ill_posed: bool,
    pub warnings: Vec<String>,
    /// The Chebyshev fits: the tilt (degrees) of the axis from the reference axis.
    pub tilt_deg: Option<f64>,
    pub reference_axis: Option<[f64; 3]>,
    /// With a warm start: whether the global search had to run.
    pub warm_fallback: Option<bool>,
}

/// (theta, phi) of a direction, flipped into the upper half sphere (theta <= pi/2); the
/// norm summed in order, as the package always computed it. An axis whose theta is 0
/// (z within rounding: the x and y parts below about 1e-8) has phi 0: its azimuth is the
/// angle of rounding noise (the bracket's boss, direction (0, -5e-16, 1), reported phi
/// -90 degrees, and -50.7 degrees after a rounding-level change of its fit).
pub fn axis_angles(d: [f64; 3]) -> (f64, f64) {
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut a = [d[0] / n, d[1] / n, d[2] / n];
    if a[2] < 0.0 || (a[2] == 0.0 && (a[1] < 0.0 || (a[1] == 0.0 && a[0] < 0.0))) {
        a = [-a[0], -a[1], -a[2]];
    }
    let theta = a[2].clamp(-1.0, 1.0).acos();
    (theta, if theta == 0.0 { 0.0 } else { a[1].atan2(a[0]) })
}

/// The least-squares cylinder of `n_points` points.
pub fn cylinder_least_squares(c: LeastSquaresCylinder, n_points: usize) -> CylinderResult {
    let arc_deg = c.arc.to_degrees();
    let (theta, phi) = axis_angles(c.direction);
    CylinderResult {
        criterion: FitCriterion::LeastSquares,
        n_points,
        point: c.point,
        direction: c.direction,
        theta,
        phi,
        radius: c.radius,
        form_error: c.form_error(),
        certificate: c.extent.into(),
        inner_radius: None,
        outer_radius: None,
        control_points: Vec::new(),
        iterations: 0,
        evaluations: 0,
        arc_deg,
        ill_posed: false,
        warnings: words::cylinder_arc(FitCriterion::LeastSquares, arc_deg),
        tilt_deg: None,
        reference_axis: None,
        warm_fallback: None,
    }
}

/// A Chebyshev cylinder (MCC, MIC, MZC) searched within `max_tilt_deg` of its reference
/// axis; `warm_fallback` as [`crate::cylinder::fit_near`] returned it.
pub fn cylinder_minimax(r: CylinderFit, max_tilt_deg: f64, warm_fallback: Option<bool>, n_points: usize) -> CylinderResult {
    let crit = r.criterion.fit_criterion();
    let certificate = Certificate::from(r.extent);
    let (radius, form_error, control, inner, outer) = match crit {
        FitCriterion::MinCircumscribed => (r.r_out, certificate.spread(), r.control_out.clone(), None, None),
        FitCriterion::MaxInscribed => (r.r_in, certificate.spread(), r.control_in.clone(), None, None),
        _ => (r.radius, r.r_out - r.r_in, merge_control(&r.control_in, &r.control_out), Some(r.r_in), Some(r.r_out)),
    };
    let arc_deg = r.arc.to_degrees();
    let mut warnings = words::cylinder_arc(crit, arc_deg);
    if r.at_limit {
        warnings.push(words::at_limit(max_tilt_deg));
    }
    if let Some(o) = &r.outside {
        warnings.push(words::outside_warning(crit, o.value, o.tilt, max_tilt_deg));
    }
    CylinderResult {
        criterion: crit,
        n_points,
        point: r.point,
        direction: r.direction,
        theta: r.theta,
        phi: r.phi,
        radius,
        form_error,
        certificate,
        inner_radius: inner,
        outer_radius: outer,
        control_points: control,
        iterations: r.iterations,
        evaluations: r.evaluations,
        arc_deg,
        ill_posed: r.ill_posed,
        warnings,
        tilt_deg: Some(r.tilt.to_degrees()),
        reference_axis: Some(r.reference),
        warm_fallback,
    }
}

/// A fitted cone: `point` the axis point of the reference section, `direction` the axis
/// along which the radius grows, `half_angle` (rad), `radius` at the reference section
/// (minimum zone: the mean of the zone's `inner_radius` and `outer_radius`), `distance`
/// = radius cos(half_angle); `certificate`: min / max signed normal deviation; `gap`
/// (Chebyshev cones): the decrease a linear step of the local search predicts (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct ConeResult {
    pub criterion: FitCriterion,
    pub n_points: usize,
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub apex: [f64; 3],
    pub half_angle: f64,
    pub radius: f64,
    pub distance: f64,
    pub form_error: f64,
    pub certificate: Certificate,
    pub fixed_angle: bool,
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    pub control_points: Vec<usize>,
    pub gap: f64,
    pub evaluations: usize,
}

impl ConeResult {
    /// The full apex angle (rad).
    pub fn apex_angle(&self) -> f64 {
        2.0 * self.half_angle
    }

    /// Radius at axial coordinate `z` (mm along `direction`) from the reference section.
    pub fn radius_at(&self, z: f64) -> f64 {
        self.radius + z * self.half_angle.tan()
    }
}

/// The cone of `n_points` points.
pub fn cone(c: ConeFit, n_points: usize) -> ConeResult {
    let zone = c.criterion == FitCriterion::MinZone;
    ConeResult {
        criterion: c.criterion,
        n_points,
        point: c.point,
        direction: c.direction,
        apex: c.apex,
        half_angle: c.half_angle,
        radius: c.radius,
        distance: c.distance,
        form_error: c.form_error(),
        certificate: c.extent.into(),
        fixed_angle: c.fixed_angle,
        inner_radius: zone.then_some(c.r_in),
        outer_radius: zone.then_some(c.r_out),
        control_points: merge_control(&c.control_in, &c.control_out),
        gap: c.gap,
        evaluations: c.evaluations,
    }
}
