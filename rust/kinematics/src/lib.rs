//! Machine-tool chains of homogeneous transforms, first-order error model, identification (Ch. 3).
//!
//! - [`chain`]: serial chains of shape and joint transforms (Eq. 3.1), their exact perturbed
//!   forms (Eq. 3.2, 3.3, 3.5) and the analytic first-order design matrix (Eq. 3.13), assembled
//!   in parallel over commands.
//! - [`ident`]: which parameters and combinations the volumetric error reveals (Eq. 3.14),
//!   least squares with covariance (Eq. 3.18), and the closed-form rigid fit of a tracker
//!   frame (Step 1 of Sec. 3.1.5).
//! - [`ridge`]: leave-one-cycle-out errors of the temperature ridge model of thermal tracking
//!   (Sec. 4.3.4), every strength from one eigendecomposition per training set.
//!
//! - [`ballbar`]: circular tests with a ballbar (ISO 230-4:2022): G, F, H and the diagnostics.
//!
//! Linear algebra uses nalgebra: the matrices here are at most a few thousand rows by ~60
//! columns, where nalgebra's SVD takes milliseconds and compiles far faster than faer.

pub mod ballbar;
pub mod chain;
pub mod ident;
pub mod ridge;

pub use chain::{example_machine, Element, Machine, ParamLabel};
pub use ident::{identifiability, lstsq, rigid_fit, Identifiability, Lstsq, RigidFit};
