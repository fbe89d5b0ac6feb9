//! Exact 3-D quickhull (Barber, Dobkin & Huhdanpaa 1996) on distinct points.
//!
//! Visibility is decided by the exact sign of `orient3d`: a point sees a face
//! only when it lies strictly above its plane. The furthest point of a face's
//! outside set is chosen in floating point, which only affects speed. With
//! strict visibility degenerate input (coplanar faces, points on edges) yields
//! a correct triangulated hull that may contain coplanar neighbouring
//! triangles and non-extreme vertices; [`Hull::extreme_vertices`] removes those.

use super::exact::{cross, dot, orient3d, sub, P3};
use gagekit_core::{GkError, Result};

/// A triangulated convex polytope; every face is counter-clockwise seen from
/// outside, `nbrs[f][i]` is the face across the edge `(faces[f][i], faces[f][i+1])`.
pub struct Hull {
    pub faces: Vec<[u32; 3]>,
    pub nbrs: Vec<[u32; 3]>,
}

struct Face {
    v: [u32; 3],
    nb: [u32; 3],
    alive: bool,
    outside: Vec<u32>,
    normal: P3,
}

#[inline]
fn above(p: &[P3], v: [u32; 3], q: P3) -> bool {
    orient3d(p[v[0] as usize], p[v[1] as usize], p[v[2] as usize], q) < 0.0
}

fn new_face(p: &[P3], v: [u32; 3], nb: [u32; 3]) -> Face {
    let a = p[v[0] as usize];
    let normal = cross(sub(p[v[1] as usize], a), sub(p[v[2] as usize], a));
    Face {
        v,
        nb,
        alive: true,
        outside: Vec::new(),
        normal,
    }
}

fn edge_slot(v: &[u32; 3], from: u32, to: u32) -> Option<usize> {
    (0..3).find(|&i| v[i] == from && v[(i + 1) % 3] == to)
}

fn broken(what: &str) -> GkError {
    GkError::numerical(format!(
        "convex hull: inconsistent {what} (please report this input)"
    ))
}

/// Hull of the distinct points `p`, starting from the non-degenerate
/// tetrahedron `init` (indices into `p`).
pub fn hull3d(p: &[P3], init: [usize; 4]) -> Result<Hull> {
    let mut b = Builder::start(p, init)?;
    let mut stack: Vec<u32> = (0..4u32).filter(|&f| !b.faces[f as usize].outside.is_empty()).collect();
    while let Some(f) = stack.pop() {
        let f = f as usize;
        if !b.faces[f].alive || b.faces[f].outside.is_empty() {
            continue;
        }
        let q = b.furthest(f)?;
        b.mark_visible(f, p[q as usize]);
        b.chain_horizon()?;
        let base = b.cone(q)?;
        b.reassign_orphans(q, base);
        stack.extend((base..b.faces.len() as u32).filter(|&nf| !b.faces[nf as usize].outside.is_empty()));
    }
    b.finish()
}

/// The state of one quickhull run: the faces (dead ones kept, so indices stay valid) and
/// the work buffers of the current step.
struct Builder<'a> {
    p: &'a [P3],
    faces: Vec<Face>,
    /// `stamp` marks a face visible from the current apex, `stamp + 1` hidden.
    mark: Vec<u32>,
    stamp: u32,
    visible: Vec<u32>,
    /// Edges (u, w, hidden face) from a visible to a hidden face, one cycle.
    horizon: Vec<(u32, u32, u32)>,
    orphans: Vec<u32>,
}

impl<'a> Builder<'a> {
    /// The starting tetrahedron, its adjacency and the points outside each of its faces.
    fn start(p: &'a [P3], init: [usize; 4]) -> Result<Self> {
        let [a, b, c, d] = init.map(|i| i as u32);
        let mut faces: Vec<Face> = Vec::new();
        for t in [[a, b, c, d], [a, b, d, c], [a, c, d, b], [b, c, d, a]] {
            let mut v = [t[0], t[1], t[2]];
            if above(p, v, p[t[3] as usize]) {
                v.swap(1, 2);
            }
            faces.push(new_face(p, v, [0; 3]));
        }
        for f in 0..4 {
            for i in 0..3 {
                let (u, w) = (faces[f].v[i], faces[f].v[(i + 1) % 3]);
                let g = (0..4).find(|&g| edge_slot(&faces[g].v, w, u).is_some()).ok_or_else(|| broken("start"))?;
                faces[f].nb[i] = g as u32;
            }
        }
        for i in 0..p.len() {
            if init.contains(&i) {
                continue;
            }
            if let Some(f) = (0..4).find(|&f| above(p, faces[f].v, p[i])) {
                faces[f].outside.push(i as u32);
            }
        }
        let mark = vec![0; faces.len()];
        Ok(Self { p, faces, mark, stamp: 0, visible: Vec::new(), horizon: Vec::new(), orphans: Vec::new() })
    }

    /// The furthest point of face f's outside set (floating point: a heuristic only).
    fn furthest(&self, f: usize) -> Result<u32> {
        let p = self.p;
        let (apex, nrm) = (p[self.faces[f].v[0] as usize], self.faces[f].normal);
        self.faces[f]
            .outside
            .iter()
            .max_by(|&&x, &&y| {
                let dx = dot(nrm, sub(p[x as usize], apex));
                let dy = dot(nrm, sub(p[y as usize], apex));
                dx.total_cmp(&dy)
            })
            .copied()
            .ok_or_else(|| broken("outside set"))
    }

    /// Faces strictly visible from `qp`: a connected region around f (breadth-first).
    fn mark_visible(&mut self, f: usize, qp: P3) {
        self.stamp += 2;
        let stamp = self.stamp;
        self.visible.clear();
        self.visible.push(f as u32);
        self.mark[f] = stamp;
        let mut k = 0;
        while k < self.visible.len() {
            let g = self.visible[k] as usize;
            k += 1;
            for i in 0..3 {
                let h = self.faces[g].nb[i] as usize;
                if self.mark[h] == stamp || self.mark[h] == stamp + 1 {
                    continue;
                }
                if above(self.p, self.faces[h].v, qp) {
                    self.mark[h] = stamp;
                    self.visible.push(h as u32);
                } else {
                    self.mark[h] = stamp + 1;
                }
            }
        }
    }

    /// Horizon: the edges from a visible to a hidden face, sorted by their first vertex
    /// (each vertex starts one edge of the cycle).
    fn chain_horizon(&mut self) -> Result<()> {
        self.horizon.clear();
        for &g in &self.visible {
            let g = g as usize;
            for i in 0..3 {
                let h = self.faces[g].nb[i];
                if self.mark[h as usize] != self.stamp {
                    self.horizon.push((self.faces[g].v[i], self.faces[g].v[(i + 1) % 3], h));
                }
            }
        }
        self.horizon.sort_unstable_by_key(|e| e.0);
        if self.horizon.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(broken("horizon"));
        }
        Ok(())
    }

    /// The cone of new faces from the horizon to apex q, linked to each other and to the
    /// hidden faces; returns the index of the first new face.
    fn cone(&mut self, q: u32) -> Result<u32> {
        let m = self.horizon.len();
        let base = self.faces.len() as u32;
        let mut cur = 0usize;
        for k in 0..m {
            let (u, w, h) = self.horizon[cur];
            let nb = [h, base + ((k + 1) % m) as u32, base + ((k + m - 1) % m) as u32];
            self.faces.push(new_face(self.p, [u, w, q], nb));
            let hf = &mut self.faces[h as usize];
            let j = edge_slot(&hf.v, w, u).ok_or_else(|| broken("neighbour"))?;
            hf.nb[j] = base + k as u32;
            cur = self.horizon.binary_search_by_key(&w, |e| e.0).map_err(|_| broken("horizon cycle"))?;
            if (cur == 0) != (k + 1 == m) {
                return Err(broken("horizon cycle"));
            }
        }
        self.mark.resize(self.faces.len(), 0);
        Ok(base)
    }

    /// The visible faces die; their points go to the new face they see, if any.
    fn reassign_orphans(&mut self, q: u32, base: u32) {
        self.orphans.clear();
        for &g in &self.visible {
            let g = g as usize;
            self.faces[g].alive = false;
            self.orphans.append(&mut self.faces[g].outside);
        }
        for &o in &self.orphans {
            if o == q {
                continue;
            }
            let op = self.p[o as usize];
            if let Some(nf) = (base as usize..self.faces.len()).find(|&nf| above(self.p, self.faces[nf].v, op)) {
                self.faces[nf].outside.push(o);
            }
        }
    }

    /// The live faces, renumbered, with their adjacency.
    fn finish(self) -> Result<Hull> {
        let faces = self.faces;
        let mut remap = vec![u32::MAX; faces.len()];
        let mut out = Hull { faces: Vec::new(), nbrs: Vec::new() };
        for (f, face) in faces.iter().enumerate() {
            if face.alive {
                remap[f] = out.faces.len() as u32;
                out.faces.push(face.v);
            }
        }
        for face in faces.iter().filter(|f| f.alive) {
            out.nbrs.push(face.nb.map(|g| remap[g as usize]));
        }
        if out.nbrs.iter().flatten().any(|&g| g == u32::MAX) {
            return Err(broken("face adjacency"));
        }
        Ok(out)
    }
}

impl Hull {
    /// Vertices (indices into `p`) that are extreme points of the polytope: those
    /// whose incident triangles span at least three distinct planes. A vertex
    /// whose star is flat lies inside a facet, one whose star spans two planes
    /// lies inside an edge (decided exactly).
    pub fn extreme_vertices(&self, p: &[P3]) -> Vec<usize> {
        let mut star: Vec<Vec<u32>> = vec![Vec::new(); p.len()];
        for (f, v) in self.faces.iter().enumerate() {
            for &i in v {
                star[i as usize].push(f as u32);
            }
        }
        let coplanar = |r: [u32; 3], g: [u32; 3]| {
            let (a, b, c) = (p[r[0] as usize], p[r[1] as usize], p[r[2] as usize]);
            g.iter().all(|&x| orient3d(a, b, c, p[x as usize]) == 0.0)
        };
        let mut out = Vec::new();
        for (i, fs) in star.iter().enumerate() {
            let mut planes: Vec<[u32; 3]> = Vec::with_capacity(3);
            for &f in fs {
                let g = self.faces[f as usize];
                if planes.iter().all(|&r| !coplanar(r, g)) {
                    planes.push(g);
                    if planes.len() == 3 {
                        out.push(i);
                        break;
                    }
                }
            }
        }
        out
    }
}
