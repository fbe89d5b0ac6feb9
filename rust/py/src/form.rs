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
    Ok(())
}
