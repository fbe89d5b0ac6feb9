//! The exact closest point of a triangle to a point (Ericson, *Real-Time Collision
//! Detection*, 2005, Sec. 5.1.5): the Voronoi regions of the vertices, the edges and the
//! face are tested in turn, so the answer also says which feature the closest point lies
//! on -- the feature whose pseudonormal signs the distance (Baerentzen and Aanaes 2005).

use gagekit_gdt::vec3::{add, dot, scale, sub, V3};

/// The feature of a triangle (a, b, c) a closest point lies on. Edge k joins vertex k
/// and vertex (k + 1) mod 3: 0 = ab, 1 = bc, 2 = ca.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    Vertex(u8),
    Edge(u8),
    Face,
}

/// The closest point of triangle (a, b, c) to `p`, and its feature.
#[inline]
pub fn closest_point(p: V3, a: V3, b: V3, c: V3) -> (V3, Feature) {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add(a, scale(ab, v)), Feature::Edge(0));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add(a, scale(ac, w)), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add(b, scale(sub(c, b), w)), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (add(a, add(scale(ab, v), scale(ac, w))), Feature::Face)
}

/// Squared distance from `p` to the axis-aligned box [lo, hi] (0 inside).
#[inline]
pub fn box_distance2(p: &V3, lo: &V3, hi: &V3) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let v = if p[k] < lo[k] {
            lo[k] - p[k]
        } else if p[k] > hi[k] {
            p[k] - hi[k]
        } else {
            0.0
        };
        d2 += v * v;
    }
    d2
}
