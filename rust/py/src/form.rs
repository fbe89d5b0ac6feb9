//! Bindings of gagekit-form.

use pyo3::prelude::*;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    register_3d(m)?;
    Ok(())
}

// 3-D fits (lines, planes, spheres, 3-D circles, cylinders) ------------------

use crate::arrays::rows;
use crate::errors::{gagekit_err, run};
use gagekit_form::lsq;
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};

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

fn register_3d(m: &Bound<'_, PyModule>) -> PyResult<()> {
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
