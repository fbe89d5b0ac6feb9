//! Bindings of gagekit-cloudio: ASCII point-cloud reading and writing.

use crate::arrays::rows;
use crate::errors::{gagekit_err, run};
use gagekit_cloudio::{parse_ascii, read_e57, write_ascii, AsciiOptions, PlyFile};
use gagekit_core::GkError;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;

/// Read an ASCII point file: returns (points (n, dim), header_lines, columns).
#[pyfunction]
#[pyo3(signature = (path, dim=3, skip_lines=0))]
fn cloud_read_ascii<'py>(
    py: Python<'py>,
    path: String,
    dim: usize,
    skip_lines: usize,
) -> PyResult<(Bound<'py, PyAny>, usize, Vec<usize>)> {
    let parsed = run(py, || {
        let bytes = std::fs::read(&path)
            .map_err(|e| GkError::invalid(format!("{path}: cannot be read ({e})")))?;
        parse_ascii(&bytes, &AsciiOptions { dim, skip_lines }, &path)
    })?;
    let n = parsed.coords.len() / dim;
    let arr = PyArray1::from_vec(py, parsed.coords).reshape([n, dim])?;
    Ok((arr.into_any(), parsed.header_lines, parsed.columns))
}

/// Read the vertices of a PLY file (memory-mapped): returns (points (n, 3), format name).
/// The points are decoded straight into numpy's allocation (one pass, no copy).
#[pyfunction]
fn cloud_read_ply<'py>(py: Python<'py>, path: String) -> PyResult<(Bound<'py, PyAny>, &'static str)> {
    let file = run(py, || PlyFile::open(std::path::Path::new(&path), &path))?;
    let n = file.vertex_count();
    // SAFETY: uninitialised until `read_into` has written every element; on an error the
    // array is dropped without being seen by Python.
    let arr = unsafe { PyArray2::<f64>::new(py, [n, 3], false) };
    {
        // SAFETY: the array was just created, is C-contiguous and nothing else refers to it.
        let out = unsafe { arr.as_slice_mut() }.map_err(|e| gagekit_err(py, "InternalError", e.to_string()))?;
        run(py, || file.read_into(out))?;
    }
    Ok((arr.into_any(), file.format_name()))
}

/// Read every scan of an E57 file (metres, poses applied): returns
/// (points (n, 3), number of scans, number of invalid points dropped).
#[pyfunction]
fn cloud_read_e57<'py>(py: Python<'py>, path: String) -> PyResult<(Bound<'py, PyAny>, usize, usize)> {
    let p = run(py, || read_e57(std::path::Path::new(&path), &path))?;
    let n = p.coords.len() / 3;
    let arr = PyArray1::from_vec(py, p.coords).reshape([n, 3])?;
    Ok((arr.into_any(), p.scans, p.invalid_dropped))
}

/// Open a PLY file and, when its vertices are stored as exactly `double x, y, z`
/// little-endian with nothing else (gagekit's own layout), return (vertex count, byte
/// offset of the data) after checking sizes and finiteness; otherwise (count, None).
/// Python then maps the file (copy-on-write) as the array: no copy at all.
#[pyfunction]
fn cloud_ply_direct(py: Python<'_>, path: String) -> PyResult<(usize, Option<usize>)> {
    run(py, || {
        let f = PlyFile::open(std::path::Path::new(&path), &path)?;
        Ok((f.vertex_count(), f.direct_f64_offset()?))
    })
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
        _ => return Err(gagekit_err(py, "InvalidInputError", format!("separator must be one character, got {sep:?}"))),
    };
    run(py, || {
        let text = write_ascii(flat, dim, sep, header.as_deref())?;
        std::fs::write(&path, text).map_err(|e| GkError::invalid(format!("{path}: cannot be written ({e})")))
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(cloud_read_ascii, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_write_ascii, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_read_ply, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_ply_direct, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_read_e57, m)?)?;
    Ok(())
}
