//! The minimum width of a 3-D point set: the thinnest slab of free orientation that
//! contains it -- the minimum zone of flatness (ISO 12781-1, two parallel planes of
//! least separation) and the orientation of a free primary datum plane (ISO 5459).
//!
//! Exact, as the 2-D width of [`crate::width2`]: the thinnest slab has a supporting
//! plane through a facet of the convex hull (a face-vertex pair) or two supporting
//! planes through two non-parallel hull edges (an edge-edge pair; Houle & Toussaint
//! 1988). The hull is the exact quickhull of `gagekit-geometry` (triangulated; edges
//! inside a flat facet are no candidates). Every candidate direction is scored by the
//! width of the hull's vertices along it, so a candidate can never report a width
//! narrower than the set; an edge pair is a candidate when its direction lies (within
//! rounding) in both edges' cones of supporting normals (the arcs between their two
//! faces' normals), which only ever admits more candidates than the exact test. The
//! reported slab is recomputed from all points along the best direction.

use crate::vec3::{self, check_points, cross, dot, norm, sub, V3};
use crate::width3::{self, Slab};
use gagekit_core::Result;
use gagekit_geometry::HullMesh;
use rayon::prelude::*;

/// An edge between two hull triangles: its end (relative to the centroid), its unit
/// direction, and the outward unit normals of the two triangles.
struct Edge {
    a: V3,
    dir: V3,
    n1: V3,
    n2: V3,
}

/// Slack of the cone test (unit vectors): wider than any rounding, only adds candidates.
const CONE_SLACK: f64 = 1e-9;

/// Whether the unit `m` (perpendicular to the edge) lies in the edge's cone of
/// supporting normals, the arc from `n1` to `n2`.
fn in_cone(e: &Edge, m: V3) -> bool {
    let k = cross(e.n1, e.n2);
    let (a, b) = (dot(cross(e.n1, m), k), dot(cross(m, e.n2), k));
    let s = CONE_SLACK * norm(k);
    a >= -s && b >= -s && dot(m, vec3::add(e.n1, e.n2)) > 0.0
}

/// Point `i` of `pts` relative to `c`.
fn rel(pts: &[f64], c: V3, i: usize) -> V3 {
    sub(vec3::at(pts, i), c)
}

/// The width of the (relative) hull vertices `vp` along the unit `m`.
fn width_along(vp: &[V3], m: V3) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in vp {
        let d = dot(*p, m);
        lo = lo.min(d);
        hi = hi.max(d);
    }
    hi - lo
}

/// The hull's vertices (each once, relative to `c`).
fn hull_vertices(mesh: &HullMesh, pts: &[f64], c: V3) -> Vec<V3> {
    let mut verts: Vec<usize> = mesh.triangles.iter().flatten().copied().collect();
    verts.sort_unstable();
    verts.dedup();
    verts.iter().map(|&i| rel(pts, c, i)).collect()
}

/// The outward unit normal of each hull triangle (`None` for a degenerate one).
fn facet_normals(mesh: &HullMesh, pts: &[f64], c: V3) -> Vec<Option<V3>> {
    mesh.triangles
        .iter()
        .map(|t| {
            let (p0, p1, p2) = (rel(pts, c, t[0]), rel(pts, c, t[1]), rel(pts, c, t[2]));
            let n = cross(sub(p1, p0), sub(p2, p0));
            let l = norm(n);
            // outward: away from the centroid (the origin here), inside the hull
            let s = if dot(n, p0) >= 0.0 { 1.0 } else { -1.0 };
            (l > 0.0).then(|| vec3::scale(n, s / l))
        })
        .collect()
}

/// Face-vertex candidates: the narrowest width along a facet normal, and that normal
/// (ties to the first facet).
fn best_face(normals: &[Option<V3>], vp: &[V3]) -> Option<(f64, V3)> {
    normals
        .par_iter()
        .enumerate()
        .filter_map(|(f, n)| n.map(|n| (width_along(vp, n), f, n)))
        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
        .map(|(w, _, n)| (w, n))
}

/// The hull's edges between two non-coplanar triangles, each once.
fn hull_edges(mesh: &HullMesh, normals: &[Option<V3>], pts: &[f64], c: V3) -> Vec<Edge> {
    let mut edges = Vec::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        for i in 0..3 {
            let g = mesh.neighbors[f][i];
            if g <= f {
                continue;
            }
            let (Some(n1), Some(n2)) = (normals[f], normals[g]) else { continue };
            if norm(cross(n1, n2)) <= 1e-12 && dot(n1, n2) > 0.0 {
                continue; // inside a flat facet: its face candidate covers it
            }
            let a = rel(pts, c, t[i]);
            let e = sub(rel(pts, c, t[(i + 1) % 3]), a);
            let l = norm(e);
            if l > 0.0 {
                edges.push(Edge { a, dir: vec3::scale(e, 1.0 / l), n1, n2 });
            }
        }
    }
    edges
}

/// Edge-edge candidates: the narrowest width along the common normal of two
/// non-parallel edges that lies in both edges' cones, with that normal (ties to the
/// first edge).
fn best_edge_pair(edges: &[Edge], vp: &[V3]) -> Option<(f64, V3)> {
    edges
        .par_iter()
        .enumerate()
        .filter_map(|(i, e1)| {
            let mut local: Option<(f64, V3)> = None;
            for e2 in &edges[i + 1..] {
                let d = cross(e1.dir, e2.dir);
                let l = norm(d);
                if l <= 1e-12 {
                    continue; // parallel edges: a face candidate covers them
                }
                let m = vec3::scale(d, 1.0 / l);
                // m points out of the set at e1 and into it at e2, or the reverse
                let m = if dot(m, sub(e1.a, e2.a)) >= 0.0 { m } else { vec3::scale(m, -1.0) };
                if !(in_cone(e1, m) && in_cone(e2, vec3::scale(m, -1.0))) {
                    continue;
                }
                // a quick bound first: the two edges' lines are at least this far apart
                if local.is_some_and(|b| dot(m, sub(e1.a, e2.a)) >= b.0) {
                    continue;
                }
                let w = width_along(vp, m);
                if local.is_none_or(|b| w < b.0) {
                    local = Some((w, m));
                }
            }
            local.map(|(w, m)| (w, i, m))
        })
        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
        .map(|(w, _, m)| (w, m))
}

/// The thinnest slab of free orientation containing the points (at least 3).
pub fn min_width(pts: &[f64]) -> Result<Slab> {
    const WHAT: &str = "minimum width";
    check_points(pts, 3, WHAT)?;
    let Some(mesh) = gagekit_geometry::convex_hull_mesh(pts)? else {
        // exactly coplanar (or collinear): width 0 normal to their plane
        let p = gagekit_form::lsq::plane(pts)?;
        return width3::along(pts, [p.normal[0], p.normal[1], p.normal[2]]);
    };
    let c = vec3::centroid(pts);
    let vp = hull_vertices(&mesh, pts, c);
    let normals = facet_normals(&mesh, pts, c);
    let mut best = best_face(&normals, &vp);
    let edges = hull_edges(&mesh, &normals, pts, c);
    if let Some((w, m)) = best_edge_pair(&edges, &vp) {
        if best.is_none_or(|b| w < b.0) {
            best = Some((w, m));
        }
    }
    match best {
        Some((_, n)) => width3::along(pts, n),
        None => {
            let p = gagekit_form::lsq::plane(pts)?;
            width3::along(pts, [p.normal[0], p.normal[1], p.normal[2]])
        }
    }
}
