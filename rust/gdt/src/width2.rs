//! Minimum width of a 2-D point set: the two parallel lines of least separation that
//! enclose it (a straightness zone of a profile, ISO 12780; the zone of a plane free
//! to turn about one datum direction, ISO 1101 Sec. 18).
//!
//! The width of a set is the width of its convex hull, and the minimum over all
//! directions is attained with one line flush with a hull edge (Houle and Toussaint,
//! "Computing the width of a set", IEEE PAMI 10 (1988) 761-765). The hull is built by
//! `gagekit_geometry::hull_2d` (Andrew's monotone chain, exact predicate); rotating calipers then visit every edge
//! with its farthest vertex in O(h).

use gagekit_core::{check_finite, GkError, Result};

/// A width of a 2-D set along a unit `normal`: `lo` and `hi` are the smallest and
/// largest of `normal . p` over the points; `width = hi - lo`.
#[derive(Debug, Clone, PartialEq)]
pub struct Width2 {
    pub normal: [f64; 2],
    pub lo: f64,
    pub hi: f64,
    pub width: f64,
}


/// Indices of the convex hull vertices of `p`, counter-clockwise, no collinear
/// vertices. Fewer than 3 when the set is collinear (the two extremes) or a point.
pub use gagekit_geometry::hull_2d as hull;

/// Minimum width of (n, 2) points (flat `[x0, y0, x1, y1, ...]`), n >= 2.
///
/// Collinear points have width 0 (normal perpendicular to their line); coincident
/// points are an error.
pub fn min_width(pts: &[f64]) -> Result<Width2> {
    const WHAT: &str = "minimum width";
    check_finite(pts, 2, WHAT)?;
    let n = pts.len() / 2;
    if n < 2 {
        return Err(GkError::invalid(format!("{WHAT}: need at least 2 points, got {n}")));
    }
    // centre on the bounding box: the predicates are exact, the distances then lose nothing
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in pts.chunks_exact(2) {
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let p: Vec<[f64; 2]> = pts.chunks_exact(2).map(|q| [q[0] - c[0], q[1] - c[1]]).collect();
    let h = hull(&p);
    let normal = if h.len() < 2 {
        return Err(GkError::degenerate(format!("{WHAT}: all {n} points coincide")));
    } else if h.len() == 2 {
        let e = [p[h[1]][0] - p[h[0]][0], p[h[1]][1] - p[h[0]][1]];
        let l = e[0].hypot(e[1]);
        [-e[1] / l, e[0] / l]
    } else {
        calipers(&p, &h)
    };
    Ok(along(&p, &h, normal, c))
}

/// The width along `normal` of the hull vertices `h`, shifted back by `c`.
fn along(p: &[[f64; 2]], h: &[usize], normal: [f64; 2], c: [f64; 2]) -> Width2 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &i in h {
        let d = normal[0] * p[i][0] + normal[1] * p[i][1];
        lo = lo.min(d);
        hi = hi.max(d);
    }
    let off = normal[0] * c[0] + normal[1] * c[1];
    Width2 { normal, lo: lo + off, hi: hi + off, width: hi - lo }
}

/// Rotating calipers over a counter-clockwise hull: the unit inward normal of the edge
/// whose farthest vertex is nearest.
fn calipers(p: &[[f64; 2]], h: &[usize]) -> [f64; 2] {
    let m = h.len();
    let dist = |k: usize, j: usize| -> f64 {
        let (a, b, q) = (p[h[k]], p[h[(k + 1) % m]], p[h[j % m]]);
        let e = [b[0] - a[0], b[1] - a[1]];
        (e[0] * (q[1] - a[1]) - e[1] * (q[0] - a[0])) / e[0].hypot(e[1])
    };
    let mut best = (f64::INFINITY, 0usize);
    let mut j = 1usize;
    for k in 0..m {
        if j <= k {
            j = k + 1;
        }
        // advance the antipodal vertex while it gets farther from edge k
        let mut steps = 0;
        while steps < m && dist(k, j + 1) >= dist(k, j) {
            j += 1;
            steps += 1;
        }
        let d = dist(k, j);
        if d < best.0 {
            best = (d, k);
        }
    }
    let (a, b) = (p[h[best.1]], p[h[(best.1 + 1) % m]]);
    let e = [b[0] - a[0], b[1] - a[1]];
    let l = e[0].hypot(e[1]);
    [-e[1] / l, e[0] / l]
}
