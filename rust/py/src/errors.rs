//! Mapping of kernel errors and panics to the exception classes of `gagekit.errors`.

use gagekit_core::{ErrorKind, GkError};
use pyo3::prelude::*;
use pyo3::types::PyType;
use std::panic::{catch_unwind, AssertUnwindSafe};

fn class_name(kind: ErrorKind) -> &'static str {
    match kind {
        ErrorKind::InvalidInput => "InvalidInputError",
        ErrorKind::DegenerateGeometry => "DegenerateGeometryError",
        ErrorKind::Infeasible => "InfeasibleError",
        ErrorKind::Config => "ConfigError",
        ErrorKind::Numerical => "NumericalError",
        ErrorKind::Interrupted => "InternalError", // never reaches here: `run` raises KeyboardInterrupt
    }
}

/// Build a `gagekit.errors.<name>` exception carrying `message`.
pub fn gagekit_err(py: Python<'_>, name: &str, message: String) -> PyErr {
    let ty = py
        .import("gagekit.errors")
        .and_then(|m| m.getattr(name))
        .and_then(|t| t.cast_into::<PyType>().map_err(PyErr::from));
    match ty {
        Ok(t) => PyErr::from_type(t, message),
        Err(e) => e,
    }
}

pub fn to_pyerr(py: Python<'_>, e: GkError) -> PyErr {
    gagekit_err(py, class_name(e.kind), e.message)
}

/// Run a kernel with the GIL released, turning its errors and any panic into
/// gagekit exceptions (a panic becomes `gagekit.errors.InternalError`).
pub fn run<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> gagekit_core::Result<T> + Send,
{
    install_sigint_action();
    gagekit_core::interrupt::clear();
    let out = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match out {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) if e.kind == ErrorKind::Interrupted => {
            // Python's own SIGINT handler has run too: raise what it raises (KeyboardInterrupt)
            py.check_signals()?;
            Err(pyo3::exceptions::PyKeyboardInterrupt::new_err("interrupted"))
        }
        Ok(Err(e)) => Err(to_pyerr(py, e)),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(gagekit_err(
                py,
                "InternalError",
                format!("internal error in a gagekit kernel (please report it): {what}"),
            ))
        }
    }
}

/// Ctrl-C while a kernel runs without the GIL: Python's handler only sets a flag that the
/// interpreter reads when the kernel returns, so a long kernel would ignore it. A SIGINT
/// action (chained before Python's own handler, which still runs) also sets the kernels'
/// cancel flag ([`gagekit_core::interrupt`]), which the long kernels poll between chunks.
fn install_sigint_action() {
    #[cfg(unix)]
    {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            // SAFETY: the action only stores to an atomic (async-signal-safe).
            let _ = unsafe { signal_hook::low_level::register(signal_hook::consts::SIGINT, gagekit_core::interrupt::request) };
        });
    }
}
