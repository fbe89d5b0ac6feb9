//! Conversions between numpy arrays and the flat row-major slices the kernels take.

use crate::errors::gagekit_err;
use numpy::{Element, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A contiguous (n, dim) float64 array as a flat slice, or an InvalidInputError.
pub fn rows<'a>(
    py: Python<'_>,
    arr: &'a PyReadonlyArray2<'_, f64>,
    dim: usize,
    what: &str,
) -> PyResult<&'a [f64]> {
    let shape = arr.shape();
    if shape[1] != dim {
        return Err(gagekit_err(
            py,
            "InvalidInputError",
            format!("{what}: expected an (n, {dim}) array, got shape {shape:?}"),
        ));
    }
    arr.as_slice().map_err(|_| {
        gagekit_err(py, "InvalidInputError", format!("{what}: array must be C-contiguous"))
    })
}

/// A contiguous 1-D array as a slice, or an InvalidInputError naming `what`.
pub fn values<'a, T: Element>(
    py: Python<'_>,
    arr: &'a PyReadonlyArray1<'_, T>,
    what: &str,
) -> PyResult<&'a [T]> {
    arr.as_slice().map_err(|_| {
        gagekit_err(py, "InvalidInputError", format!("{what}: array must be C-contiguous"))
    })
}

/// Indices as a numpy int64 array.
pub fn indices<'py>(py: Python<'py>, idx: Vec<usize>) -> Bound<'py, PyArray1<i64>> {
    PyArray1::from_vec(py, idx.into_iter().map(|i| i as i64).collect())
}
