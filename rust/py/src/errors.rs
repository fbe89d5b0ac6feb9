//! Mapping of kernel errors and panics to the exception classes of `gagekit.errors`, and the
//! one wrapper every binding's kernel call goes through ([`run`]).
//!
//! The classes are imported once per interpreter (`import_exception!` caches the type object)
//! and constructed lazily: building an error does not need the GIL.

use gagekit_core::{ErrorKind, GkError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};

pyo3::import_exception!(gagekit.errors, InvalidInputError);
pyo3::import_exception!(gagekit.errors, DegenerateGeometryError);
pyo3::import_exception!(gagekit.errors, InfeasibleError);
pyo3::import_exception!(gagekit.errors, ConfigError);
pyo3::import_exception!(gagekit.errors, NumericalError);
pyo3::import_exception!(gagekit.errors, InternalError);
pyo3::import_exception!(gagekit.errors, FileFormatError);
pyo3::import_exception!(gagekit.errors, FileAccessError);

/// The gagekit exception of a kernel error.
pub fn to_pyerr(e: GkError) -> PyErr {
    let m = e.message;
    match e.kind {
        ErrorKind::InvalidInput => InvalidInputError::new_err(m),
        ErrorKind::DegenerateGeometry => DegenerateGeometryError::new_err(m),
        ErrorKind::Infeasible => InfeasibleError::new_err(m),
        ErrorKind::Config => ConfigError::new_err(m),
        ErrorKind::Numerical => NumericalError::new_err(m),
        ErrorKind::FileFormat => FileFormatError::new_err(m),
        ErrorKind::FileAccess => FileAccessError::new_err(m),
        // `run` turns an interrupted kernel into KeyboardInterrupt before it gets here
        ErrorKind::Interrupted => pyo3::exceptions::PyKeyboardInterrupt::new_err(m),
    }
}

/// An `InvalidInputError` raised by the conversion layer (shapes, contiguity).
pub fn invalid(message: impl Into<String>) -> PyErr {
    to_pyerr(GkError::invalid(message))
}

/// How many kernel calls run at this moment, in all threads.
static RUNNING: AtomicUsize = AtomicUsize::new(0);

/// One kernel call in progress (counted in [`RUNNING`] until dropped). The first call to
/// start while none runs forgets an earlier stop request; a call that starts while another
/// runs leaves it set, so that a Ctrl-C meant for the running call is not swallowed by a
/// call another thread starts (the request stops every running kernel, this one too).
struct Running;

impl Running {
    fn enter() -> Self {
        if RUNNING.fetch_add(1, Ordering::SeqCst) == 0 {
            gagekit_core::interrupt::clear();
        }
        Running
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        RUNNING.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Run a kernel with the GIL released, turning its errors and any panic into
/// gagekit exceptions (a panic becomes `gagekit.errors.InternalError`).
///
/// Ctrl-C: the SIGINT action of [`crate::sigint`] stops the kernel at its next check
/// ([`gagekit_core::interrupt`]); then Python's handler runs here. If it raises
/// (KeyboardInterrupt, or a user's handler raising its own exception), that is what
/// this call raises. If it returns (a handler that only takes note), the kernel runs
/// again from the start: kernels are deterministic, so the answer is the same as if
/// the signal had not come.
pub fn run<T, F>(py: Python<'_>, mut f: F) -> PyResult<T>
where
    T: Send,
    F: FnMut() -> gagekit_core::Result<T> + Send,
{
    loop {
        crate::sigint::ensure();
        let running = Running::enter();
        py.check_signals()?; // a Ctrl-C that came just before the clear
        let outcome = py.detach(|| catch_unwind(AssertUnwindSafe(&mut f)));
        drop(running);
        match outcome {
            Ok(Ok(v)) => return Ok(v),
            Ok(Err(e)) if e.kind == ErrorKind::Interrupted => {
                // Python's handler for the SIGINT that stopped the kernel
                py.check_signals()?;
                // the handler returned (or this is not the main thread, whose handler
                // raises there): the run goes on once the request is forgotten, which the
                // first call to start while none runs does (this one, if every call the
                // request stopped has ended). The wait is without the GIL, which the other
                // calls need to end.
                py.detach(|| {
                    while RUNNING.load(Ordering::SeqCst) != 0 && gagekit_core::interrupt::requested() {
                        std::thread::sleep(std::time::Duration::from_millis(1));
                    }
                });
                continue;
            }
            Ok(Err(e)) => return Err(to_pyerr(e)),
            Err(payload) => {
                let what = payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".to_string());
                return Err(InternalError::new_err(format!(
                    "internal error in a gagekit kernel (please report it): {what}"
                )));
            }
        }
    }
}
