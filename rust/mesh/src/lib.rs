//! Triangle meshes for comparing a scan with its CAD model (ISO 1101 profile of a
//! surface, ISO 1660): signed point-to-surface distances and the alignments built on them.
//!
//! Points and vertices are flat row-major buffers (`[x0, y0, z0, x1, ...]`, mm);
//! triangles are flat vertex-index triples. Every function is deterministic: the work is
//! split into fixed chunks of points, so the thread count never changes a result.
//!
//! - [`closest`]: the exact closest point of a triangle (Ericson, *Real-Time Collision
//!   Detection*, Sec. 5.1.5) and the feature (vertex, edge, face) it lies on.
//! - [`bvh`]: a bounding-volume hierarchy over the triangles (binned SAH, built in
//!   parallel) and the nearest-triangle query, with the margin that certifies a later
//!   query near the same point without a search.
//! - [`mesh`]: validated meshes (finite vertices, no degenerate triangles), their
//!   topology (closed, manifold, consistently oriented) and the angle-weighted
//!   pseudonormals of Baerentzen and Aanaes (IEEE TVCG 11(3), 2005) that sign distances.
//! - [`distance`]: signed distances of many points, in parallel.
//! - [`rigid`]: rigid motions (rotation matrix and translation) and their small steps.
//! - [`align`]: best-fit (robust point-to-plane ICP, from principal axes and their flips).
//! - [`minimax`]: the Chebyshev (minimax) alignment, a sequence of LPs (clarabel) with its
//!   certificate.

pub mod align;
pub mod bvh;
pub mod closest;
pub mod distance;
#[doc(hidden)]
pub mod grid;
pub mod mesh;
pub mod minimax;
pub mod rigid;

pub use distance::{Distances, Query};
pub use mesh::{TriMesh, VertexIndex};

#[cfg(test)]
mod tests;
