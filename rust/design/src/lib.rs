//! Optimal experimental design: A-, D-, K-, E-, I-optimal plans with zones (Ch. 4).
//!
//! Generic over the linear model: the caller supplies, for each candidate point,
//! the r x k block of design-matrix rows it would add (Eq. 4.9); the search picks
//! n of them (repeats allowed), each inside its zone (Eq. 4.8), minimising the
//! criterion (Eqs. 4.3-4.5).

// `!(x > 0.0)` deliberately treats NaN as failing; the small-matrix kernels index by hand.
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::needless_range_loop,
    clippy::manual_is_multiple_of
)]

pub mod criteria;
pub mod dense;
pub mod exchange;
mod lanes;
pub mod qmc;

pub use criteria::{design_metrics, information, metrics, Criterion, Metrics};
pub use exchange::{search, Options, Outcome, Problem};
pub use qmc::halton;
