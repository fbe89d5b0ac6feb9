//! Bindings of gagekit-geometry: regions and the convex-hull filter.

use crate::arrays::{indices, rows};
use crate::errors::run;
use gagekit_geometry::OrientedBox;
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

fn boxes_from(py: Python<'_>, boxes: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<OrientedBox>> {
    let flat = rows(py, boxes, 9, "regions")?;
    Ok(flat
        .chunks_exact(9)
        .map(|b| OrientedBox {
            center: [b[0], b[1], b[2]],
            size: [b[3], b[4], b[5]],
            rotation: [b[6], b[7], b[8]],
        })
        .collect())
}

/// Indices of the points inside each box; `boxes` is (k, 9): centre, size, rotation vector.
#[pyfunction]
fn classify_boxes<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    boxes: PyReadonlyArray2<'py, f64>,
) -> PyResult<Vec<Bound<'py, PyArray1<i64>>>> {
    let pts = rows(py, &points, 3, "points")?;
    let bx = boxes_from(py, &boxes)?;
    let out = run(py, || gagekit_geometry::classify(pts, &bx))?;
    Ok(out.into_iter().map(|v| indices(py, v)).collect())
}

/// Check an oriented box (Sec. 5.4.1): finite centre, size and rotation, a positive size on
/// every axis; ConfigError naming the region otherwise.
#[pyfunction]
fn validate_box(py: Python<'_>, name: &str, center: [f64; 3], size: [f64; 3], rotation: [f64; 3]) -> PyResult<()> {
    run(py, || OrientedBox { center, size, rotation }.validate(name))
}

/// Ascending indices of the convex-hull vertices of an (n, 3) point array (Eq. 5.21).
#[pyfunction]
fn hull_indices<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let pts = rows(py, &points, 3, "points")?;
    let out = run(py, || gagekit_geometry::convex_hull_indices(pts))?;
    Ok(indices(py, out))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(classify_boxes, m)?)?;
    m.add_function(wrap_pyfunction!(hull_indices, m)?)?;
    m.add_function(wrap_pyfunction!(validate_box, m)?)?;
    Ok(())
}
