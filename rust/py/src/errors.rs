//! Mapping of kernel errors and panics to the exception classes of `gagekit.errors`, and the
//! one wrapper every binding's kernel call goes through ([`run`]).
//!
//! The classes are imported once per interpreter (`import_exception!` caches the type object)
//! and constructed lazily: building an error does not need the GIL.

use gagekit_core::{ErrorKind, GkError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

pyo3::import_exception!(gagekit.errors, InvalidInputError);
pyo3::import_exception!(gagekit.errors, DegenerateGeometryError);
pyo3::import_exception!(gagekit.errors, InfeasibleError);
pyo3::import_exception!(gagekit.errors, ConfigError);
pyo3::import_exception!(gagekit.errors, NumericalError);
pyo3::import_exception!(gagekit.errors, InternalError);

/// The gagekit exception of a kernel error.
pub fn to_pyerr(e: GkError) -> PyErr {
    let m = e.message;
    match e.kind {
        ErrorKind::InvalidInput => InvalidInputError::new_err(m),
        ErrorKind::DegenerateGeometry => DegenerateGeometryError::new_err(m),
        ErrorKind::Infeasible => InfeasibleError::new_err(m),
        ErrorKind::Config => ConfigError::new_err(m),
        ErrorKind::Numerical => NumericalError::new_err(m),
        // `run` turns an interrupted kernel into KeyboardInterrupt before it gets here
        ErrorKind::Interrupted => pyo3::exceptions::PyKeyboardInterrupt::new_err(m),
    }
}

/// An `InvalidInputError` raised by the conversion layer (shapes, contiguity).
pub fn invalid(message: impl Into<String>) -> PyErr {
    to_pyerr(GkError::invalid(message))
}

/// Build a `gagekit.errors.<name>` exception carrying `message` (by class name; kept for the
/// form bindings: the other bindings use [`to_pyerr`] / [`invalid`]).
pub fn gagekit_err(_py: Python<'_>, name: &str, message: String) -> PyErr {
    match name {
        "InvalidInputError" => InvalidInputError::new_err(message),
        "DegenerateGeometryError" => DegenerateGeometryError::new_err(message),
        "InfeasibleError" => InfeasibleError::new_err(message),
        "ConfigError" => ConfigError::new_err(message),
        "NumericalError" => NumericalError::new_err(message),
        _ => InternalError::new_err(message),
    }
}

/// Run a kernel with the GIL released, turning its errors and any panic into
/// gagekit exceptions (a panic becomes `gagekit.errors.InternalError`).
pub fn run<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> gagekit_core::Result<T> + Send,
{
    install_sigint_action(py);
    gagekit_core::interrupt::clear();
    match py.detach(|| catch_unwind(AssertUnwindSafe(f))) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) if e.kind == ErrorKind::Interrupted => {
            // Python's own SIGINT handler has run too: raise what it raises (KeyboardInterrupt)
            py.check_signals()?;
            Err(pyo3::exceptions::PyKeyboardInterrupt::new_err("interrupted"))
        }
        Ok(Err(e)) => Err(to_pyerr(e)),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(InternalError::new_err(format!(
                "internal error in a gagekit kernel (please report it): {what}"
            )))
        }
    }
}

/// Ctrl-C while a kernel runs without the GIL: Python's handler only sets a flag that the
/// interpreter reads when the kernel returns, so a long kernel would ignore it. A SIGINT
/// action (chained before Python's own handler, which still runs) also sets the kernels'
/// cancel flag ([`gagekit_core::interrupt`]), which the long kernels poll between chunks.
fn install_sigint_action(py: Python<'_>) {
    #[cfg(unix)]
    {
        static ONCE: std::sync::Once = std::sync::Once::new();
        if ONCE.is_completed() || !python_handles_sigint(py) {
            return; // SIGINT ignored or left to the system (nohup, background jobs): keep it so
        }
        ONCE.call_once(|| {
            // SAFETY: the action only stores to an atomic (async-signal-safe).
            let _ = unsafe { signal_hook::low_level::register(signal_hook::consts::SIGINT, gagekit_core::interrupt::request) };
        });
    }
}

/// Whether Python has a handler of its own for SIGINT (its default KeyboardInterrupt or a
/// user's function), rather than SIG_IGN or SIG_DFL.
#[cfg(unix)]
fn python_handles_sigint(py: Python<'_>) -> bool {
    let check = || -> PyResult<bool> {
        let signal = py.import("signal")?;
        let handler = signal.getattr("getsignal")?.call1((signal.getattr("SIGINT")?,))?;
        Ok(handler.is_callable())
    };
    check().unwrap_or(false)
}
