//! `gagekit._core`: the only crate that knows PyO3. It converts numpy arrays to
//! slices, releases the GIL around each kernel, and maps errors and panics to
//! the exception classes of `gagekit.errors`. No algorithm lives here.

mod arrays;
mod cloudio;
mod errors;
mod design;
mod form;
mod gage;
mod gdt;
mod geometry;
mod kinematics;

use pyo3::prelude::*;

/// Panics inside a kernel call: lets the tests check that a panic arrives as
/// `gagekit.errors.InternalError` and never aborts the interpreter.
#[pyfunction]
fn _panic_for_test(py: Python<'_>) -> PyResult<()> {
    errors::run(py, || -> gagekit_core::Result<()> { panic!("deliberate test panic") })
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(_panic_for_test, m)?)?;
    cloudio::register(m)?;
    geometry::register(m)?;
    form::register(m)?;
    kinematics::register(m)?;
    gage::register(m)?;
    gdt::register(m)?;
    design::register(m)?;
    Ok(())
}
