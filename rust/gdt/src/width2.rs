//! Minimum width of a 2-D point set: the two parallel lines of least separation that
//! enclose it (a straightness zone of a profile, ISO 12780; the zone of a plane free
//! to turn about one datum direction, ISO 1101 Sec. 18).
//!
//! The width of a set is the width of its convex hull, and the minimum over all
//! directions is attained with one line flush with a hull edge (Houle and Toussaint,
//! "Computing the width of a set", IEEE PAMI 10 (1988) 761-765). The hull is built by
//! Andrew's monotone chain with Shewchuk's exact orientation predicate, after an
//! Akl-Toussaint prefilter for large inputs; rotating calipers then visit every edge
//! with its farthest vertex in O(h).

use gagekit_core::{check_finite, GkError, Result};
use rayon::prelude::*;
use robust::{orient2d, Coord};

/// Inputs larger than this are prefiltered (points inside the octagon of extremes dropped).
const PREFILTER_ABOVE: usize = 4096;

/// A width of a 2-D set along a unit `normal`: `lo` and `hi` are the smallest and
/// largest of `normal . p` over the points; `width = hi - lo`.
#[derive(Debug, Clone, PartialEq)]
pub struct Width2 {
    pub normal: [f64; 2],
    pub lo: f64,
    pub hi: f64,
    pub width: f64,
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    orient2d(Coord { x: a[0], y: a[1] }, Coord { x: b[0], y: b[1] }, Coord { x: c[0], y: c[1] })
}

/// Indices of the convex hull vertices of `p`, counter-clockwise, no collinear
/// vertices. Fewer than 3 when the set is collinear (the two extremes) or a point.
pub fn hull(p: &[[f64; 2]]) -> Vec<usize> {
    let mut ids: Vec<usize> = if p.len() > PREFILTER_ABOVE { survivors(p) } else { (0..p.len()).collect() };
    ids.sort_by(|&i, &j| p[i][0].total_cmp(&p[j][0]).then(p[i][1].total_cmp(&p[j][1])).then(i.cmp(&j)));
    ids.dedup_by(|a, b| p[*a] == p[*b]);
    if ids.len() < 3 {
        return ids;
    }
    let mut lower: Vec<usize> = Vec::new();
    for &i in &ids {
        while lower.len() >= 2 && orient(p[lower[lower.len() - 2]], p[lower[lower.len() - 1]], p[i]) <= 0.0 {
            lower.pop();
        }
        lower.push(i);
    }
    let mut upper: Vec<usize> = Vec::new();
    for &i in ids.iter().rev() {
        while upper.len() >= 2 && orient(p[upper[upper.len() - 2]], p[upper[upper.len() - 1]], p[i]) <= 0.0 {
            upper.pop();
        }
        upper.push(i);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Akl-Toussaint: drop the points strictly inside the polygon of the extremes in 8
/// directions (they cannot be hull vertices). Exact predicate, parallel.
fn survivors(p: &[[f64; 2]]) -> Vec<usize> {
    let dirs: [[f64; 2]; 8] = [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, 0.0], [-1.0, -1.0], [0.0, -1.0], [1.0, -1.0]];
    let ext: Vec<usize> = dirs
        .iter()
        .map(|d| {
            (0..p.len())
                .into_par_iter()
                .map(|i| (d[0] * p[i][0] + d[1] * p[i][1], i))
                .reduce(|| (f64::NEG_INFINITY, usize::MAX), |a, b| if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a })
                .1
        })
        .collect();
    let mut poly: Vec<usize> = Vec::new();
    for &i in &ext {
        if poly.last() != Some(&i) && poly.first() != Some(&i) {
            poly.push(i);
        }
    }
    if poly.len() < 3 {
        return (0..p.len()).collect();
    }
    (0..p.len())
        .into_par_iter()
        .filter(|&i| {
            // keep unless strictly inside every (counter-clockwise) edge
            !(0..poly.len()).all(|k| orient(p[poly[k]], p[poly[(k + 1) % poly.len()]], p[i]) > 0.0)
        })
        .collect()
}

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
