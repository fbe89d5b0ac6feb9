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

/// The closest point of triangle (a, b, c) to `p`, and its feature. Always inlined: the
/// group query's single-lane tests (about 1.3 a point) otherwise pay a call with its
/// arguments and answer passed through memory (300 k points of the torus bench: the
/// tests 42.4 M instructions called, 27.2 M inlined). Inlining changes no operation, so
/// no bit (no fused multiply-add without `mul_add`).
#[inline(always)]
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

/// Lanes of [`closest_lanes`]: eight points at once.
pub const LANES: usize = 8;

/// [`closest_lanes`]'s answers per lane: the squared distance, the closest point (by axis)
/// and the feature's code ([`feature_of_code`]).
#[derive(Debug, Clone, Copy)]
pub struct Closest8 {
    pub d2: [f64; LANES],
    pub foot: [[f64; LANES]; 3],
    pub code: [u8; LANES],
}

/// The feature of a code of [`closest_lanes`]: 0-2 vertex k, 3-5 edge k - 3, 6 the face
/// (7 too, never made). By a table (one load; the match took about 20 instructions).
#[inline(always)]
pub fn feature_of_code(c: u8) -> Feature {
    const TABLE: [Feature; 8] = [Feature::Vertex(0), Feature::Vertex(1), Feature::Vertex(2), Feature::Edge(0), Feature::Edge(1), Feature::Edge(2), Feature::Face, Feature::Face];
    TABLE[(c & 7) as usize]
}

/// [`closest_point`] of eight points (coordinates by axis) to one triangle, and the
/// squared distance `dot(p - foot, p - foot)`, without branches: every region's
/// candidate is computed by the very operations [`closest_point`] uses for it (the same
/// IEEE operations in the same order, no fused multiply-add: Rust never contracts), and
/// each lane keeps the first region whose test holds, in [`closest_point`]'s order. So
/// each lane's answer equals [`closest_point`]'s to the bit; the quotients of regions a
/// lane does not keep may be infinite or NaN and are never read. Written over arrays so
/// that it compiles to vector instructions (four lanes an AVX instruction).
#[inline(always)]
pub fn closest_lanes(p: [&[f64; LANES]; 3], a: V3, b: V3, c: V3, out: &mut Closest8) {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let bc = sub(c, b);
    for i in 0..LANES {
        let q = [p[0][i], p[1][i], p[2][i]];
        let ap = sub(q, a);
        let d1 = dot(ab, ap);
        let d2 = dot(ac, ap);
        let bp = sub(q, b);
        let d3 = dot(ab, bp);
        let d4 = dot(ac, bp);
        let vc = d1 * d4 - d3 * d2;
        let cp = sub(q, c);
        let d5 = dot(ab, cp);
        let d6 = dot(ac, cp);
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        let e0 = d1 / (d1 - d3);
        let e2 = d2 / (d2 - d6);
        let e1 = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        let denom = 1.0 / (va + vb + vc);
        let (v, w) = (vb * denom, vc * denom);
        // the regions from the last to the first: the first that holds is kept
        let mut f = add(a, add(scale(ab, v), scale(ac, w)));
        let mut code = 6u8;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            f = add(b, scale(bc, e1));
            code = 4;
        }
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            f = add(a, scale(ac, e2));
            code = 5;
        }
        if d6 >= 0.0 && d5 <= d6 {
            f = c;
            code = 2;
        }
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            f = add(a, scale(ab, e0));
            code = 3;
        }
        if d3 >= 0.0 && d4 <= d3 {
            f = b;
            code = 1;
        }
        if d1 <= 0.0 && d2 <= 0.0 {
            f = a;
            code = 0;
        }
        let r = sub(q, f);
        out.d2[i] = dot(r, r);
        out.foot[0][i] = f[0];
        out.foot[1][i] = f[1];
        out.foot[2][i] = f[2];
        out.code[i] = code;
    }
}

/// [`closest_lanes`] compiled for AVX2 (the tests compare it with [`closest_point`]).
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn closest_lanes_avx2(p: [&[f64; LANES]; 3], a: V3, b: V3, c: V3, out: &mut Closest8) {
    closest_lanes(p, a, b, c, out)
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
