//! Oriented boxes: the sampling volumes of Sec. 5.4.1.
//!
//! A box has a centre, a full size along each of its own axes and a rotation
//! vector (axis times angle, radians) that turns the part axes onto the box
//! axes. A point p is inside when every component of R^T (p - c) lies within
//! half the size (boundary included).

use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Points handled per parallel task; large enough to amortise scheduling.
const CHUNK: usize = 16 * 1024;

#[derive(Debug, Clone, PartialEq)]
pub struct OrientedBox {
    pub center: [f64; 3],
    pub size: [f64; 3],
    /// Rotation vector (axis * angle, rad) of the box axes in the cloud frame.
    pub rotation: [f64; 3],
}

pub use gagekit_core::rotation_from_vector as rotation_matrix;

impl OrientedBox {
    /// Validate the box: finite numbers and a positive size on every axis.
    pub fn validate(&self, name: &str) -> Result<()> {
        for (what, v) in [("center", &self.center), ("size", &self.size), ("rotation", &self.rotation)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(GkError::config(format!("region '{name}': {what} must be finite, got {v:?}")));
            }
        }
        if let Some(axis) = self.size.iter().position(|&s| s <= 0.0) {
            return Err(GkError::config(format!(
                "region '{name}': size along its {} axis is {} but must be positive",
                ["x", "y", "z"][axis],
                self.size[axis]
            )));
        }
        Ok(())
    }

    /// A membership test with the rotation precomputed.
    pub(crate) fn tester(&self) -> impl Fn(&[f64]) -> bool + Sync + '_ {
        let r = rotation_matrix(self.rotation);
        let half = [self.size[0] / 2.0, self.size[1] / 2.0, self.size[2] / 2.0];
        let c = self.center;
        move |p: &[f64]| {
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            // local = R^T d: column k of R dotted with d.
            (0..3).all(|k| {
                let l = r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2];
                l.abs() <= half[k]
            })
        }
    }
}

fn check_points(points: &[f64]) -> Result<()> {
    gagekit_core::check_finite(points, 3, "point cloud")
}

/// Indices (ascending) of the points inside `b`. `points` is row-major (n, 3).
pub fn select(points: &[f64], b: &OrientedBox) -> Result<Vec<usize>> {
    check_points(points)?;
    b.validate("region")?;
    let inside = b.tester();
    let parts: Vec<Vec<usize>> = points
        .par_chunks(3 * CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            chunk
                .chunks_exact(3)
                .enumerate()
                .filter(|(_, p)| inside(p))
                .map(|(i, _)| ci * CHUNK + i)
                .collect()
        })
        .collect();
    Ok(parts.concat())
}

/// For each box, the ascending indices of the points inside it. A point may
/// fall in several boxes. One parallel pass over the points.
pub fn classify(points: &[f64], boxes: &[OrientedBox]) -> Result<Vec<Vec<usize>>> {
    check_points(points)?;
    for (i, b) in boxes.iter().enumerate() {
        b.validate(&format!("#{i}"))?;
    }
    let testers: Vec<_> = boxes.iter().map(|b| b.tester()).collect();
    let nb = boxes.len();
    let parts: Vec<Vec<Vec<usize>>> = points
        .par_chunks(3 * CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut out = vec![Vec::new(); nb];
            for (i, p) in chunk.chunks_exact(3).enumerate() {
                for (k, t) in testers.iter().enumerate() {
                    if t(p) {
                        out[k].push(ci * CHUNK + i);
                    }
                }
            }
            out
        })
        .collect();
    let mut result = vec![Vec::new(); nb];
    for part in parts {
        for (k, v) in part.into_iter().enumerate() {
            result[k].extend(v);
        }
    }
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<f64> {
        let mut pts = Vec::new();
        for i in -10..=10 {
            for j in -10..=10 {
                for k in -10..=10 {
                    pts.extend([i as f64, j as f64, k as f64]);
                }
            }
        }
        pts
    }

    #[test]
    fn axis_aligned_box_counts_boundary() {
        let pts = grid();
        let b = OrientedBox { center: [0.0; 3], size: [4.0, 2.0, 0.5], rotation: [0.0; 3] };
        let idx = select(&pts, &b).unwrap();
        assert_eq!(idx.len(), 5 * 3 * 1);
        for &i in &idx {
            let p = &pts[3 * i..3 * i + 3];
            assert!(p[0].abs() <= 2.0 && p[1].abs() <= 1.0 && p[2] == 0.0);
        }
    }

    #[test]
    fn rotated_box_by_quarter_turn_swaps_axes() {
        let pts = grid();
        let rot = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        let a = OrientedBox { center: [1.0, 2.0, 0.0], size: [6.1, 2.1, 1.0], rotation: rot };
        let b = OrientedBox { center: [1.0, 2.0, 0.0], size: [2.1, 6.1, 1.0], rotation: [0.0; 3] };
        assert_eq!(select(&pts, &a).unwrap(), select(&pts, &b).unwrap());
    }

    #[test]
    fn classify_matches_select() {
        let pts = grid();
        let boxes = vec![
            OrientedBox { center: [0.0; 3], size: [3.0; 3], rotation: [0.1, 0.2, 0.3] },
            OrientedBox { center: [5.0, 5.0, 5.0], size: [4.0, 1.0, 9.0], rotation: [0.0; 3] },
        ];
        let all = classify(&pts, &boxes).unwrap();
        for (b, got) in boxes.iter().zip(all) {
            assert_eq!(select(&pts, b).unwrap(), got);
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let b = OrientedBox { center: [0.0; 3], size: [1.0, 0.0, 1.0], rotation: [0.0; 3] };
        let e = select(&[0.0; 3], &b).unwrap_err();
        assert!(e.message.contains("y axis"), "{}", e.message);
        let good = OrientedBox { center: [0.0; 3], size: [1.0; 3], rotation: [0.0; 3] };
        assert!(select(&[0.0, f64::NAN, 0.0], &good).is_err());
        assert!(select(&[], &good).unwrap().is_empty());
    }

    #[test]
    fn rodrigues_is_orthonormal() {
        let r = rotation_matrix([0.3, -0.2, 0.9]);
        for i in 0..3 {
            for j in 0..3 {
                let d: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }
}
