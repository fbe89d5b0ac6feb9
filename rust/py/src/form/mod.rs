//! `gagekit._core.form`: bindings of gagekit-form (fits.rs: the fits' entry points; results.rs:
//! their public results) and gagekit-profile (filtered.rs: filtered form parameters, ISO 16610-21).

use crate::arrays::rows;
use crate::errors::run;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

mod filtered;
mod fits;
mod results;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // the kernels' constants, defined once in Rust (the Python facades read them here)
    m.add("CIRCLE_MIN_ARC_DEG", gagekit_form::circle::MIN_ARC_DEG)?;
    m.add("CYLINDER_MIN_ARC_DEG", gagekit_form::cylinder::MIN_ARC.to_degrees())?;
    m.add("DEFAULT_MAX_TILT_DEG", gagekit_form::cylinder::DEFAULT_MAX_TILT.to_degrees())?;
    fits::register(m)?;
    filtered::register(m)?;
    Ok(())
}

