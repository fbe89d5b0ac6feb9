//! Bindings of gagekit-form.

use crate::arrays::{indices, rows};
use crate::errors::run;
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

// circles ------------------------------------------------------------------------------

use gagekit_form::circle;

type CircleOut<'py> = ((f64, f64), f64, Bound<'py, PyArray1<i64>>);
type ZoneOut<'py> = (
    (f64, f64),
    f64,
    f64,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
);

fn circle_out(py: Python<'_>, c: circle::Circle) -> CircleOut<'_> {
    ((c.center[0], c.center[1]), c.radius, indices(py, c.control))
}

/// Minimum circumscribed circle of (n, 2) points: (center, radius, control indices).
#[pyfunction]
fn form_circle_mc<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
) -> PyResult<CircleOut<'py>> {
    let pts = rows(py, &points, 2, "points")?;
    Ok(circle_out(py, run(py, || circle::min_circumscribed(pts))?))
}

/// Maximum inscribed circle within MC (Eq. 6.2): (center, radius, control indices).
#[pyfunction]
fn form_circle_mi<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
) -> PyResult<CircleOut<'py>> {
    let pts = rows(py, &points, 2, "points")?;
    Ok(circle_out(py, run(py, || circle::max_inscribed(pts))?))
}

/// Geometric least-squares circle: (center, radius, control indices).
#[pyfunction]
fn form_circle_lsq<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
) -> PyResult<CircleOut<'py>> {
    let pts = rows(py, &points, 2, "points")?;
    Ok(circle_out(py, run(py, || circle::least_squares(pts))?))
}

/// Minimum zone circle: (center, r_in, r_out, control_in, control_out).
#[pyfunction]
fn form_circle_mz<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
) -> PyResult<ZoneOut<'py>> {
    let pts = rows(py, &points, 2, "points")?;
    let z = run(py, || circle::min_zone(pts))?;
    Ok((
        (z.center[0], z.center[1]),
        z.r_in,
        z.r_out,
        indices(py, z.control_in),
        indices(py, z.control_out),
    ))
}

/// Largest angular gap (rad) of the points seen from `center`.
#[pyfunction]
fn form_circle_angular_gap(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    center: (f64, f64),
) -> PyResult<f64> {
    let pts = rows(py, &points, 2, "points")?;
    run(py, || {
        Ok(circle::max_angular_gap(pts, [center.0, center.1]))
    })
}

fn register_circles(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(form_circle_mc, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_mi, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_mz, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_angular_gap, m)?)?;
    Ok(())
}

// end circles --------------------------------------------------------------------------

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    register_circles(m)?;
    register_3d(m)?;
    Ok(())
}

// 3-D fits (lines, planes, spheres, 3-D circles, cylinders) ------------------

use crate::errors::gagekit_err;
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
        return Err(gagekit_err(
            py,
            "InvalidInputError",
            format!("points: expected an (n, 2) or (n, 3) array, got shape {:?}", points.shape()),
        ));
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

/// Least-squares cylinder: (axis point, axis direction, radius, (min, max) distance to the axis).
#[pyfunction]
#[pyo3(signature = (points, start_axis=None))]
fn form_cylinder_lsq(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    start_axis: Option<[f64; 3]>,
) -> PyResult<([f64; 3], [f64; 3], f64, Ext)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, || {
        let c = lsq::cylinder(pts, start_axis)?;
        Ok((c.point, c.direction, c.radius, ext(lsq::axis_extent(pts, &c.point, &c.direction))))
    })
}

/// Minimum-zone plane (dim 3) or 2-D line (dim 2): (point, normal, direction, width,
/// upper control points, lower control points, LP solves).
#[pyfunction]
#[allow(clippy::type_complexity)]
fn form_min_zone_flat(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<f64>, f64, Vec<usize>, Vec<usize>, usize)> {
    let (pts, dim) = rows23(py, &points)?;
    run(py, || {
        let z = if dim == 3 { gagekit_form::minzone::plane(pts)? } else { gagekit_form::minzone::line2(pts)? };
        Ok((z.point, z.normal, z.direction, z.width, z.control_upper, z.control_lower, z.iterations))
    })
}

/// Certificate of a plane: (min, max) signed distance of 3-D points to it.
#[pyfunction]
fn form_plane_extent(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, point: [f64; 3], normal: [f64; 3]) -> PyResult<Ext> {
    let pts = rows(py, &points, 3, "points")?;
    Ok(ext(lsq::plane_extent(pts, &point, &normal)))
}

/// Certificate of a line: (min, max) signed (2-D) or unsigned (3-D) distance to it.
#[pyfunction]
fn form_line_extent(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, point: Vec<f64>, direction: Vec<f64>) -> PyResult<Ext> {
    let (pts, dim) = rows23(py, &points)?;
    if point.len() != dim || direction.len() != dim {
        return Err(gagekit_err(py, "InvalidInputError", format!("line: point and direction must have {dim} coordinates")));
    }
    Ok(ext(lsq::line_extent(pts, dim, &point, &direction)))
}

/// Certificate of a cylinder axis: (min, max) distance of 3-D points to it.
#[pyfunction]
fn form_axis_extent(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, point: [f64; 3], direction: [f64; 3]) -> PyResult<Ext> {
    let pts = rows(py, &points, 3, "points")?;
    Ok(ext(lsq::axis_extent(pts, &point, &direction)))
}

fn config_err(py: Python<'_>, msg: String) -> PyErr {
    gagekit_err(py, "ConfigError", msg)
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
    fn new(o: gagekit_form::cylinder::Outside) -> Self {
        Self { value: o.value, direction: o.direction, tilt: o.tilt }
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
    use gagekit_form::criterion::FitCriterion as F;
    use gagekit_form::cylinder::{fit, Criterion, Options};
    let pts = rows(py, &points, 3, "points")?;
    let allowed = [F::MinCircumscribed, F::MaxInscribed, F::MinZone];
    let crit = match F::parse_for(criterion, &allowed, "cylinder") {
        Ok(F::MinCircumscribed) => Criterion::MinCircumscribed,
        Ok(F::MaxInscribed) => Criterion::MaxInscribed,
        Ok(_) => Criterion::MinZone,
        Err(e) => return Err(config_err(py, e.message)),
    };
    let opts = Options { seed, particles, max_iterations, stall_iterations, search: search_of(axis, max_tilt), refine_starts, hop_rounds };
    let r = run(py, || fit(pts, crit, &opts))?;
    let name = match crit {
        Criterion::MinCircumscribed => F::MinCircumscribed,
        Criterion::MaxInscribed => F::MaxInscribed,
        Criterion::MinZone => F::MinZone,
    };
    let outside = match r.outside {
        Some(o) => Some(Py::new(py, OutsideResult::new(o))?),
        None => None,
    };
    Ok(CylinderResult {
        criterion: name.name().to_string(),
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
    let outside = match z.outside.clone() {
        Some(o) => Some(Py::new(py, OutsideResult::new(o))?),
        None => None,
    };
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
    use gagekit_form::criterion::FitCriterion as F;
    let allowed: Vec<F> = if allowed.is_empty() {
        F::ALL.to_vec()
    } else {
        allowed.iter().map(|a| a.parse::<F>()).collect::<Result<_, _>>().map_err(|e| config_err(py, e.message))?
    };
    F::parse_for(name, &allowed, shape).map(|c| c.name().to_string()).map_err(|e| config_err(py, e.message))
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
    /// Arc (rad) covered seen from the centre.
    pub arc: f64,
}

/// Circle of (n, 3) points in any pose: least-squares plane, projection, 2-D fit of
/// `criterion` (any name of the criterion table).
#[pyfunction]
fn form_circle_in_plane(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<Circle3Result> {
    use gagekit_form::criterion::FitCriterion as F;
    let pts = rows(py, &points, 3, "points")?;
    let crit = F::parse_for(criterion, &F::ALL, "circle").map_err(|e| config_err(py, e.message))?;
    let c = run(py, || gagekit_form::circle::in_plane::fit(pts, crit))?;
    Ok(Circle3Result {
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
    /// The certified global bound (MZ: no narrower zone; MI: no larger sphere; MC: the
    /// radius), within 1e-9 mm of the value.
    pub bound: f64,
}

/// Minimum circumscribed, maximum inscribed or minimum-zone sphere of (n, 3) points.
#[pyfunction]
fn form_sphere_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<SphereResult> {
    use gagekit_form::criterion::FitCriterion as F;
    use gagekit_form::sphere;
    let pts = rows(py, &points, 3, "points")?;
    let allowed = [F::MinCircumscribed, F::MaxInscribed, F::MinZone];
    let crit = F::parse_for(criterion, &allowed, "sphere").map_err(|e| config_err(py, e.message))?;
    let (z, e) = run(py, || {
        let z = match crit {
            F::MinCircumscribed => sphere::min_circumscribed(pts),
            F::MaxInscribed => sphere::max_inscribed(pts),
            _ => sphere::min_zone(pts),
        }?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok((z, e))
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
        bound: z.bound,
    })
}

/// 2-D circle by the PSO over the centre (Eqs. 6.1, 6.4, 6.5; cross-check of the
/// exact kernels): (center, r_in, r_out, control_in, control_out, iterations, evaluations).
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=2000, stall_iterations=100))]
#[allow(clippy::type_complexity)]
fn form_circle_pso(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
) -> PyResult<((f64, f64), f64, f64, Vec<usize>, Vec<usize>, usize, usize)> {
    use gagekit_form::circle_pso::{fit, Kind};
    let pts = rows(py, &points, 2, "points")?;
    let kind = match criterion {
        "mc" => Kind::MinCircumscribed,
        "mi" => Kind::MaxInscribed,
        "mz" => Kind::MinZone,
        other => return Err(config_err(py, format!("circle (PSO): no swarm fit for criterion {other:?} (mc, mi, mz)"))),
    };
    let settings = gagekit_pso::Settings { seed, particles, max_iterations, stall_iterations, ..Default::default() };
    let r = run(py, || fit(pts, kind, &settings))?;
    let z = r.zone;
    Ok(((z.center[0], z.center[1]), z.r_in, z.r_out, z.control_in, z.control_out, r.iterations, r.evaluations))
}

/// Angle (rad) the points cover around an axis (2 pi minus the largest angular gap).
#[pyfunction]
fn form_cylinder_arc(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, point: [f64; 3], direction: [f64; 3]) -> PyResult<f64> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, || Ok(gagekit_form::cylinder::arc(pts, &point, &direction)))
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
    m.add_function(wrap_pyfunction!(form_cylinder_arc, m)?)?;
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
    m.add_function(wrap_pyfunction!(form_circle_pso, m)?)?;
    m.add_function(wrap_pyfunction!(form_plane_extent, m)?)?;
    m.add_function(wrap_pyfunction!(form_line_extent, m)?)?;
    m.add_function(wrap_pyfunction!(form_axis_extent, m)?)?;
    m.add_function(wrap_pyfunction!(form_min_zone_flat, m)?)?;
    m.add_function(wrap_pyfunction!(form_line_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_plane_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle3d_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_cylinder_lsq, m)?)?;
    Ok(())
}
