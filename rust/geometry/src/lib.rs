//! Point-set kernels: sampling regions (oriented boxes, Sec. 5.4.1) and the
//! convex-hull filter (Eq. 5.21).

pub mod region;

pub use region::{classify, rotation_matrix, select, OrientedBox};
