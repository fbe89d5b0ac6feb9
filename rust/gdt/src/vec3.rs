//! Small 3-D vector helpers on `[f64; 3]`.

use gagekit_core::{GkError, Result};

pub type V3 = [f64; 3];

#[inline]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or an error naming `what` for a zero or non-finite vector.
pub fn unit(a: V3, what: &str) -> Result<V3> {
    let n = norm(a);
    if !(n.is_finite() && n > 0.0) {
        return Err(GkError::invalid(format!("{what}: needs a non-zero finite direction, got {a:?}")));
    }
    Ok(scale(a, 1.0 / n))
}

/// A right-handed orthonormal pair (u, v) with u x v = a for a unit vector `a`
/// (Frisvad's construction with the Duff et al. fix: continuous except at one pole).
pub fn basis(a: V3) -> (V3, V3) {
    let s = if a[2] >= 0.0 { 1.0 } else { -1.0 };
    let p = -1.0 / (s + a[2]);
    let q = a[0] * a[1] * p;
    let u = [1.0 + s * a[0] * a[0] * p, s * q, -s * a[0]];
    let v = [q, s + a[1] * a[1] * p, -a[1]];
    (u, v)
}

/// The point `i` of a flat (n, 3) buffer.
pub fn at(pts: &[f64], i: usize) -> V3 {
    [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]]
}

/// Mean of the points of a flat (n, 3) buffer.
pub fn centroid(pts: &[f64]) -> V3 {
    let n = (pts.len() / 3).max(1) as f64;
    let mut c = [0.0; 3];
    for p in pts.chunks_exact(3) {
        for k in 0..3 {
            c[k] += p[k];
        }
    }
    scale(c, 1.0 / n)
}

/// The points projected onto the plane normal to `a` as 2-D coordinates (u.p, v.p),
/// with `(u, v) = basis(a)`, relative to `origin`.
pub fn project(pts: &[f64], a: V3, origin: V3) -> (Vec<f64>, V3, V3) {
    let (u, v) = basis(a);
    let mut out = Vec::with_capacity(pts.len() / 3 * 2);
    for p in pts.chunks_exact(3) {
        let d = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        out.push(dot(d, u));
        out.push(dot(d, v));
    }
    (out, u, v)
}

/// Check a flat (n, 3) buffer: finite values, at least `min_points` points.
pub fn check_points(pts: &[f64], min_points: usize, what: &str) -> Result<usize> {
    gagekit_core::check_finite(pts, 3, what)?;
    let n = pts.len() / 3;
    if n < min_points {
        return Err(GkError::invalid(format!("{what}: need at least {min_points} points, got {n}")));
    }
    Ok(n)
}
