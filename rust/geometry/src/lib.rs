//! Point-set kernels: sampling regions (oriented boxes, Sec. 5.4.1) and the
//! convex-hull filter (Eq. 5.21), and a cell grid for interactive region queries.

pub mod grid;
pub mod hull;
pub mod region;

pub use grid::CellGrid;
pub use hull::{convex_hull_indices, convex_hull_mesh, hull_2d, HullMesh};
pub use region::{classify, rotation_matrix, select, OrientedBox};
