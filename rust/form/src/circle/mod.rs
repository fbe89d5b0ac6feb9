//! 2-D circle fits (Sec. 6.2): minimum circumscribed (MC, Eq. 6.1), maximum inscribed
//! (MI, Eq. 6.2), minimum zone (MZ, roundness, Eqs. 6.5-6.8) and geometric least squares.
//!
//! Points are a flat row-major buffer `[x0, y0, x1, y1, ...]`. Every result names its
//! control points: indices into the input of the points that fix the solution.
//!
//! All fits work on data translated to the middle of its bounding box, so a part
//! 10^6 mm away from the origin is fitted as accurately as one at the origin.

mod complete;
pub mod in_plane;
mod lsq;
mod mc;
mod mi;
mod mi_tiled;
mod mz;
mod subset;
mod voronoi;

#[cfg(test)]
mod tests;

use gagekit_core::{GkError, Result};

pub use complete::{fit, from_circle, from_zone, CircleFit, MIN_ARC_DEG};
pub use lsq::least_squares;
pub use mc::min_circumscribed;
pub use mi::{max_inscribed, max_inscribed_near};
pub use mz::min_zone;

/// A circle with the indices of the input points that fix it.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle {
    pub center: [f64; 2],
    pub radius: f64,
    /// Indices into the input of the points that determine the circle (for least
    /// squares: the points of largest and smallest radial deviation).
    pub control: Vec<usize>,
}

/// A pair of concentric circles enclosing all points (a roundness zone).
#[derive(Debug, Clone, PartialEq)]
pub struct Zone {
    pub center: [f64; 2],
    pub r_in: f64,
    pub r_out: f64,
    /// Points on the inner circle that fix the zone.
    pub control_in: Vec<usize>,
    /// Points on the outer circle that fix the zone.
    pub control_out: Vec<usize>,
}

impl Zone {
    /// Radial separation of the two circles (the roundness error).
    pub fn form_error(&self) -> f64 {
        self.r_out - self.r_in
    }

    /// The points that fix the zone: `control_in`, then those of `control_out` not in it.
    pub fn control(&self) -> Vec<usize> {
        let mut c = self.control_in.clone();
        c.extend(self.control_out.iter().filter(|i| !self.control_in.contains(i)));
        c
    }
}

/// Points translated to the middle of their bounding box, with the shift and extent.
pub(crate) struct Centered {
    pub pts: Vec<[f64; 2]>,
    pub shift: [f64; 2],
    /// Half the diagonal of the bounding box (0 if all points coincide).
    pub scale: f64,
    /// Half the width and height of the bounding box.
    pub half: [f64; 2],
}

impl Centered {
    pub fn new(pts: &[f64], what: &str, min_points: usize) -> Result<Self> {
        gagekit_core::check_finite(pts, 2, what)?;
        let n = pts.len() / 2;
        if n < min_points {
            return Err(GkError::invalid(format!(
                "{what}: need at least {min_points} points, got {n}"
            )));
        }
        if let Some(pos) = pts.iter().position(|v| v.abs() > MAX_COORD) {
            return Err(GkError::invalid(format!(
                "{what}: point {} has a coordinate beyond 1e150 mm ({:e}); check the units",
                pos / 2,
                pts[pos]
            )));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in pts.chunks_exact(2) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let shift = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let scale = 0.5 * (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        let half = [0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1])];
        let pts = pts
            .chunks_exact(2)
            .map(|p| [p[0] - shift[0], p[1] - shift[1]])
            .collect();
        Ok(Self { pts, shift, scale, half })
    }

    pub fn uncenter(&self, c: [f64; 2]) -> [f64; 2] {
        [c[0] + self.shift[0], c[1] + self.shift[1]]
    }

    /// Error unless the points span a proper 2-D set (not coincident, not collinear).
    /// Uses the exact orientation predicate, so "collinear" means exactly collinear.
    pub fn require_not_collinear(&self, what: &str) -> Result<()> {
        let p0 = self.pts[0];
        let far = self
            .pts
            .iter()
            .enumerate()
            .max_by(|a, b| dist2(*a.1, p0).total_cmp(&dist2(*b.1, p0)))
            .map(|(i, _)| i)
            .unwrap_or(0);
        if dist2(self.pts[far], p0) == 0.0 {
            return Err(GkError::degenerate(format!(
                "{what}: all {} points coincide; a circle needs points spread around it",
                self.pts.len()
            )));
        }
        let (a, b) = (coord(p0), coord(self.pts[far]));
        if self
            .pts
            .iter()
            .all(|p| robust::orient2d(a, b, coord(*p)) == 0.0)
        {
            return Err(GkError::degenerate(format!(
                "{what}: all {} points lie on one straight line; no circle fits them",
                self.pts.len()
            )));
        }
        Ok(())
    }
}

#[inline]
pub(crate) fn coord(p: [f64; 2]) -> robust::Coord<f64> {
    robust::Coord { x: p[0], y: p[1] }
}

#[inline]
pub(crate) fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    dx * dx + dy * dy
}

#[inline]
pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    // plain sqrt (libm's hypot is several times slower); coordinates are bounded by
    // MAX_COORD, so the squares cannot overflow
    dist2(a, b).sqrt()
}

/// Largest accepted coordinate magnitude (mm): squares of distances stay finite.
pub(crate) use crate::lsq::MAX_COORD;

/// Centre of the circle through three points, or `None` if they are collinear.
/// Computed relative to `a` for accuracy.
pub(crate) fn circumcenter(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Option<[f64; 2]> {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    let u = [a[0] + ux, a[1] + uy];
    if u[0].is_finite() && u[1].is_finite() {
        Some(u)
    } else {
        None
    }
}

/// Largest angular gap (rad) of the points seen from `center`; `2 pi - gap` is the arc
/// the points cover. Linear time (bucket maximum-gap).
pub fn max_angular_gap(pts: &[f64], center: [f64; 2]) -> f64 {
    use rayon::prelude::*;
    let ang: Vec<f64> = pts
        .par_chunks_exact(2)
        .with_min_len(8192)
        .filter(|p| p[0] != center[0] || p[1] != center[1])
        .map(|p| (p[1] - center[1]).atan2(p[0] - center[0]))
        .collect();
    let n = ang.len();
    if n < 2 {
        return std::f64::consts::TAU;
    }
    let (lo, hi) = ang
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &a| {
            (l.min(a), h.max(a))
        });
    let mut gap = lo + std::f64::consts::TAU - hi;
    if hi > lo {
        let nb = n + 1;
        let mut bmin = vec![f64::INFINITY; nb];
        let mut bmax = vec![f64::NEG_INFINITY; nb];
        for &a in &ang {
            let k = (((a - lo) / (hi - lo)) * (nb - 1) as f64) as usize;
            let k = k.min(nb - 1);
            bmin[k] = bmin[k].min(a);
            bmax[k] = bmax[k].max(a);
        }
        let mut prev = bmax[0];
        for k in 1..nb {
            if bmin[k].is_finite() {
                gap = gap.max(bmin[k] - prev);
                prev = bmax[k];
            }
        }
    }
    gap
}
