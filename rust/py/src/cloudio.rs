//! Bindings of gagekit-cloudio: ASCII point-cloud reading and writing.

use crate::arrays::rows;
use crate::errors::{invalid, run};
use gagekit_cloudio::{parse_ascii, write_ascii, AsciiOptions};
use gagekit_core::GkError;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;

/// A parsed ASCII point file.
#[pyclass(frozen, get_all, module = "gagekit._core")]
pub struct AsciiCloud {
    /// (n, dim) coordinates.
    points: Py<PyAny>,
    /// Header lines skipped before the first point.
    header_lines: usize,
    /// Number of columns of each data line.
    columns: Vec<usize>,
}

/// Read an ASCII point file.
#[pyfunction]
#[pyo3(signature = (path, dim=3, skip_lines=0))]
fn cloud_read_ascii<'py>(
    py: Python<'py>,
    path: String,
    dim: usize,
    skip_lines: usize,
) -> PyResult<AsciiCloud> {
    let parsed = run(py, || {
        let bytes = std::fs::read(&path)
            .map_err(|e| GkError::invalid(format!("{path}: cannot be read ({e})")))?;
        parse_ascii(&bytes, &AsciiOptions { dim, skip_lines }, &path)
    })?;
    let n = parsed.coords.len() / dim;
    let arr = PyArray1::from_vec(py, parsed.coords).reshape([n, dim])?;
    Ok(AsciiCloud { points: arr.into_any().unbind(), header_lines: parsed.header_lines, columns: parsed.columns })
}

/// Write points (n, d) as ASCII with separator `sep` and an optional header line.
#[pyfunction]
#[pyo3(signature = (path, points, sep=",", header=None))]
fn cloud_write_ascii(
    py: Python<'_>,
    path: String,
    points: PyReadonlyArray2<'_, f64>,
    sep: &str,
    header: Option<String>,
) -> PyResult<()> {
    let dim = points.as_array().ncols();
    let flat = rows(py, &points, dim, "points")?;
    let sep = match sep.as_bytes() {
        [b] => *b,
        _ => return Err(invalid(format!("separator must be one character, got {sep:?}"))),
    };
    run(py, || {
        let text = write_ascii(flat, dim, sep, header.as_deref())?;
        std::fs::write(&path, text).map_err(|e| GkError::invalid(format!("{path}: cannot be written ({e})")))
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<AsciiCloud>()?;
    m.add_function(wrap_pyfunction!(cloud_read_ascii, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_write_ascii, m)?)?;
    Ok(())
}
