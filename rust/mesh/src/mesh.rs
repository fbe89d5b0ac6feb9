//! Validated triangle meshes, their topology and their angle-weighted pseudonormals.
//!
//! A mesh is refused (typed error naming the element) when a vertex is not finite or lies
//! beyond +-[`MAX_COORDINATE`] (1e9 mm: a damaged file or a wrong unit; beyond 1e154 the
//! squared distances would overflow to infinity), a triangle names a vertex that does not exist, or a triangle is degenerate (two equal
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
use gagekit_core::{GkError, Result, MAX_COORDINATE};
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
        // one scan for both: `!(|v| <= MAX)` holds for NaN and the infinities too
        if let Some(pos) = verts.as_flattened().par_iter().position_first(|v| !(v.abs() <= MAX_COORDINATE)) {
            let v = verts.as_flattened()[pos];
            return Err(GkError::invalid(if v.is_finite() {
                format!(
                    "mesh: vertex {} has a coordinate of magnitude {:e}, beyond the supported {:e}; the model is damaged or its unit is wrong (--cad-units)",
                    pos / 3,
                    v.abs(),
                    MAX_COORDINATE
                )
            } else {
                format!("mesh: vertex {} has a non-finite coordinate ({v}); the model is damaged", pos / 3)
            }));
        }
        if let Some((i, k)) = tris.par_iter().enumerate().find_map_first(|(i, t)| t.iter().position(|&k| k as usize >= nv).map(|k| (i, k))) {
            let bad = triangles[3 * i + k];
            return Err(GkError::invalid(format!("mesh: triangle {i} names vertex {bad}, but there are {nv} vertices")));
        }
        // per triangle (in parallel): the unit normal, and twice the area (or -1 when
        // degenerate: the normal [0; 3]) kept in the place of its first edge normal until
        // the edge pass writes every edge normal (no array of areas); the area summed in
        // triangle order
        let mut edge_normals = vec![[[0.0; 3]; 3]; nt];
        let mut normals: Vec<V3> = tris
            .par_iter()
            .zip(edge_normals.par_iter_mut())
            .map(|(t, en)| {
                let (a, b, c) = (verts[t[0] as usize], verts[t[1] as usize], verts[t[2] as usize]);
                let n = cross(sub(b, a), sub(c, a));
                let n2 = norm(n);
                let longest = [sub(b, a), sub(c, b), sub(a, c)].iter().map(|e| dot(*e, *e)).fold(0.0, f64::max);
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(n2 > 1e-12 * longest) {
                    en[0][0] = -1.0;
                    [0.0; 3]
                } else {
                    en[0][0] = n2;
                    scale(n, 1.0 / n2)
                }
            })
            .collect();
        let mut area = 0.0;
        let mut degenerate = Vec::new();
        for (i, en) in edge_normals.iter().enumerate() {
            let n2 = en[0][0];
            if n2 < 0.0 {
                degenerate.push(i);
            } else {
                area += 0.5 * n2;
            }
        }
        if !degenerate.is_empty() {
            let first: Vec<String> = degenerate.iter().take(5).map(|i| i.to_string()).collect();
            return Err(GkError::degenerate(format!(
                "mesh: {} degenerate triangle(s) (zero area or repeated corners), first: {}; repair the model (remove them) first",
                degenerate.len(),
                first.join(", ")
            )));
        }
        // the topology and pseudonormals (partly serial: the edges' counting sort, the
        // volume, the pass over the edges) beside the tree's build, which needs
        // neither: the idle core of the tree's serial stretches runs them. Each side is
        // computed as alone (no shared state), so the same bits
        let ((topology, normals, vertex_normals, edge_normals), bvh) = rayon::join(
            || {
                let edges = sorted_edges(&tris, nv);
                // the signed volume first: when negative (a closed mesh wound inwards, read
                // turned outwards) the normals are turned before the one pass over the edges
                // that sums the edge normals and counts the topology. A mesh that turns out
                // not closed is read as given: its normals turned back and its edge normals
                // summed again (the same values as summed once from the right normals)
                let signed = signed_volume(&verts, &tris);
                let turn = |normals: &mut Vec<V3>| {
                    for n in normals.iter_mut() {
                        *n = scale(*n, -1.0);
                    }
                };
                if signed < 0.0 {
                    turn(&mut normals);
                }
                let topology = topology(edge_pass(&tris, &normals, &edges, &mut edge_normals), signed);
                if topology.flipped != (signed < 0.0) {
                    turn(&mut normals);
                    edge_pass(&tris, &normals, &edges, &mut edge_normals);
                }
                let vertex_normals = pseudonormals(&verts, &tris, &normals, zeroed_in(edges.e, nv));
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

/// Every triangle's edge, grouped by its low vertex: the edges of low vertex v are
/// `e[start[v]..start[v + 1]]`, each `(high vertex << 32) | triangle`, sorted (distinct:
/// a triangle has one edge between two vertices, its corners being distinct), so the
/// runs of one high vertex are the groups of one undirected edge, their triangles in
/// increasing order. 8 bytes an edge (the low vertex is the group's, the edge's place in
/// the triangle is found from its corners): 24 MB at 1 M triangles.
pub(crate) struct Edges {
    start: Vec<usize>,
    e: Vec<u64>,
}

impl Edges {
    /// `f(low vertex, entries)` for the entries of each undirected edge, in the order of
    /// the low vertex, then the high one.
    #[inline(always)]
    fn for_each_group(&self, mut f: impl FnMut(u32, &[u64])) {
        for (v, w) in self.start.windows(2).enumerate() {
            let edges = &self.e[w[0]..w[1]];
            let mut i = 0;
            while i < edges.len() {
                let mut j = i + 1;
                while j < edges.len() && edges[j] >> 32 == edges[i] >> 32 {
                    j += 1;
                }
                f(v as u32, &edges[i..j]);
                i = j;
            }
        }
    }
}

/// `n` zero vectors written over the edges' buffer, which is no longer read: its pages are
/// already touched (the vertex pseudonormals' 12 MB at 1 M triangles need no fresh pages,
/// 3 k page faults), the unused rest given back. When the buffer is too small (more
/// vertices than triangles), a new vector.
fn zeroed_in(e: Vec<u64>, n: usize) -> Vec<V3> {
    let bytes = e.capacity() * std::mem::size_of::<u64>();
    if n == 0 || !bytes.is_multiple_of(std::mem::size_of::<V3>()) || bytes / std::mem::size_of::<V3>() < n {
        return vec![[0.0; 3]; n];
    }
    let cap = bytes / std::mem::size_of::<V3>();
    let mut e = std::mem::ManuallyDrop::new(e);
    let p = e.as_mut_ptr().cast::<V3>();
    // SAFETY: the allocation holds cap >= n vectors (its bytes, checked above) with the
    // alignment of u64, which is that of V3; it is not read through `e` again (forgotten);
    // the first n are written with zero bytes (0.0) before the vector is made of them
    unsafe {
        std::ptr::write_bytes(p, 0, n);
        let mut v = Vec::from_raw_parts(p, n, cap);
        v.shrink_to_fit();
        v
    }
}

const _: () = assert!(std::mem::align_of::<u64>() == std::mem::align_of::<V3>());

/// The triangle of an edge entry.
#[inline(always)]
fn tri_of(e: u64) -> usize {
    e as u32 as usize
}

/// Where the edge from `lo` of entry `e` is in triangle `t`: (k, forward): edge k runs from
/// corner k to k + 1, and forward when it runs from the low vertex to the high one.
#[inline(always)]
fn edge_in(t: &[u32; 3], lo: u32, e: u64) -> (usize, bool) {
    let hi = (e >> 32) as u32;
    // edge k leaves out corner k + 2
    let other = |v: u32| v != lo && v != hi;
    let k = if other(t[2]) {
        0
    } else if other(t[0]) {
        1
    } else {
        2
    };
    (k, t[k] == lo)
}

/// The triangles' edges grouped by low vertex ([`Edges`]): a counting sort by the low
/// vertex (linear, in triangle order), then each vertex's few edges sorted in parallel.
/// `tris` has no repeated corner (refused before).
fn sorted_edges(tris: &[[u32; 3]], nv: usize) -> Edges {
    use rayon::prelude::*;
    let low_high = |t: &[u32; 3], k: usize| {
        let (u, v) = (t[k], t[(k + 1) % 3]);
        (u.min(v), u.max(v))
    };
    // start[v + 1]: the number of edges of low vertex v, then where they begin, then
    // (advanced by the scatter) where they end, which is where those of v + 1 begin
    let mut start = vec![0usize; nv + 1];
    for t in tris {
        for k in 0..3 {
            start[low_high(t, k).0 as usize + 1] += 1;
        }
    }
    let mut at = 0;
    for s in &mut start[1..] {
        let count = *s;
        *s = at;
        at += count;
    }
    let mut e = vec![0u64; 3 * tris.len()];
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (lo, hi) = low_high(t, k);
            let at = &mut start[lo as usize + 1];
            e[*at] = ((hi as u64) << 32) | i as u64;
            *at += 1;
        }
    }
    // each vertex's edges sorted, in parallel by blocks of vertices
    const BLOCK: usize = 4096;
    let mut blocks = Vec::with_capacity(nv.div_ceil(BLOCK));
    let mut rest: &mut [u64] = &mut e;
    for v0 in (0..nv).step_by(BLOCK) {
        let v1 = (v0 + BLOCK).min(nv);
        let (block, tail) = std::mem::take(&mut rest).split_at_mut(start[v1] - start[v0]);
        blocks.push((v0, v1, block));
        rest = tail;
    }
    blocks.into_par_iter().for_each(|(v0, v1, block)| {
        for v in v0..v1 {
            block[start[v] - start[v0]..start[v + 1] - start[v0]].sort_unstable();
        }
    });
    Edges { start, e }
}

/// The signed enclosed volume, summed in triangle order (meaningful for a closed mesh:
/// negative when its triangles face inwards).
fn signed_volume(verts: &[V3], tris: &[[u32; 3]]) -> f64 {
    let mut volume = 0.0;
    for t in tris {
        let (a, b, c) = (verts[t[0] as usize], verts[t[1] as usize], verts[t[2] as usize]);
        volume += dot(a, cross(b, c)) / 6.0;
    }
    volume
}

/// One pass over the edge groups: each edge normal (the sum of the normals of the
/// triangles sharing the edge, in triangle order) written into `en` (every entry: each
/// triangle's edge is in one group), and the numbers of boundary edges, of edges shared
/// by more than two triangles, and of pairs run in the same direction.
fn edge_pass(tris: &[[u32; 3]], normals: &[V3], edges: &Edges, en: &mut [[V3; 3]]) -> [usize; 3] {
    let (mut boundary, mut nonmanifold, mut inconsistent) = (0usize, 0usize, 0usize);
    edges.for_each_group(|lo, g| {
        let mut sum = [0.0; 3];
        for &e in g {
            sum = add(sum, normals[tri_of(e)]);
        }
        // an edge's direction in a triangle: forward when it runs from its low to its high vertex
        let mut forward = [false; 2];
        for (i, &e) in g.iter().enumerate() {
            let t = tri_of(e);
            let (k, f) = edge_in(&tris[t], lo, e);
            en[t][k] = sum;
            forward[i.min(1)] = f;
        }
        match g.len() {
            1 => boundary += 1,
            2 => inconsistent += usize::from(forward[0] == forward[1]),
            _ => nonmanifold += 1,
        }
    });
    [boundary, nonmanifold, inconsistent]
}

/// The topology from the edge groups' counts ([`edge_pass`]) and the signed volume.
fn topology([boundary, nonmanifold, inconsistent]: [usize; 3], signed_volume: f64) -> Topology {
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
        volume = signed_volume;
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
    atan2_upper(norm(cross(u, v)), dot(u, v))
}

/// atan2(y, x) for y >= 0 (an angle in [0, pi]), within 2 units in the last place of
/// libm's (glibc 2.36; tested): Moshier's rational approximation of atan on [0, 0.66] with his reduction of
/// larger arguments by tan(3 pi / 8) and pi / 4 (Cephes Mathematical Library, atan.c; the
/// same constants as Go's math.Atan). A third of libm's instructions; the pseudonormals'
/// 3 M corner angles at 1 M triangles are weights, for which a few ulp do not matter.
// the constants as published, digit for digit (they round to the same f64)
#[allow(clippy::excessive_precision)]
pub(crate) fn atan2_upper(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    // atan of 0 <= t <= 0.66
    fn xatan(t: f64) -> f64 {
        const P: [f64; 5] = [-8.750608600031904122785e-01, -1.615753718733365076637e+01, -7.500855792314704667340e+01, -1.228866684490136173410e+02, -6.485021904942025371773e+01];
        const Q: [f64; 5] = [2.485846490142306297962e+01, 1.650270098316988542046e+02, 4.328810604912902668951e+02, 4.853903996359136964868e+02, 1.945506571482613964425e+02];
        let z = t * t;
        let z = z * ((((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4]) / (((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4]);
        t * z + t
    }
    // atan of y / x for y >= 0, x > 0 (pi / 2 = FRAC_PI_2 + MORE), the reductions' quotients
    // taken from y and x (one division before the approximation's own, not two)
    fn satan(y: f64, x: f64) -> f64 {
        const MORE: f64 = 6.123233995736765886130e-17;
        const TAN_3PI_8: f64 = 2.41421356237309504880;
        if y <= 0.66 * x {
            xatan(y / x)
        } else if y > TAN_3PI_8 * x {
            FRAC_PI_2 - xatan(x / y) + MORE
        } else {
            let (d, s) = (y - x, y + x);
            // (the quotient by way of y / x where y + x overflows)
            let t = if s.is_finite() { d / s } else { (y / x - 1.0) / (y / x + 1.0) };
            FRAC_PI_4 + xatan(t) + 0.5 * MORE
        }
    }
    if x > 0.0 {
        satan(y, x)
    } else if x < 0.0 {
        PI - satan(y, -x)
    } else if y > 0.0 {
        FRAC_PI_2
    } else {
        // atan2(0, +-0)
        if x.is_sign_negative() {
            PI
        } else {
            0.0
        }
    }
}

/// The vertex pseudonormals (the edge normals: [`edge_pass`]).
/// `vn`: `verts.len()` zeros.
fn pseudonormals(verts: &[V3], tris: &[[u32; 3]], normals: &[V3], mut vn: Vec<V3>) -> Vec<V3> {
    use rayon::prelude::*;
    // each vertex's pseudonormal: its corners' angle-weighted face normals summed in
    // triangle order. The vertices in ranges, one a thread, in parallel: each range
    // scans all the triangles for its own corners (no array of all angles, no
    // sequential scatter; the same sums in the same order, whatever the thread count)
    assert_eq!(vn.len(), verts.len());
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
    vn
}
