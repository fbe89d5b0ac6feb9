//! Exact geometric predicates (Shewchuk's adaptive arithmetic via the `robust`
//! crate). Every orientation decision of the hull filter goes through here, so
//! the sign of each test is the sign of the exact determinant.

use robust::{Coord, Coord3D};

pub type P3 = [f64; 3];

#[inline]
pub fn pt(points: &[f64], i: usize) -> P3 {
    [points[3 * i], points[3 * i + 1], points[3 * i + 2]]
}

#[inline]
fn c3(p: P3) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

/// Positive when `d` lies below the plane of `a, b, c` (they appear
/// counter-clockwise seen from above), negative above, exactly zero when coplanar.
#[inline]
pub fn orient3d(a: P3, b: P3, c: P3, d: P3) -> f64 {
    robust::orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Positive when `a, b, c` turn counter-clockwise, zero exactly when collinear.
#[inline]
pub fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    robust::orient2d(Coord { x: a[0], y: a[1] }, Coord { x: b[0], y: b[1] }, Coord { x: c[0], y: c[1] })
}

/// Drop coordinate `axis` (exact: no arithmetic).
#[inline]
pub fn project(p: P3, axis: usize) -> [f64; 2] {
    match axis {
        0 => [p[1], p[2]],
        1 => [p[2], p[0]],
        _ => [p[0], p[1]],
    }
}

/// Exact collinearity of three points in space: all three coordinate-plane
/// projections are collinear exactly when the cross product vanishes.
pub fn collinear(a: P3, b: P3, c: P3) -> bool {
    (0..3).all(|ax| orient2d(project(a, ax), project(b, ax), project(c, ax)) == 0.0)
}

#[inline]
pub fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn cross(a: P3, b: P3) -> P3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
