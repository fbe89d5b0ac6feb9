//! `gagekit._core.form`: bindings of gagekit-form (circle.rs: planar circles; solid.rs: 3-D
//! fits) and gagekit-profile (filtered.rs: filtered form parameters, ISO 16610-21).

use crate::arrays::rows;
use crate::errors::run;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

/// Read-only attributes that mirror the fields of the kernel result a pyclass holds in
/// `self.fit`: one getter per named field (converted on access), so the binding never
/// restates the kernel's list of fields and types; `extra` holds the class's other getters.
macro_rules! mirror {
    ($class:ident { $($field:ident),* $(,)? } extra { $($extra:tt)* }) => {
        #[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
        #[pymethods]
        impl $class {
            $(
                #[getter]
                fn $field(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
                    use pyo3::IntoPyObjectExt;
                    self.fit.$field.clone().into_py_any(py)
                }
            )*
            $($extra)*
        }
    };
}

mod circle;
mod filtered;
mod solid;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // the kernels' constants, defined once in Rust (the Python facades read them here)
    m.add("CIRCLE_MIN_ARC_DEG", gagekit_form::circle::MIN_ARC_DEG)?;
    m.add("CYLINDER_MIN_ARC_DEG", gagekit_form::cylinder::MIN_ARC.to_degrees())?;
    m.add("DEFAULT_MAX_TILT_DEG", gagekit_form::cylinder::DEFAULT_MAX_TILT.to_degrees())?;
    circle::register(m)?;
    solid::register(m)?;
    filtered::register(m)?;
    Ok(())
}

