//! `gagekit._core`: the only crate that knows PyO3. It converts numpy arrays to
//! slices, releases the GIL around each kernel, and maps errors and panics to
//! the exception classes of `gagekit.errors`. No algorithm lives here.

mod arrays;
mod cloudio;
mod errors;
mod design;
mod form;
mod gage;
mod geometry;
mod kinematics;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    cloudio::register(m)?;
    geometry::register(m)?;
    form::register(m)?;
    kinematics::register(m)?;
    gage::register(m)?;
    design::register(m)?;
    Ok(())
}
