//! Virtual-gage linear program with slacks (Ch. 5).
//!
//! * [`problem`]: gages with their point-sets (Eq. 5.4) and the motion set Omega (Eq. 5.2);
//! * [`lp`]: the linearised Eq. 5.11 assembled in CSC form and solved with clarabel;
//! * [`solve`]: re-linearisation about the exact transform until it stops moving,
//!   slacks, infeasible groups (Eq. 5.10) and limiting motion bounds (Sec. 5.2.2);
//! * [`result`]: the public result (gage outcomes by name, T*, limiting bounds, status);
//! * [`transform`]: T = [Rz(alpha) Ry(beta) Rx(gamma) | t] and its derivatives.

pub mod lp;
pub mod problem;
pub mod result;
pub mod solve;
pub mod transform;

pub use lp::{assemble, assemble_checked, solve_linearised, solve_lp, solve_single, Linearisation, LpData, LpSolution};
pub use problem::{extremes, GageSet, Motion};
pub use solve::{infeasible_groups, solve, solve_from, ActiveBound, Options, Solution};
pub use transform::{matrix, MOTION_NAMES};

#[cfg(test)]
mod tests;
