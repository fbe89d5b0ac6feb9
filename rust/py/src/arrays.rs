//! Conversions between numpy arrays and the flat row-major slices the kernels take.

use crate::errors::invalid;
use numpy::{Element, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A contiguous (n, dim) float64 array as a flat slice, or an InvalidInputError.
pub fn rows<'a>(
    _py: Python<'_>,
    arr: &'a PyReadonlyArray2<'_, f64>,
    dim: usize,
    what: &str,
) -> PyResult<&'a [f64]> {
    let shape = arr.shape();
    if shape[1] != dim {
        return Err(invalid(format!("{what}: expected an (n, {dim}) array, got shape {shape:?}")));
    }
    arr.as_slice().map_err(|_| invalid(format!("{what}: array must be C-contiguous")))
}

/// A contiguous 1-D array as a slice, or an InvalidInputError naming `what`.
pub fn values<'a, T: Element>(
    _py: Python<'_>,
    arr: &'a PyReadonlyArray1<'_, T>,
    what: &str,
) -> PyResult<&'a [T]> {
    arr.as_slice().map_err(|_| invalid(format!("{what}: array must be C-contiguous")))
}

/// Indices as a numpy int64 array.
pub fn indices<'py>(py: Python<'py>, idx: Vec<usize>) -> Bound<'py, PyArray1<i64>> {
    PyArray1::from_vec(py, idx.into_iter().map(|i| i as i64).collect())
}

/// A flat row-major buffer as an (n, ncols) numpy array.
pub fn matrix<'py>(py: Python<'py>, v: Vec<f64>, ncols: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    use numpy::PyArrayMethods;
    let nrows = if ncols == 0 { 0 } else { v.len() / ncols };
    PyArray1::from_vec(py, v).reshape([nrows, ncols])
}
