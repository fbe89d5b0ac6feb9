//! Shared pieces of the gagekit kernels: the error type every kernel returns.
//!
//! Kernels never depend on PyO3; the binding crate maps [`ErrorKind`] to the
//! Python exception classes of `gagekit.errors`.

use std::fmt;

/// What went wrong, in the categories the Python exception hierarchy uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// Bad numbers or shapes: NaN, infinities, empty input, wrong sizes.
    InvalidInput,
    /// Geometry too degenerate for the requested computation.
    DegenerateGeometry,
    /// An optimisation problem without a feasible point.
    Infeasible,
    /// A configuration (machine file, gage file, region) is inconsistent.
    Config,
    /// A numerical method did not converge or lost accuracy.
    Numerical,
    /// The caller asked the kernel to stop (Ctrl-C): see [`interrupt`].
    Interrupted,
    /// A file's content is not what its format says (truncated, malformed, wrong kind).
    FileFormat,
    /// A file cannot be opened or read (missing, permissions, an I/O error).
    FileAccess,
}

/// The error every gagekit kernel returns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GkError {
    pub kind: ErrorKind,
    pub message: String,
}

impl GkError {
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Self { kind, message: message.into() }
    }
    pub fn invalid(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::InvalidInput, message)
    }
    pub fn degenerate(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::DegenerateGeometry, message)
    }
    pub fn infeasible(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Infeasible, message)
    }
    pub fn config(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Config, message)
    }
    pub fn numerical(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Numerical, message)
    }
    pub fn file_format(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::FileFormat, message)
    }
    pub fn file_access(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::FileAccess, message)
    }
    pub fn interrupted() -> Self {
        Self::new(ErrorKind::Interrupted, "interrupted")
    }
}

pub mod select;

/// Cooperative cancellation of long kernels (Ctrl-C answered within a second).
///
/// One process-wide flag: whoever handles the interrupt (the Python binding installs a
/// SIGINT action that only stores to this atomic, which is async-signal-safe) calls
/// [`interrupt::request`]; long kernels call [`interrupt::check`] between chunks of work
/// (a few milliseconds each) and return [`ErrorKind::Interrupted`]. A request stops every
/// kernel running in the process at that moment, as Ctrl-C stops the process.
pub mod interrupt {
    use super::{GkError, Result};
    use std::sync::atomic::{AtomicBool, Ordering};

    static REQUESTED: AtomicBool = AtomicBool::new(false);

    /// Ask the running kernels to stop (safe to call from a signal handler).
    pub fn request() {
        REQUESTED.store(true, Ordering::Relaxed);
    }
    /// Forget a request (before a new kernel call starts).
    pub fn clear() {
        REQUESTED.store(false, Ordering::Relaxed);
    }
    /// Whether a stop was requested.
    pub fn requested() -> bool {
        REQUESTED.load(Ordering::Relaxed)
    }
    /// `Err(Interrupted)` once a stop was requested: `interrupt::check()?` between chunks.
    pub fn check() -> Result<()> {
        if requested() {
            Err(GkError::interrupted())
        } else {
            Ok(())
        }
    }

    /// Run `f` (a computation on owned data that cannot check the flag itself, such as a
    /// library's SVD of a tall matrix) on a thread of its own and wait for it, checking the
    /// flag every 10 ms: `Err(Interrupted)` as soon as a stop is requested. The abandoned
    /// computation then finishes in the background and its result is dropped (a CLI
    /// process exits at once). The answer is `f`'s own, the same as a direct call.
    pub fn run_detached<T, F>(f: F) -> Result<T>
    where
        T: Send + 'static,
        F: FnOnce() -> T + Send + 'static,
    {
        let (tx, rx) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("gagekit-detached".into()).spawn(move || {
            let _ = tx.send(f());
        });
        if spawned.is_err() {
            return Err(GkError::numerical("cannot start a thread for the computation"));
        }
        loop {
            check()?;
            match rx.recv_timeout(std::time::Duration::from_millis(10)) {
                Ok(v) => return Ok(v),
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(GkError::numerical("the computation stopped without a result (a panic in its thread)"));
                }
            }
        }
    }
}

impl fmt::Display for GkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for GkError {}

pub type Result<T> = std::result::Result<T, GkError>;

/// Largest coordinate magnitude the machine, gage and mesh kernels accept: 1e9 (mm for
/// positions, the joint unit for commands). A machine tool or a casting spans at most a
/// few 1e4 mm; beyond 1e9 the squares and products of the least-squares and LP
/// kernels lose every significant digit long before they overflow (1e154 squared is
/// already infinite), so such input is refused up front instead of returning NaN.
pub const MAX_COORDINATE: f64 = 1e9;

/// [`check_finite`], then every value within +-[`MAX_COORDINATE`]; the message names
/// the first offending point (0-based row).
pub fn check_coordinates(coords: &[f64], dim: usize, what: &str) -> Result<()> {
    check_finite(coords, dim, what)?;
    if let Some(pos) = coords.iter().position(|v| v.abs() > MAX_COORDINATE) {
        let row = pos / dim;
        return Err(GkError::invalid(format!(
            "{what}: point {row} has a coordinate of magnitude {:e}, beyond the supported {:e} (check the units)",
            coords[pos].abs(),
            MAX_COORDINATE
        )));
    }
    Ok(())
}

/// Check that a flat row-major coordinate buffer holds finite values only.
///
/// `dim` is the number of coordinates per point; the message names the first
/// offending point (0-based row) so a user can find it in the file.
pub fn check_finite(coords: &[f64], dim: usize, what: &str) -> Result<()> {
    if dim == 0 || coords.len() % dim != 0 {
        return Err(GkError::invalid(format!(
            "{what}: expected {dim} coordinates per point, got a buffer of {} values",
            coords.len()
        )));
    }
    // blocks checked without a branch a value (vectorised), the bad value looked for only
    // in a block that holds one
    let bad = coords.chunks(256).position(|c| !c.iter().fold(true, |ok, v| ok & v.is_finite()));
    if let Some(pos) = bad.map(|b| b * 256 + coords[b * 256..].iter().position(|v| !v.is_finite()).unwrap_or(0)) {
        let row = pos / dim;
        return Err(GkError::invalid(format!(
            "{what}: point {row} has a non-finite coordinate ({}); remove NaN/inf values first",
            coords[pos]
        )));
    }
    Ok(())
}

/// Rotation matrix (row-major) of a rotation vector v = axis * angle (rad), by Rodrigues'
/// formula; the identity for v = 0 (the box regions of Sec. 5.4.1).
pub fn rotation_from_vector(rv: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = (rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2]).sqrt();
    if theta == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let (kx, ky, kz) = (rv[0] / theta, rv[1] / theta, rv[2] / theta);
    let (s, c) = theta.sin_cos();
    let v = 1.0 - c;
    [
        [c + kx * kx * v, kx * ky * v - kz * s, kx * kz * v + ky * s],
        [ky * kx * v + kz * s, c + ky * ky * v, ky * kz * v - kx * s],
        [kz * kx * v - ky * s, kz * ky * v + kx * s, c + kz * kz * v],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_check_names_the_row() {
        let e = check_finite(&[0.0, 1.0, 2.0, 3.0, f64::NAN, 5.0], 3, "cloud").unwrap_err();
        assert_eq!(e.kind, ErrorKind::InvalidInput);
        assert!(e.message.contains("point 1"), "{}", e.message);
        assert!(check_finite(&[0.0; 6], 3, "cloud").is_ok());
        assert!(check_finite(&[0.0; 5], 3, "cloud").is_err());
    }
}
