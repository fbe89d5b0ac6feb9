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

/// Minimax cylinder by the projection model + PSO (Sec. 6.3). `criterion` is "mcc",
/// "mic" or "mzc"; `half_angle` (rad) restricts the search to a cone around `axis`
/// (or around the least-squares axis when `axis` is None); no `half_angle`: the
/// half sphere. Returns a dict of the fit.
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=300, stall_iterations=6, axis=None, half_angle=None, refine_starts=8, hop_rounds=3))]
#[allow(clippy::too_many_arguments)]
fn form_cylinder_fit<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
    axis: Option<[f64; 3]>,
    half_angle: Option<f64>,
    refine_starts: usize,
    hop_rounds: usize,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    use gagekit_form::cylinder::{fit, Criterion, Options, Search};
    let pts = rows(py, &points, 3, "points")?;
    let crit = match criterion {
        "mcc" => Criterion::MinCircumscribed,
        "mic" => Criterion::MaxInscribed,
        "mzc" => Criterion::MinZone,
        other => return Err(config_err(py, format!("cylinder: unknown criterion {other:?} (mcc, mic, mzc)"))),
    };
    let search = match (axis, half_angle) {
        (_, None) => Search::HalfSphere,
        (Some(a), Some(h)) => Search::Cone { axis: a, half_angle: h },
        (None, Some(h)) => Search::AroundLeastSquares { half_angle: h },
    };
    let opts = Options { seed, particles, max_iterations, stall_iterations, search, refine_starts, hop_rounds };
    let r = run(py, || fit(pts, crit, &opts))?;
    let d = pyo3::types::PyDict::new(py);
    d.set_item("point", r.point)?;
    d.set_item("direction", r.direction)?;
    d.set_item("theta", r.theta)?;
    d.set_item("phi", r.phi)?;
    d.set_item("radius", r.radius)?;
    d.set_item("r_in", r.r_in)?;
    d.set_item("r_out", r.r_out)?;
    d.set_item("control_in", r.control_in)?;
    d.set_item("control_out", r.control_out)?;
    d.set_item("min_distance", r.extent.min)?;
    d.set_item("max_distance", r.extent.max)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("evaluations", r.evaluations)?;
    Ok(d)
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
