//! `gagekit._core`: the only crate that knows PyO3. It converts numpy arrays to
//! slices, releases the GIL around each kernel and maps errors and panics to the exception
//! classes of `gagekit.errors` (one wrapper, `errors::run`), and returns typed results
//! (`#[pyclass(frozen, get_all)]`). No algorithm lives here. Test-only bindings live in the
//! submodule `gagekit._core._testing`.

mod arrays;
mod ballbar;
mod cloudio;
mod design;
mod errors;
mod form;
mod gage;
mod gdt;
mod geometry;
mod kinematics;
mod mesh;
mod nc;
mod profile;
mod sigint;

use pyo3::prelude::*;

/// Panics inside a kernel call: lets the tests check that a panic arrives as
/// `gagekit.errors.InternalError` and never aborts the interpreter.
#[pyfunction]
fn panic_in_kernel(py: Python<'_>) -> PyResult<()> {
    errors::run(py, || -> gagekit_core::Result<()> { panic!("deliberate test panic") })
}

fn testing(py: Python<'_>, parent: &Bound<'_, PyModule>) -> PyResult<()> {
    let m = PyModule::new(py, "_testing")?;
    m.add_function(wrap_pyfunction!(panic_in_kernel, &m)?)?;
    gage::register_testing(&m)?;
    parent.add_submodule(&m)?;
    // importable as `gagekit._core._testing`, not only reachable as an attribute
    py.import("sys")?.getattr("modules")?.set_item("gagekit._core._testing", &m)?;
    Ok(())
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    cloudio::register(m)?;
    geometry::register(m)?;
    form::register(m)?;
    kinematics::register(m)?;
    ballbar::register(m)?;
    nc::register(m)?;
    gage::register(m)?;
    gdt::register(m)?;
    design::register(m)?;
    mesh::register(m)?;
    profile::register(m)?;
    testing(m.py(), m)
}
