//! `gagekit._core`: the only crate that knows PyO3. It converts numpy arrays to
//! slices, releases the GIL around each kernel and maps errors and panics to the exception
//! classes of `gagekit.errors` (one wrapper, `errors::run`), and returns typed results
//! (`#[pyclass(frozen, get_all)]`). No algorithm lives here. Test-only bindings live in the
//! submodule `gagekit._core._testing`.

mod arrays;
mod cloud;
mod design;
mod errors;
mod form;
mod gage;
mod gdt;
mod geometry;
mod kinematics;
mod mesh;
mod nc;
mod sigint;

use pyo3::prelude::*;

/// Panics inside a kernel call: lets the tests check that a panic arrives as
/// `gagekit.errors.InternalError` and never aborts the interpreter.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core._testing"))]
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

/// A domain submodule `gagekit._core.NAME`, importable (`import gagekit._core.form`) and not
/// only reachable as an attribute.
fn domain<'py>(parent: &Bound<'py, PyModule>, name: &str) -> PyResult<Bound<'py, PyModule>> {
    let py = parent.py();
    let m = PyModule::new(py, name)?;
    let qualified = format!("gagekit._core.{name}");
    m.setattr("__name__", &qualified)?;
    parent.add_submodule(&m)?;
    py.import("sys")?.getattr("modules")?.set_item(qualified, &m)?;
    Ok(m)
}

/// `gagekit._core`: one submodule per kernel domain, each filled by its own file.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    cloud::register(&domain(m, "cloud")?)?;
    geometry::register(&domain(m, "geometry")?)?;
    form::register(&domain(m, "form")?)?;
    gdt::register(&domain(m, "gdt")?)?;
    gage::register(&domain(m, "gage")?)?;
    kinematics::register(&domain(m, "kinematics")?)?;
    nc::register(&domain(m, "nc")?)?;
    design::register(&domain(m, "design")?)?;
    mesh::register(&domain(m, "mesh")?)?;
    testing(m.py(), m)
}

#[cfg(feature = "stubs")]
/// What the stub generator (`src/bin/stub_gen.rs`) needs: every binding registered by the
/// `gen_stub_*` attributes, written under `root` (default: the repository's `python/`).
pub fn stub_info(root: Option<std::path::PathBuf>) -> pyo3_stub_gen::Result<pyo3_stub_gen::StubInfo> {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let root = root.unwrap_or_else(|| repo.join("python"));
    pyo3_stub_gen::StubInfo::from_project_root("gagekit._core".to_string(), root, true, Default::default())
}
