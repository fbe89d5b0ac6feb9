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
    Face { v, nb, alive: true, outside: Vec::new(), normal }
}

fn edge_slot(v: &[u32; 3], from: u32, to: u32) -> Option<usize> {
    (0..3).find(|&i| v[i] == from && v[(i + 1) % 3] == to)
}

fn broken(what: &str) -> GkError {
    GkError::numerical(format!("convex hull: inconsistent {what} (please report this input)"))
}

/// Hull of the distinct points `p`, starting from the non-degenerate
/// tetrahedron `init` (indices into `p`).
pub fn hull3d(p: &[P3], init: [usize; 4]) -> Result<Hull> {
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

    let mut stack: Vec<u32> = (0..4u32).filter(|&f| !faces[f as usize].outside.is_empty()).collect();
    let mut mark: Vec<u32> = vec![0; faces.len()];
    let mut stamp = 0u32;
    let mut visible: Vec<u32> = Vec::new();
    let mut horizon: Vec<(u32, u32, u32)> = Vec::new();
    let mut orphans: Vec<u32> = Vec::new();
    while let Some(f) = stack.pop() {
        let f = f as usize;
        if !faces[f].alive || faces[f].outside.is_empty() {
            continue;
        }
        // Furthest point (floating point: a heuristic only).
        let (apex, nrm) = (p[faces[f].v[0] as usize], faces[f].normal);
        let q = *faces[f]
            .outside
            .iter()
            .max_by(|&&x, &&y| {
                let dx = dot(nrm, sub(p[x as usize], apex));
                let dy = dot(nrm, sub(p[y as usize], apex));
                dx.total_cmp(&dy)
            })
            .ok_or_else(|| broken("outside set"))?;
        let qp = p[q as usize];

        // Faces strictly visible from q: a connected region (breadth-first).
        stamp += 2;
        visible.clear();
        visible.push(f as u32);
        mark[f] = stamp;
        let mut k = 0;
        while k < visible.len() {
            let g = visible[k] as usize;
            k += 1;
            for i in 0..3 {
                let h = faces[g].nb[i] as usize;
                if mark[h] == stamp || mark[h] == stamp + 1 {
                    continue;
                }
                if above(p, faces[h].v, qp) {
                    mark[h] = stamp;
                    visible.push(h as u32);
                } else {
                    mark[h] = stamp + 1;
                }
            }
        }
        // Horizon: edges from a visible to a hidden face, chained into one cycle.
        horizon.clear();
        for &g in &visible {
            let g = g as usize;
            for i in 0..3 {
                let h = faces[g].nb[i];
                if mark[h as usize] != stamp {
                    horizon.push((faces[g].v[i], faces[g].v[(i + 1) % 3], h));
                }
            }
        }
        horizon.sort_unstable_by_key(|e| e.0);
        if horizon.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(broken("horizon"));
        }
        let m = horizon.len();
        let base = faces.len() as u32;
        let mut cur = 0usize;
        for k in 0..m {
            let (u, w, h) = horizon[cur];
            let nb = [h, base + ((k + 1) % m) as u32, base + ((k + m - 1) % m) as u32];
            faces.push(new_face(p, [u, w, q], nb));
            let hf = &mut faces[h as usize];
            let j = edge_slot(&hf.v, w, u).ok_or_else(|| broken("neighbour"))?;
            hf.nb[j] = base + k as u32;
            cur = horizon.binary_search_by_key(&w, |e| e.0).map_err(|_| broken("horizon cycle"))?;
            if (cur == 0) != (k + 1 == m) {
                return Err(broken("horizon cycle"));
            }
        }
        mark.resize(faces.len(), 0);

        // Points of the removed faces go to the new face they see, if any.
        orphans.clear();
        for &g in &visible {
            let g = g as usize;
            faces[g].alive = false;
            orphans.append(&mut faces[g].outside);
        }
        for &o in &orphans {
            if o == q {
                continue;
            }
            let op = p[o as usize];
            if let Some(nf) = (base as usize..faces.len()).find(|&nf| above(p, faces[nf].v, op)) {
                faces[nf].outside.push(o);
            }
        }
        for nf in base as usize..faces.len() {
            if !faces[nf].outside.is_empty() {
                stack.push(nf as u32);
            }
        }
    }

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
