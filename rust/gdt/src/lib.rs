//! GD&T zone kernels for inspecting a scan against its drawing (ISO 1101, ISO 5459).
//!
//! Points are flat row-major buffers (`[x0, y0, z0, x1, ...]`, mm). Every kernel is
//! exact in the combinatorial sense (the optimum is attained at a vertex of the convex
//! hull, found by exact predicates) and reports its value recomputed from the reported
//! geometry, so a reported zone always contains the points it was computed from.
//!
//! - [`vec3`]: small 3-D vector helpers (basis of a direction, projections).
//! - [`width2`]: minimum width of a 2-D set: convex hull and rotating calipers.
//! - [`width3`]: width of a 3-D set in a fixed direction, the minimum over directions
//!   perpendicular to an axis (orientation free about a datum), and over a cone of
//!   directions at a basic angle to an axis (angularity).
//! - [`min_width3`]: the minimum width of a 3-D set (flatness; a free datum plane),
//!   exact: hull facets and antipodal edge pairs.
//! - [`datum`]: datum planes (constrained Chebyshev tangent plane on the air side,
//!   ISO 5459) and axes of a fixed direction (maximum inscribed / minimum
//!   circumscribed / least-squares cylinder along a given direction).
//! - [`turn`]: the searches over a turn angle a datum system leaves free: a datum axis
//!   at a basic angle to a datum plane, angularity of an axis, position of centres, axes
//!   and planes with the rotation about z free, the datum shift (exact where the optimum
//!   is an envelope vertex, otherwise grid and golden section to machine precision).
//! - [`plan`]: a whole inspection compiled once and evaluated on many simulated
//!   measurements in one call (the Monte Carlo uncertainty, JCGM 101).
//! - [`size`]: local sizes of features of size (ISO 14405-1): two-point sizes in
//!   sections, widths between two faces, the distance of two convex hulls.
//!
//! Sphericity uses the form crate's certified minimum-zone sphere
//! (`gagekit_form::sphere::min_zone`).

pub mod datum;
pub mod min_width3;
pub mod plan;
pub mod size;
pub mod turn;
pub mod vec3;
pub mod width2;
pub mod width3;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod turn_tests;
