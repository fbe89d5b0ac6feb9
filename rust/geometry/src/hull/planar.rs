//! Lower-dimensional hulls: points that are exactly collinear or coplanar.

use super::exact::{orient2d, project, P3};

/// Vertices of the 2-D hull of distinct, exactly coplanar (not all collinear)
/// points, found by Andrew's monotone chain in the coordinate plane where the
/// projection of the points' plane is one-to-one (`axis` is the dropped
/// coordinate; the caller guarantees the projection of a non-degenerate
/// triangle of the set is non-degenerate). Points on hull edges are dropped.
pub fn hull2d(pts: &[P3], ids: &[usize], axis: usize) -> Vec<usize> {
    let mut q: Vec<([f64; 2], usize)> = ids.iter().map(|&i| (project(pts[i], axis), i)).collect();
    q.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
    let mut hull: Vec<([f64; 2], usize)> = Vec::with_capacity(64);
    for pass in 0..2 {
        let start = hull.len();
        let seq: Box<dyn Iterator<Item = &([f64; 2], usize)>> =
            if pass == 0 { Box::new(q.iter()) } else { Box::new(q.iter().rev()) };
        for &p in seq {
            while hull.len() >= start + 2
                && orient2d(hull[hull.len() - 2].0, hull[hull.len() - 1].0, p.0) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull.into_iter().map(|(_, i)| i).collect()
}
