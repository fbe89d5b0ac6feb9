//! Signed distances of many points to a mesh, in parallel (rayon), deterministic.
//!
//! The points are cut into fixed chunks of [`CHUNK`]; inside a chunk they are queried in
//! order, each starting from the previous point's nearest triangle (its distance bounds
//! the search: a scan's consecutive points are neighbours, so most of the tree is pruned
//! at once). Chunks never depend on the thread count, so neither does any result.
//!
//! The distance is exact for the mesh: the closest point of the nearest triangle
//! ([`crate::closest`]); inside a face it is the plane distance n . (p - a). Its sign
//! (closed meshes) is that of the pseudonormal of the closest feature (see [`crate::mesh`]):
//! positive outside the material.

use crate::bvh::Nearest;
use crate::closest::Feature;
use crate::mesh::TriMesh;
use gagekit_core::{check_finite, interrupt, GkError, Result};
use gagekit_gdt::vec3::{dot, norm, scale, sub, V3};
use rayon::prelude::*;

/// Points per chunk of work (fixed: results never depend on the thread count).
pub const CHUNK: usize = 256;

/// What to compute.
#[derive(Debug, Clone, Copy, Default)]
pub struct Query {
    /// points farther than this get no triangle (`triangle = -1`, distance NaN) and are counted
    pub max_distance: Option<f64>,
    /// unsigned distances even on a closed mesh
    pub unsigned: bool,
    /// also return each point's closest point of the surface
    pub foot: bool,
}

/// Per point: the distance (signed when [`Distances::signed`]), the nearest triangle
/// (-1 beyond `max_distance`) and, if asked, the closest point (flat, 3 per point).
#[derive(Debug, Clone)]
pub struct Distances {
    pub distance: Vec<f64>,
    pub triangle: Vec<i64>,
    pub foot: Vec<f64>,
    pub beyond: usize,
    pub signed: bool,
}

/// One point's answer: the triangle (input index), the distance, the closest point, the
/// unit gradient of the distance with respect to the point (the face normal inside a
/// face, (p - c) / |p - c| elsewhere, signed like the distance) and the leaf slot.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub slot: u32,
    pub triangle: u32,
    pub distance: f64,
    pub foot: V3,
    pub gradient: V3,
    pub feature: Feature,
}

impl TriMesh {
    /// Turn a nearest triangle into a (signed) hit.
    #[inline]
    pub fn hit_of(&self, p: V3, n: &Nearest, signed: bool) -> Hit {
        let t = self.bvh.order[n.slot as usize];
        let fnrm = self.face_normals[t as usize];
        let (distance, gradient) = match n.feature {
            Feature::Face => {
                let a = self.bvh.corners[n.slot as usize][0];
                let d = dot(fnrm, sub(p, a));
                if signed || d >= 0.0 {
                    (if signed { d } else { d.abs() }, fnrm)
                } else {
                    (-d, scale(fnrm, -1.0))
                }
            }
            Feature::Edge(_) | Feature::Vertex(_) => {
                let pn = match n.feature {
                    Feature::Edge(k) => self.edge_normals[t as usize][k as usize],
                    Feature::Vertex(k) => self.vertex_normals[self.triangles[t as usize][k as usize] as usize],
                    Feature::Face => unreachable!(),
                };
                let v = sub(p, n.foot);
                let d = n.d2.sqrt();
                if d == 0.0 {
                    let l = norm(pn);
                    (0.0, if l > 0.0 { scale(pn, 1.0 / l) } else { fnrm })
                } else {
                    let g = scale(v, 1.0 / d);
                    if signed && dot(pn, v) < 0.0 {
                        (-d, scale(g, -1.0))
                    } else {
                        (d, g)
                    }
                }
            }
        };
        Hit { slot: n.slot, triangle: t, distance, foot: n.foot, gradient, feature: n.feature }
    }

    /// The nearest point of the surface to `p` within `sqrt(bound2)`, signed if asked
    /// and the mesh is closed. `hint`: a leaf slot to try first.
    #[inline]
    pub fn hit(&self, p: V3, bound2: f64, hint: Option<u32>, signed: bool) -> Option<Hit> {
        self.bvh.nearest(p, bound2, hint).map(|n| self.hit_of(p, &n, signed && self.signed()))
    }

    /// Distances of every point (flat (n, 3), finite) to the surface; see [`Query`].
    pub fn distances(&self, points: &[f64], q: &Query) -> Result<Distances> {
        check_finite(points, 3, "points")?;
        let bound2 = match q.max_distance {
            Some(m) if m.is_nan() || m < 0.0 => {
                return Err(GkError::invalid(format!("max_distance must be zero or positive, got {m}")));
            }
            Some(m) => m * m,
            None => f64::INFINITY,
        };
        let signed = !q.unsigned && self.signed();
        let n = points.len() / 3;
        let mut distance = vec![0.0; n];
        let mut triangle = vec![-1i64; n];
        let work = |c: usize, d: &mut [f64], t: &mut [i64], mut f: Option<&mut [f64]>| -> Result<()> {
            if c % 64 == 0 {
                interrupt::check()?;
            }
            let mut hint = None;
            for k in 0..d.len() {
                let i = c * CHUNK + k;
                let p = [points[3 * i], points[3 * i + 1], points[3 * i + 2]];
                match self.hit(p, bound2, hint, signed) {
                    Some(h) => {
                        d[k] = h.distance;
                        t[k] = h.triangle as i64;
                        hint = Some(h.slot);
                        if let Some(f) = f.as_deref_mut() {
                            f[3 * k..3 * k + 3].copy_from_slice(&h.foot);
                        }
                    }
                    None => {
                        d[k] = f64::NAN;
                        t[k] = -1;
                        if let Some(f) = f.as_deref_mut() {
                            f[3 * k..3 * k + 3].copy_from_slice(&[f64::NAN; 3]);
                        }
                    }
                }
            }
            Ok(())
        };
        let mut foot = Vec::new();
        if q.foot {
            foot = vec![0.0; 3 * n];
            distance
                .par_chunks_mut(CHUNK)
                .zip(triangle.par_chunks_mut(CHUNK))
                .zip(foot.par_chunks_mut(3 * CHUNK))
                .enumerate()
                .try_for_each(|(c, ((d, t), f))| work(c, d, t, Some(f)))?;
        } else {
            distance
                .par_chunks_mut(CHUNK)
                .zip(triangle.par_chunks_mut(CHUNK))
                .enumerate()
                .try_for_each(|(c, (d, t))| work(c, d, t, None))?;
        }
        let beyond = triangle.iter().filter(|&&t| t < 0).count();
        Ok(Distances { distance, triangle, foot, beyond, signed })
    }
}
