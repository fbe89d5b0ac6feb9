//! Bindings of gagekit-form.

use crate::arrays::rows;
use crate::errors::run;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

// circles ------------------------------------------------------------------------------

use gagekit_form::circle;
use gagekit_form::criterion::FitCriterion;

/// A 2-D circle fit, complete (Sec. 6.2): centre, radius, the zone or certificate, the
/// control points, the arc covered and whether the fit is ill-posed.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct CircleResult {
    /// Canonical criterion name (the package's table).
    pub criterion: String,
    pub center: [f64; 2],
    /// The fitted radius (minimum zone: the mean of `r_in` and `r_out`).
    pub radius: f64,
    /// Minimum zone: inner and outer zone radii; otherwise the certificate, min and max
    /// distance of the points from the centre.
    pub r_in: f64,
    pub r_out: f64,
    /// `r_out - r_in`.
    pub form_error: f64,
    pub control: Vec<usize>,
    /// Minimum zone only: points on the inner / outer circle.
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Arc (rad) covered, seen from `arc_center` (the least-squares centre for an MI of
    /// a short arc), and whether the fit is ill-posed (MI of an arc below 90 degrees).
    pub arc: f64,
    pub arc_center: [f64; 2],
    pub ill_posed: bool,
}

impl From<circle::CircleFit> for CircleResult {
    fn from(f: circle::CircleFit) -> Self {
        Self {
            criterion: f.criterion.name().to_string(),
            center: f.center,
            radius: f.radius,
            r_in: f.r_in,
            r_out: f.r_out,
            form_error: f.form_error(),
            control: f.control,
            control_in: f.control_in,
            control_out: f.control_out,
            arc: f.arc,
            arc_center: f.arc_center,
            ill_posed: f.ill_posed,
        }
    }
}

/// Circle of (n, 2) points by the exact kernels: `criterion` is any name of the
/// criterion table (least squares, MC Eq. 6.1, MI Eq. 6.2, MZ Eqs. 6.5-6.8).
#[pyfunction]
fn form_circle_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<CircleResult> {
    let pts = rows(py, &points, 2, "points")?;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "circle")?;
        circle::fit(pts, crit)
    })
    .map(CircleResult::from)
}

/// 2-D circle by the PSO over the centre (Eqs. 6.1, 6.4, 6.5; a cross-check of the
/// exact kernels) for MC, MI or MZ.
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=2000, stall_iterations=100))]
fn form_circle_pso(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
) -> PyResult<CircleResult> {
    use gagekit_form::circle_pso::{fit, Kind};
    let pts = rows(py, &points, 2, "points")?;
    let settings = gagekit_pso::Settings { seed, particles, max_iterations, stall_iterations, ..Default::default() };
    run(py, || {
        let allowed = [FitCriterion::MinCircumscribed, FitCriterion::MaxInscribed, FitCriterion::MinZone];
        let crit = FitCriterion::parse_for(criterion, &allowed, "circle (PSO)")?;
        let kind = match crit {
            FitCriterion::MinCircumscribed => Kind::MinCircumscribed,
            FitCriterion::MaxInscribed => Kind::MaxInscribed,
            _ => Kind::MinZone,
        };
        circle::from_zone(pts, crit, fit(pts, kind, &settings)?.zone)
    })
    .map(CircleResult::from)
}

fn register_circles(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<CircleResult>()?;
    m.add_function(wrap_pyfunction!(form_circle_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_pso, m)?)?;
    Ok(())
}

// end circles --------------------------------------------------------------------------

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    register_circles(m)?;
    register_3d(m)?;
    Ok(())
}

// 3-D fits (lines, planes, spheres, 3-D circles, cylinders) ------------------

use crate::errors::invalid;
use gagekit_form::lsq;
use numpy::PyUntypedArrayMethods;

type Ext = (f64, f64);

fn ext(e: lsq::Extent) -> Ext {
    (e.min, e.max)
}

/// Points as a flat slice of an (n, 2) or (n, 3) array, with its dimension.
fn rows23<'a>(py: Python<'_>, points: &'a PyReadonlyArray2<'_, f64>) -> PyResult<(&'a [f64], usize)> {
    let dim = points.shape()[1];
    if dim != 2 && dim != 3 {
        return Err(invalid(format!("points: expected an (n, 2) or (n, 3) array, got shape {:?}", points.shape())));
    }
    Ok((rows(py, points, dim, "points")?, dim))
}

/// Least-squares line of 2-D or 3-D points: (point, direction, (min, max) distance).
#[pyfunction]
fn form_line_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<(Vec<f64>, Vec<f64>, Ext)> {
    let (pts, dim) = rows23(py, &points)?;
    run(py, || {
        let l = lsq::line(pts, dim)?;
        let e = lsq::line_extent(pts, dim, &l.point, &l.direction);
        Ok((l.point, l.direction, ext(e)))
    })
}

/// Least-squares plane: (point, normal, (min, max) signed distance).
#[pyfunction]
fn form_plane_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<([f64; 3], [f64; 3], Ext)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, || {
        let p = lsq::plane(pts)?;
        Ok((p.point, p.normal, ext(lsq::plane_extent(pts, &p.point, &p.normal))))
    })
}

/// Least-squares circle (2-D) or sphere (3-D): (centre, radius, (min, max) distance to the centre).
#[pyfunction]
fn form_sphere_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<(Vec<f64>, f64, Ext)> {
    let (pts, dim) = rows23(py, &points)?;
    run(py, || {
        let s = lsq::sphere(pts, dim)?;
        let e = lsq::center_extent(pts, dim, &s.center);
        Ok((s.center, s.radius, ext(e)))
    })
}

/// Least-squares 3-D circle: (centre, normal, radius, (min, max) in-plane radial distance).
#[pyfunction]
fn form_circle3d_lsq(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
) -> PyResult<([f64; 3], [f64; 3], f64, Ext)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, || {
        let c = lsq::circle3(pts)?;
        Ok((c.center, c.normal, c.radius, ext(lsq::circle3_extent(pts, &c.center, &c.normal))))
    })
}

/// A least-squares cylinder, complete: axis, angles, radius, certificate, arc covered.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct LeastSquaresCylinderResult {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub theta: f64,
    pub phi: f64,
    pub radius: f64,
    /// Certificate: min and max 3-D distance of the points to the axis.
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
    /// Arc (rad) the points cover around the axis.
    pub arc: f64,
}

/// Least-squares cylinder of (n, 3) points (from the principal axes and `start_axis`).
#[pyfunction]
#[pyo3(signature = (points, start_axis=None))]
fn form_cylinder_lsq(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    start_axis: Option<[f64; 3]>,
) -> PyResult<LeastSquaresCylinderResult> {
    let pts = rows(py, &points, 3, "points")?;
    let c = run(py, || gagekit_form::cylinder::least_squares(pts, start_axis))?;
    Ok(LeastSquaresCylinderResult {
        point: c.point,
        direction: c.direction,
        theta: c.theta,
        phi: c.phi,
        radius: c.radius,
        min_distance: c.extent.min,
        max_distance: c.extent.max,
        form_error: c.form_error(),
        arc: c.arc,
    })
}

/// A minimum-zone plane (flatness) or 2-D line (straightness), with its certificate.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct MinZoneFlatResult {
    /// A point on the mid-plane (mid-line), its unit normal, and a 2-D line's direction
    /// (empty for planes).
    pub point: Vec<f64>,
    pub normal: Vec<f64>,
    pub direction: Vec<f64>,
    /// Separation of the two bounding planes (lines).
    pub form_error: f64,
    /// Points on the upper and lower bound, sorted and merged.
    pub control: Vec<usize>,
    /// Certificate: min and max signed distance of the points to the mid-plane (mid-line).
    pub min_distance: f64,
    pub max_distance: f64,
    /// Linear programs solved.
    pub iterations: usize,
}

/// Minimum-zone plane of (n, 3) points or line of (n, 2) points (LP, then the exact
/// solve of the active constraints).
#[pyfunction]
fn form_min_zone_flat(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<MinZoneFlatResult> {
    let (pts, dim) = rows23(py, &points)?;
    let z = run(py, || if dim == 3 { gagekit_form::minzone::plane(pts) } else { gagekit_form::minzone::line2(pts) })?;
    let mut control: Vec<usize> = z.control_upper.iter().chain(&z.control_lower).copied().collect();
    control.sort_unstable();
    control.dedup();
    Ok(MinZoneFlatResult {
        point: z.point,
        normal: z.normal,
        direction: z.direction,
        form_error: z.form_error,
        control,
        min_distance: z.extent.min,
        max_distance: z.extent.max,
        iterations: z.iterations,
    })
}

/// A better optimum of the free search outside the search cone.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct OutsideResult {
    /// Its radius (MCC, MIC) or zone width (MZC), mm.
    pub value: f64,
    pub direction: [f64; 3],
    /// Tilt (rad) of its axis from the reference axis.
    pub tilt: f64,
}

impl OutsideResult {
    /// The Python object of a kernel's optional better optimum outside the cone.
    fn wrap(py: Python<'_>, o: Option<gagekit_form::cylinder::Outside>) -> PyResult<Option<Py<Self>>> {
        o.map(|o| Py::new(py, Self { value: o.value, direction: o.direction, tilt: o.tilt })).transpose()
    }
}

/// A minimax cylinder (Sec. 6.3): axis, radii, control points, certificate, search
/// diagnostics (angles rad, lengths mm).
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct CylinderResult {
    pub criterion: String,
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub theta: f64,
    pub phi: f64,
    pub radius: f64,
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max 3-D distance of the points to the axis.
    pub min_distance: f64,
    pub max_distance: f64,
    pub iterations: usize,
    pub evaluations: usize,
    /// Reference axis (nominal or least squares) and the tilt (rad) from it.
    pub reference: [f64; 3],
    pub tilt: f64,
    pub outside: Option<Py<OutsideResult>>,
    /// The axis lies on the boundary of the search cone.
    pub at_limit: bool,
    /// Arc (rad) covered around the axis, ill-posed flag (MIC below 90 degrees).
    pub arc: f64,
    pub ill_posed: bool,
    /// The least-squares axis (point, direction), if it exists.
    pub lsq_axis: Option<([f64; 3], [f64; 3])>,
}

fn search_of(axis: Option<[f64; 3]>, max_tilt: f64) -> gagekit_form::cylinder::Search {
    gagekit_form::cylinder::Search { axis, max_tilt }
}

/// Minimax cylinder by the projection model + PSO (Sec. 6.3). `criterion`: any name of
/// the criterion table but least squares; the axis is searched within `max_tilt` (rad,
/// [0, pi/2]) of `axis` (default: the least-squares axis).
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=300, stall_iterations=6, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT, refine_starts=8, hop_rounds=3))]
#[allow(clippy::too_many_arguments)]
fn form_cylinder_fit(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
    refine_starts: usize,
    hop_rounds: usize,
) -> PyResult<CylinderResult> {
    use gagekit_form::cylinder::{fit, Criterion, Options};
    let pts = rows(py, &points, 3, "points")?;
    let opts = Options { seed, particles, max_iterations, stall_iterations, search: search_of(axis, max_tilt), refine_starts, hop_rounds };
    let r = run(py, || {
        let allowed = [FitCriterion::MinCircumscribed, FitCriterion::MaxInscribed, FitCriterion::MinZone];
        let crit = FitCriterion::parse_for(criterion, &allowed, "cylinder")?;
        fit(pts, Criterion::from_fit(crit).unwrap_or(Criterion::MinZone), &opts)
    })?;
    let outside = OutsideResult::wrap(py, r.outside)?;
    Ok(CylinderResult {
        criterion: r.criterion.fit_criterion().name().to_string(),
        point: r.point,
        direction: r.direction,
        theta: r.theta,
        phi: r.phi,
        radius: r.radius,
        r_in: r.r_in,
        r_out: r.r_out,
        control_in: r.control_in,
        control_out: r.control_out,
        min_distance: r.extent.min,
        max_distance: r.extent.max,
        iterations: r.iterations,
        evaluations: r.evaluations,
        reference: r.reference,
        tilt: r.tilt,
        outside,
        at_limit: r.at_limit,
        arc: r.arc,
        ill_posed: r.ill_posed,
        lsq_axis: r.lsq_axis,
    })
}

/// A minimum-zone line in space (straightness): the thinnest enclosing cylinder.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct Line3Result {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    /// Certificate: min and max distance of the points to the line.
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
    pub control: Vec<usize>,
    pub reference: [f64; 3],
    pub tilt: f64,
    pub outside: Option<Py<OutsideResult>>,
}

/// Minimum-zone 3-D line, searched within `max_tilt` (rad) of `axis` (default: the
/// least-squares direction).
#[pyfunction]
#[pyo3(signature = (points, seed=0, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT))]
fn form_line3_min_zone(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    seed: u64,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
) -> PyResult<Line3Result> {
    use gagekit_form::cylinder::Options;
    let pts = rows(py, &points, 3, "points")?;
    let opts = Options { seed, stall_iterations: 50, refine_starts: 4, search: search_of(axis, max_tilt), ..Options::default() };
    let z = run(py, || gagekit_form::straightness::line3(pts, &opts))?;
    let outside = OutsideResult::wrap(py, z.outside.clone())?;
    Ok(Line3Result {
        point: z.point,
        direction: z.direction,
        min_distance: z.extent.min,
        max_distance: z.extent.max,
        form_error: z.form_error(),
        control: z.control,
        reference: z.reference,
        tilt: z.tilt,
        outside,
    })
}

/// The canonical name of a fit criterion (any alias of the package's one table), or a
/// ConfigError listing the names `allowed` (all when empty) for `shape`.
#[pyfunction]
#[pyo3(signature = (name, allowed=Vec::new(), shape="fit"))]
fn form_criterion(py: Python<'_>, name: &str, allowed: Vec<String>, shape: &str) -> PyResult<String> {
    run(py, || {
        let allowed: Vec<FitCriterion> = if allowed.is_empty() {
            FitCriterion::ALL.to_vec()
        } else {
            allowed.iter().map(|a| a.parse::<FitCriterion>()).collect::<Result<_, _>>()?
        };
        FitCriterion::parse_for(name, &allowed, shape).map(|c| c.name().to_string())
    })
}

/// The criterion table: (alias, canonical name, circle code) for every accepted spelling.
#[pyfunction]
fn form_criteria() -> Vec<(&'static str, &'static str, &'static str)> {
    gagekit_form::criterion::ALIASES.iter().map(|(k, c)| (*k, c.name(), c.code())).collect()
}

/// A circle in space (any pose): the 2-D fit of a criterion in the least-squares plane.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct Circle3Result {
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max in-plane distance of the points to the centre.
    pub min_distance: f64,
    pub max_distance: f64,
    /// Largest distance of a point from the circle's plane.
    pub out_of_plane: f64,
    /// Points that fix the fit (minimum zone: `control_in`, then the rest of `control_out`).
    pub control: Vec<usize>,
    /// Arc (rad) covered seen from the centre (the least-squares centre for an MI of a
    /// short arc), and whether the fit is ill-posed (MI of an arc below 90 degrees).
    pub arc: f64,
    pub ill_posed: bool,
}

/// Circle of (n, 3) points in any pose: least-squares plane, projection, 2-D fit of
/// `criterion` (any name of the criterion table).
#[pyfunction]
fn form_circle_in_plane(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<Circle3Result> {
    let pts = rows(py, &points, 3, "points")?;
    let c = run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "circle")?;
        gagekit_form::circle::in_plane::fit(pts, crit)
    })?;
    Ok(Circle3Result {
        control: c.zone.control(),
        center: c.center,
        normal: c.normal,
        radius: c.radius,
        r_in: c.zone.r_in,
        r_out: c.zone.r_out,
        control_in: c.zone.control_in,
        control_out: c.zone.control_out,
        min_distance: c.extent.min,
        max_distance: c.extent.max,
        out_of_plane: c.out_of_plane,
        arc: c.arc,
        ill_posed: c.ill_posed,
    })
}

/// A Chebyshev sphere: centre, radii, control points and certificate.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct SphereResult {
    pub criterion: String,
    pub center: [f64; 3],
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max distance of the points to the centre.
    pub min_distance: f64,
    pub max_distance: f64,
    /// Linear programs of the MI / MZ searches (0 for MC).
    pub iterations: usize,
}

/// Minimum circumscribed, maximum inscribed or minimum-zone sphere of (n, 3) points.
#[pyfunction]
fn form_sphere_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<SphereResult> {
    use gagekit_form::sphere;
    use FitCriterion as F;
    let pts = rows(py, &points, 3, "points")?;
    let (crit, z, e) = run(py, || {
        let crit = F::parse_for(criterion, &[F::MinCircumscribed, F::MaxInscribed, F::MinZone], "sphere")?;
        let z = match crit {
            F::MinCircumscribed => sphere::min_circumscribed(pts),
            F::MaxInscribed => sphere::max_inscribed(pts),
            _ => sphere::min_zone(pts),
        }?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok((crit, z, e))
    })?;
    Ok(SphereResult {
        criterion: crit.name().to_string(),
        center: z.center,
        r_in: z.r_in,
        r_out: z.r_out,
        control_in: z.control_in,
        control_out: z.control_out,
        min_distance: e.min,
        max_distance: e.max,
        iterations: z.iterations,
    })
}

/// Least-squares cone: (axis point, axis direction, distance from the point to the
/// surface, half apex angle (rad), (min, max) signed orthogonal distance of the points).
#[pyfunction]
fn form_cone_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<([f64; 3], [f64; 3], f64, f64, Ext)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, || {
        let c = lsq::cone(pts)?;
        let e = lsq::cone_extent(pts, &c);
        Ok((c.point, c.direction, c.distance, c.half_angle, ext(e)))
    })
}

fn register_3d(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(form_cone_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_cylinder_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_line3_min_zone, m)?)?;
    m.add_function(wrap_pyfunction!(form_criterion, m)?)?;
    m.add_function(wrap_pyfunction!(form_criteria, m)?)?;
    m.add_class::<CylinderResult>()?;
    m.add_class::<OutsideResult>()?;
    m.add_class::<Line3Result>()?;
    m.add_function(wrap_pyfunction!(form_circle_in_plane, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_fit, m)?)?;
    m.add_class::<Circle3Result>()?;
    m.add_class::<SphereResult>()?;
    m.add_class::<LeastSquaresCylinderResult>()?;
    m.add_class::<MinZoneFlatResult>()?;
    m.add_function(wrap_pyfunction!(form_min_zone_flat, m)?)?;
    m.add_function(wrap_pyfunction!(form_line_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_plane_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle3d_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_cylinder_lsq, m)?)?;
    Ok(())
}
