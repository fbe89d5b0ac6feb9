//! Spheres by the Chebyshev criteria (issue 13 part 4), next to the least-squares
//! sphere of [`crate::lsq::sphere`]: minimum circumscribed (exact, Welzl's algorithm
//! in 3-D: the 3-D form of Eq. 6.1), maximum inscribed within it (the 3-D form of
//! Eq. 6.2) and minimum zone (sphericity: two concentric spheres of least radial
//! separation, the 3-D form of Eq. 6.5). Every result names its control points and
//! carries its certificate: min and max distance of the points to the reported centre.
//!
//! - `mc`: Welzl (move-to-front), exact, expected linear time.
//! - `global`: MI and MZ globally, by a certified branch and bound over the centre
//!   (interval bounds of the point distances on cubes of centres), to
//!   [`global_tolerance`] (1e-9 mm); the bound it proves is reported (`bound`). On more
//!   than 4096 points it runs on an active subset (the points nearest to and farthest
//!   from the centre), grown until the subset's certified centre is within the
//!   tolerance of its bound on all points (a subset's bound holds for the whole set).
//! - `minimax`: the exact local step from the branch and bound's best centre:
//!   sequential linear programming with a trust region on the centre and radii (the 3-D
//!   analogue of the cylinders' SLP); each step is a 4- or 5-variable LP ([`crate::lp`]),
//!   and the steps stop where the LP predicts no decrease (the Chebyshev conditions
//!   hold at the control points).

mod global;
mod mc;
mod minimax;

pub use mc::min_circumscribed;
pub use minimax::{max_inscribed, min_zone};

/// A sphere as a zone: centre, inner and outer radius (equal for MC and MI) and the
/// points on each.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereZone {
    pub center: [f64; 3],
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Linear programs of the final local step (MI, MZ) or 0 (MC).
    pub iterations: usize,
    /// The certificate of the global search: MZ, no centre in the searched cube gives a
    /// zone narrower than `bound`; MI, no inscribed sphere larger than `bound`; MC, the
    /// radius itself (Welzl is exact). Within [`global_tolerance`] of the value.
    pub bound: f64,
    /// Cubes of centres the branch and bound evaluated (0 for MC).
    pub cubes: usize,
}

/// The tolerance to which the MI and MZ spheres are certified global: 1e-9 mm, or
/// 1e-13 of the part's size when larger.
pub fn global_tolerance(size: f64) -> f64 {
    global::tolerance(size)
}

/// Distance between 3-D points.
#[inline]
fn dist(a: &[f64], b: &[f64; 3]) -> f64 {
    let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    (x * x + y * y + z * z).sqrt()
}

/// Min and max distance of the points to `c`, with the indices within `tol` of each.
fn extremes(pts: &[f64], c: &[f64; 3], tol: f64) -> (f64, f64, Vec<usize>, Vec<usize>) {
    let d: Vec<f64> = pts.chunks_exact(3).map(|p| dist(p, c)).collect();
    let lo = d.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = d.iter().copied().fold(0.0, f64::max);
    let near = |v: f64| d.iter().enumerate().filter(|(_, x)| (*x - v).abs() <= tol).map(|(i, _)| i).collect();
    (lo, hi, near(lo), near(hi))
}

#[cfg(test)]
mod tests;
