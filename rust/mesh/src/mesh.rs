//! Validated triangle meshes, their topology and their angle-weighted pseudonormals.
//!
//! A mesh is refused (typed error naming the element) when a vertex is not finite, a
//! triangle names a vertex that does not exist, or a triangle is degenerate (two equal
//! corners, or a height below 1e-12 of its longest edge: no normal). Its topology decides
//! whether distances can be signed: every edge shared by exactly two triangles that run
//! it in opposite directions (a closed, consistently oriented 2-manifold) gives signed
//! distances, positive outside the material; otherwise distances are unsigned and
//! [`Topology::reason`] says why (the caller warns once). A closed mesh whose triangles
//! face inwards (negative enclosed volume) is read turned outwards.
//!
//! Sign (Baerentzen and Aanaes, "Signed distance computation using the angle weighted
//! pseudonormal", IEEE TVCG 11(3), 2005, Theorem 1): with c the closest point of the
//! surface to p, the sign of (p - c) . n(c) is the side of p, where n(c) is the face
//! normal inside a face, the sum of the two face normals on an edge, and the sum of the
//! incident face normals weighted by their angles at a vertex.

use crate::bvh::Bvh;
use gagekit_core::{GkError, Result};
use gagekit_gdt::vec3::{add, cross, dot, norm, scale, sub, V3};

/// How the triangles fit together.
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    /// closed, manifold and consistently oriented: distances are signed
    pub closed: bool,
    /// why distances are unsigned (None when closed)
    pub reason: Option<String>,
    /// edges used by one triangle only
    pub boundary_edges: usize,
    /// edges used by more than two triangles
    pub nonmanifold_edges: usize,
    /// the triangles were wound inwards and are read turned outwards
    pub flipped: bool,
    /// the enclosed volume (mm^3; 0 when not closed)
    pub volume: f64,
}

/// A vertex index as given to [`TriMesh::new`]: `u32`, or `i64` (numpy's indices) or `i32`.
pub trait VertexIndex: Copy + Sync + std::fmt::Display {
    /// The index as u32; `u32::MAX` (never a vertex: at most 2^32 - 2) when out of range.
    fn to_u32(self) -> u32;
}

impl VertexIndex for u32 {
    #[inline(always)]
    fn to_u32(self) -> u32 {
        self
    }
}

impl VertexIndex for i64 {
    #[inline(always)]
    fn to_u32(self) -> u32 {
        u32::try_from(self).unwrap_or(u32::MAX)
    }
}

impl VertexIndex for i32 {
    #[inline(always)]
    fn to_u32(self) -> u32 {
        u32::try_from(self).unwrap_or(u32::MAX)
    }
}

/// A triangle mesh ready for distance queries.
#[derive(Debug, Clone)]
pub struct TriMesh {
    pub vertices: Vec<V3>,
    pub triangles: Vec<[u32; 3]>,
    /// unit outward normal of each triangle
    pub face_normals: Vec<V3>,
    /// angle-weighted pseudonormal of each vertex (not unit)
    pub vertex_normals: Vec<V3>,
    /// pseudonormal of edge k (vertex k to k + 1) of each triangle (not unit)
    pub edge_normals: Vec<[V3; 3]>,
    /// the surface area (mm^2)
    pub area: f64,
    pub topology: Topology,
    pub bvh: Bvh,
}

impl TriMesh {
    /// Build from flat vertex coordinates (3 per vertex) and flat vertex indices (3 per
    /// triangle; `u32`, or `i64` as numpy gives them, converted in the parallel copy);
    /// see the module docs for what is refused.
    pub fn new<I: VertexIndex>(vertices: &[f64], triangles: &[I]) -> Result<Self> {
        if vertices.len() % 3 != 0 || triangles.len() % 3 != 0 {
            return Err(GkError::invalid("mesh: vertices and triangles must be (n, 3) arrays"));
        }
        let nv = vertices.len() / 3;
        let nt = triangles.len() / 3;
        if nt == 0 {
            return Err(GkError::invalid("mesh: no triangles (the model has no faces)"));
        }
        if nv > u32::MAX as usize - 1 || nt > u32::MAX as usize - 1 {
            return Err(GkError::invalid("mesh: more than 2^32 - 2 vertices or triangles"));
        }
        // copied first, then checked: the copy is what the mesh uses (the caller's arrays
        // may be read in place while other threads run)
        // (the copies and checks in parallel; the first bad element is named, as by a scan)
        use rayon::prelude::*;
        let verts: Vec<V3> = vertices.par_chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect();
        // an index that is no u32 is read as u32::MAX (>= nv: refused below, by its value)
        let tris: Vec<[u32; 3]> = triangles.par_chunks_exact(3).map(|t| [t[0].to_u32(), t[1].to_u32(), t[2].to_u32()]).collect();
        if let Some(pos) = verts.as_flattened().par_iter().position_first(|v| !v.is_finite()) {
            return Err(GkError::invalid(format!(
                "mesh: vertex {} has a non-finite coordinate ({}); the model is damaged",
                pos / 3,
                verts.as_flattened()[pos]
            )));
        }
        if let Some((i, k)) = tris.par_iter().enumerate().find_map_first(|(i, t)| t.iter().position(|&k| k as usize >= nv).map(|k| (i, k))) {
            let bad = triangles[3 * i + k];
            return Err(GkError::invalid(format!("mesh: triangle {i} names vertex {bad}, but there are {nv} vertices")));
        }
        // per triangle (in parallel): the unit normal and twice the area, or ([0; 3], -1)
        // when degenerate; the area summed in triangle order
        let (mut normals, twice_area): (Vec<V3>, Vec<f64>) = {
            tris.par_iter()
                .map(|t| {
                    let (a, b, c) = (verts[t[0] as usize], verts[t[1] as usize], verts[t[2] as usize]);
                    let n = cross(sub(b, a), sub(c, a));
                    let n2 = norm(n);
                    let longest = [sub(b, a), sub(c, b), sub(a, c)].iter().map(|e| dot(*e, *e)).fold(0.0, f64::max);
                    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(n2 > 1e-12 * longest) {
                        ([0.0; 3], -1.0)
                    } else {
                        (scale(n, 1.0 / n2), n2)
                    }
                })
                .unzip()
        };
        let mut area = 0.0;
        let mut degenerate = Vec::new();
        for (i, &n2) in twice_area.iter().enumerate() {
            if n2 < 0.0 {
                degenerate.push(i);
            } else {
                area += 0.5 * n2;
            }
        }
        drop(twice_area);
        if !degenerate.is_empty() {
            let first: Vec<String> = degenerate.iter().take(5).map(|i| i.to_string()).collect();
            return Err(GkError::degenerate(format!(
                "mesh: {} degenerate triangle(s) (zero area or repeated corners), first: {}; repair the model (remove them) first",
                degenerate.len(),
                first.join(", ")
            )));
        }
        // the topology and pseudonormals (partly serial: the edges' counting sort, the
        // topology loop, the edge normals' scatter) beside the tree's build, which needs
        // neither: the idle core of the tree's serial stretches runs them. Each side is
        // computed as alone (no shared state), so the same bits
        let ((topology, normals, vertex_normals, edge_normals), bvh) = rayon::join(
            || {
                let edges = sorted_edges(&tris, nv);
                let topology = topology(&verts, &tris, &edges);
                if topology.flipped {
                    for n in normals.iter_mut() {
                        *n = scale(*n, -1.0);
                    }
                }
                let (vertex_normals, edge_normals) = pseudonormals(&verts, &tris, &normals, &edges);
                (topology, normals, vertex_normals, edge_normals)
            },
            || {
                Bvh::build(tris.len(), |i| {
                    let t = &tris[i];
                    [verts[t[0] as usize], verts[t[1] as usize], verts[t[2] as usize]]
                })
            },
        );
        Ok(Self { vertices: verts, triangles: tris, face_normals: normals, vertex_normals, edge_normals, area, topology, bvh })
    }

    /// Whether distances are signed.
    pub fn signed(&self) -> bool {
        self.topology.closed
    }

    /// The area-weighted centroid and second-moment (covariance) matrix of the surface,
    /// exact for uniform density on each triangle: E[x x^T] = (sum v v^T + s s^T) / 12,
    /// s = a + b + c.
    pub fn surface_moments(&self) -> (V3, [[f64; 3]; 3]) {
        let mut m = [0.0; 3];
        let mut s2 = [[0.0; 3]; 3];
        let mut total = 0.0;
        for t in &self.triangles {
            let (a, b, c) = (self.vertices[t[0] as usize], self.vertices[t[1] as usize], self.vertices[t[2] as usize]);
            let w = 0.5 * norm(cross(sub(b, a), sub(c, a)));
            let s = add(add(a, b), c);
            total += w;
            for i in 0..3 {
                m[i] += w * s[i] / 3.0;
                for j in 0..3 {
                    s2[i][j] += w * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]) / 12.0;
                }
            }
        }
        let mu = scale(m, 1.0 / total);
        let mut cov = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] = s2[i][j] / total - mu[i] * mu[j];
            }
        }
        (mu, cov)
    }
}

/// Every triangle's edges as (low vertex, high vertex, triangle, k), sorted (the entries
/// are distinct, so the order is unique): the groups of one undirected edge. A counting
/// sort by the low vertex (linear), then each vertex's few edges sorted in parallel.
fn sorted_edges(tris: &[[u32; 3]], nv: usize) -> Vec<(u64, u32, u8)> {
    use rayon::prelude::*;
    let key = |t: &[u32; 3], k: usize| {
        let (u, v) = (t[k], t[(k + 1) % 3]);
        ((u.min(v) as u64) << 32) | u.max(v) as u64
    };
    // start[v]: where the edges of low vertex v begin
    let mut start = vec![0usize; nv + 1];
    for t in tris {
        for k in 0..3 {
            start[(key(t, k) >> 32) as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut edges = vec![(0u64, 0u32, 0u8); 3 * tris.len()];
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let e = key(t, k);
            let at = &mut fill[(e >> 32) as usize];
            edges[*at] = (e, i as u32, k as u8);
            *at += 1;
        }
    }
    edges.par_chunk_by_mut(|a, b| a.0 >> 32 == b.0 >> 32).for_each(|g| g.sort_unstable());
    edges
}

/// The runs of `edges` that share one undirected edge.
fn edge_groups(edges: &[(u64, u32, u8)]) -> impl Iterator<Item = &[(u64, u32, u8)]> {
    edges.chunk_by(|a, b| a.0 == b.0)
}

fn topology(verts: &[V3], tris: &[[u32; 3]], edges: &[(u64, u32, u8)]) -> Topology {
    let (mut boundary, mut nonmanifold, mut inconsistent) = (0usize, 0usize, 0usize);
    // an edge's direction in a triangle: forward when it runs from its low to its high vertex
    let forward = |e: &(u64, u32, u8)| {
        let t = &tris[e.1 as usize];
        t[e.2 as usize] < t[(e.2 as usize + 1) % 3]
    };
    for g in edge_groups(edges) {
        match g.len() {
            1 => boundary += 1,
            2 => {
                if forward(&g[0]) == forward(&g[1]) {
                    inconsistent += 1;
                }
            }
            _ => nonmanifold += 1,
        }
    }
    let mut reason = None;
    if boundary > 0 {
        reason = Some(format!("the mesh is open ({boundary} boundary edges): it has no inside, distances are unsigned"));
    } else if nonmanifold > 0 {
        reason = Some(format!("the mesh is not a manifold ({nonmanifold} edges shared by more than two triangles): distances are unsigned"));
    } else if inconsistent > 0 {
        reason = Some(format!("the triangles are not consistently oriented ({inconsistent} edges): distances are unsigned"));
    }
    let mut volume = 0.0;
    let mut flipped = false;
    if reason.is_none() {
        for t in tris {
            let (a, b, c) = (verts[t[0] as usize], verts[t[1] as usize], verts[t[2] as usize]);
            volume += dot(a, cross(b, c)) / 6.0;
        }
        if volume < 0.0 {
            flipped = true;
            volume = -volume;
        } else if volume == 0.0 {
            reason = Some("the closed mesh encloses no volume: distances are unsigned".to_string());
        }
    }
    Topology { closed: reason.is_none(), reason, boundary_edges: boundary, nonmanifold_edges: nonmanifold, flipped, volume }
}

fn angle(u: V3, v: V3) -> f64 {
    // atan2 of |u x v| and u . v: accurate for small and large angles
    norm(cross(u, v)).atan2(dot(u, v))
}

fn pseudonormals(verts: &[V3], tris: &[[u32; 3]], normals: &[V3], edges: &[(u64, u32, u8)]) -> (Vec<V3>, Vec<[V3; 3]>) {
    use rayon::prelude::*;
    // each vertex's pseudonormal: its corners' angle-weighted face normals summed in
    // triangle order. The vertices in ranges, one a thread, in parallel: each range
    // scans all the triangles for its own corners (no array of all angles, no
    // sequential scatter; the same sums in the same order, whatever the thread count)
    let mut vn = vec![[0.0; 3]; verts.len()];
    let per = verts.len().div_ceil(rayon::current_num_threads().clamp(1, 16)).max(1);
    vn.par_chunks_mut(per).enumerate().for_each(|(c, out)| {
        let lo = c * per;
        for (t, n) in tris.iter().zip(normals) {
            for k in 0..3 {
                let i = (t[k] as usize).wrapping_sub(lo);
                if i < out.len() {
                    let p = verts[t[k] as usize];
                    let a = angle(sub(verts[t[(k + 1) % 3] as usize], p), sub(verts[t[(k + 2) % 3] as usize], p));
                    out[i] = add(out[i], scale(*n, a));
                }
            }
        }
    });
    // edge normals: the sum of the normals of the triangles sharing the edge
    let mut en = vec![[[0.0; 3]; 3]; tris.len()];
    for g in edge_groups(edges) {
        let mut sum = [0.0; 3];
        for e in g {
            sum = add(sum, normals[e.1 as usize]);
        }
        for e in g {
            en[e.1 as usize][e.2 as usize] = sum;
        }
    }
    (vn, en)
}
