//! Least-squares (geometric, orthogonal-distance) fits of lines, planes,
//! circles, spheres, 3-D circles and cylinders, as ASME B89.4.10 / the NIST
//! Algorithm Testing System define them.
//!
//! All fits work on centred data (the centroid is subtracted first, in two
//! passes), so coordinates far from the origin (1e6 mm) lose no accuracy.
//! Lines and planes are exact (principal axes of the scatter matrix); circles,
//! spheres and cylinders use Levenberg–Marquardt on the orthogonal distances
//! from algebraic / principal-axis starts and iterate to full double precision.
//!
//! Points are flat row-major buffers: `(n, dim)` with `dim` 2 or 3.
//!
//! One algorithm per file: [`line`](line()), [`plane`](plane()), [`sphere`](sphere()) (2-D
//! circles too), [`circle3`](circle3()), [`cylinder`](cylinder()) and [`cone`](cone()); the
//! shared Levenberg-Marquardt (`lm`), the centring and principal axes (`frame`), the
//! certificates (`extent`), and the Gauss-Newton fits from a nearby fit of a Monte Carlo
//! trial (`warm`).

mod circle3;
mod cone;
mod cylinder;
mod extent;
mod frame;
pub(crate) use frame::add_outer;
mod line;
mod lm;
mod plane;
mod sphere;
mod warm;

use nalgebra::Vector3;

pub use circle3::{circle3, Circle3};
pub use cone::{cone, cone_with, Cone};
pub use cylinder::{cylinder, cylinder_near, Cylinder};
pub use extent::{axis_distances, axis_extent, center_extent, circle3_extent, cone_extent, line_extent, plane_extent, Extent};
pub use frame::{centroid, check_magnitude, negligible, orthonormal_basis, plane_frame, principal_spread, upper, MAX_COORD};
pub use line::{line, Line};
pub use plane::{plane, Plane};
pub use sphere::{sphere, Sphere};
pub use warm::{cylinder_warm, sphere_warm};
