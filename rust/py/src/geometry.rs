//! Bindings of gagekit-geometry: regions and the convex-hull filter.

use crate::arrays::{indices, rows};
use crate::errors::run;
use crate::arrays::values;
use gagekit_geometry::{CellGrid, OrientedBox};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

pub(crate) fn boxes_from(py: Python<'_>, boxes: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<OrientedBox>> {
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

/// A cell grid over a cloud (built by `grid_build`), holding a reference to the
/// cloud's array: `select` and `count` take a box row (centre, size, rotation
/// vector) and return what `classify_boxes` finds for it. The array must not be
/// changed in place afterwards.
#[pyclass(frozen, module = "gagekit._core")]
pub struct PointGrid {
    grid: CellGrid,
    points: Py<PyArray2<f64>>,
}

fn one_box(py: Python<'_>, row: &PyReadonlyArray1<'_, f64>) -> PyResult<OrientedBox> {
    let b = values(py, row, "region")?;
    if b.len() != 9 {
        return Err(crate::errors::invalid(format!(
            "region: expected 9 numbers (centre, size, rotation), got {}",
            b.len()
        )));
    }
    Ok(OrientedBox { center: [b[0], b[1], b[2]], size: [b[3], b[4], b[5]], rotation: [b[6], b[7], b[8]] })
}

#[pymethods]
impl PointGrid {
    /// Ascending indices of the points inside the box.
    fn select<'py>(&self, py: Python<'py>, row: PyReadonlyArray1<'py, f64>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let arr = self.points.bind(py).readonly();
        let pts = rows(py, &arr, 3, "points")?;
        let b = one_box(py, &row)?;
        let out = run(py, || self.grid.select(pts, &b))?;
        Ok(indices(py, out))
    }

    /// Number of points inside the box.
    fn count(&self, py: Python<'_>, row: PyReadonlyArray1<'_, f64>) -> PyResult<usize> {
        let arr = self.points.bind(py).readonly();
        let pts = rows(py, &arr, 3, "points")?;
        let b = one_box(py, &row)?;
        run(py, || self.grid.count(pts, &b))
    }

    /// Number of points indexed.
    fn __len__(&self) -> usize {
        self.grid.len()
    }

    /// Cells along x, y, z.
    #[getter]
    fn dims(&self) -> (usize, usize, usize) {
        let d = self.grid.dims();
        (d[0], d[1], d[2])
    }

    /// Edge length of a cell (mm).
    #[getter]
    fn cell_size(&self) -> f64 {
        self.grid.cell_size()
    }

    /// Bounding box of the points: ((xmin, ymin, zmin), (xmax, ymax, zmax)).
    #[getter]
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.grid.bounds()
    }
}

/// Index an (n, 3) C-contiguous float64 cloud by grid cells of about `per_cell` points.
#[pyfunction]
fn grid_build(py: Python<'_>, points: Bound<'_, PyArray2<f64>>, per_cell: usize) -> PyResult<PointGrid> {
    let grid = {
        let arr = points.readonly();
        let pts = rows(py, &arr, 3, "points")?;
        run(py, || CellGrid::build(pts, per_cell))?
    };
    Ok(PointGrid { grid, points: points.unbind() })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PointGrid>()?;
    m.add_function(wrap_pyfunction!(grid_build, m)?)?;
    m.add_function(wrap_pyfunction!(classify_boxes, m)?)?;
    m.add_function(wrap_pyfunction!(hull_indices, m)?)?;
    m.add_function(wrap_pyfunction!(validate_box, m)?)?;
    Ok(())
}
