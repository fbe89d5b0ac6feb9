//! Form fitting of circles, cylinders, lines, planes and spheres (Ch. 6).
//!
//! - [`circle`]: 2-D circles: minimum circumscribed, maximum inscribed, minimum zone, least squares.
//! - [`circle_pso`]: 2-D circles by the particle swarm (cross-check of [`circle`]).
//! - [`lsq`]: least-squares lines, planes, spheres, 3-D circles and cylinders.
//! - [`cylinder`]: cylinders by the projection model and the parallel PSO.
//! - [`cone`]: least-squares, minimum-zone, circumscribed and inscribed cones (conicity).
//! - [`minzone`]: minimum-zone planes (flatness) and 2-D lines (straightness) by LP.
//! - [`sphere`]: minimum circumscribed (Welzl), maximum inscribed and minimum-zone spheres.
//! - [`straightness`]: minimum-zone lines in space (the thinnest enclosing cylinder).
//! - [`result`]: the public results of the fits (radius, form error, control points,
//!   certificate, warnings), assembled once from the kernels' solutions.
//! - [`criterion`]: the fit criteria and their names (one table for the package).

pub mod circle;
pub mod circle_pso;
pub mod cone;
pub mod cylinder;
mod lp;
pub mod lsq;
pub mod minzone;
pub mod result;
pub mod sphere;
pub mod straightness;
pub mod criterion;
