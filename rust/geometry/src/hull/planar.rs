//! Lower-dimensional hulls: points that are exactly collinear or coplanar.

use super::exact::{project, P3};

/// Vertices of the 2-D hull of distinct, exactly coplanar (not all collinear)
/// points, found by Andrew's monotone chain in the coordinate plane where the
/// projection of the points' plane is one-to-one (`axis` is the dropped
/// coordinate; the caller guarantees the projection of a non-degenerate
/// triangle of the set is non-degenerate). Points on hull edges are dropped.
pub fn hull2d(pts: &[P3], ids: &[usize], axis: usize) -> Vec<usize> {
    let q: Vec<[f64; 2]> = ids.iter().map(|&i| project(pts[i], axis)).collect();
    super::chain::hull_2d(&q).into_iter().map(|k| ids[k]).collect()
}
