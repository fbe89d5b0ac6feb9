//! Signed distances of many points to a mesh, in parallel (rayon), deterministic.
//!
//! The points are taken in their own order when it is coherent (scan lines), else
//! sorted along a Morton curve ([`query_order`]), and cut into fixed chunks of [`CHUNK`];
//! inside a chunk, groups of [`GROUP`] consecutive points walk the tree together
//! ([`crate::bvh::Bvh::nearest_group`]: one read of a node for the group; neighbours on
//! the curve share the path from the root), each point's search bounded from the start
//! by the previous group's last nearest triangle (neighbours in the order are neighbours in
//! space, so most of the tree is pruned at once, whatever the order of the file). Each
//! answer is the nearest triangle, the lowest slot among exact ties: a function of the
//! point alone, so the order, the groups, the chunks and the thread count change the
//! speed only, never a bit of a result (results are scattered back into input order).
//!
//! The distance is exact for the mesh: the closest point of the nearest triangle
//! ([`crate::closest`]); inside a face it is the plane distance n . (p - a). Its sign
//! (closed meshes) is that of the pseudonormal of the closest feature (see [`crate::mesh`]):
//! positive outside the material.

use crate::bvh::{Nearest, GROUP};
use crate::closest::Feature;
use crate::mesh::TriMesh;
use gagekit_core::{check_coordinates, interrupt, GkError, Result, MAX_COORDINATE};
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

/// A point's memory between queries ([`TriMesh::hit_cached`]): the position last
/// searched from, the nearest triangle's slot there (`u32::MAX`: none yet) and the margin
/// (mm) within which no other triangle lies around that position; the runner-up's slot
/// (`u32::MAX`: none) and the margin within which no triangle but those two lies.
#[derive(Debug, Clone, Copy)]
pub struct Cache {
    pub slot: u32,
    pub second: u32,
    pub margin: f64,
    pub rest: f64,
    pub at: V3,
}

impl Cache {
    pub const EMPTY: Cache = Cache { slot: u32::MAX, second: u32::MAX, margin: 0.0, rest: 0.0, at: [0.0; 3] };
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

    /// [`TriMesh::hit`] for a point queried again and again as it moves a little (the
    /// iterations of an alignment, the next point of a scan line): `cache` holds a
    /// searched position, its nearest triangle and its margin (every other triangle was at
    /// least that far, [`crate::bvh::Bvh::nearest_with_runner_up`]). When the cached triangle
    /// is nearer to `p` than the margin less the distance from that position (by the
    /// triangle inequality no other triangle can be as near; with a slack far above
    /// rounding), it is the nearest and no search is made. Else, when the nearer of it and
    /// the cached runner-up is nearer than the margin of every other triangle less that
    /// distance, that one is the nearest (a point near an edge two triangles share, whose
    /// single margin is its own distance). Otherwise a search starting from the nearer
    /// refreshes the cache. The answer is the one [`TriMesh::hit`] gives with the cached
    /// triangle as hint, to the bit.
    #[inline]
    pub fn hit_cached(&self, p: V3, bound2: f64, cache: &mut Cache, signed: bool) -> Option<Hit> {
        let signed = signed && self.signed();
        let mut start = None;
        let slots = self.bvh.corners.len();
        if (cache.slot as usize) < slots {
            let mut n = self.bvh.to_slot(p, cache.slot);
            if cache.margin > 0.0 {
                let moved = norm(sub(p, cache.at));
                let scale = 1.0 + p[0].abs().max(p[1].abs()).max(p[2].abs());
                // n within the bound and nearer than `margin` less the move
                let certified = |n: &Nearest, margin: f64| {
                    let d = n.d2.sqrt();
                    n.d2 <= bound2 && d + moved + 2e-11 * (scale + d) < margin
                };
                if certified(&n, cache.margin) {
                    return Some(self.hit_of(p, &n, signed));
                }
                if (cache.second as usize) < slots {
                    let m = self.bvh.to_slot(p, cache.second);
                    if m.d2 < n.d2 || (m.d2 == n.d2 && m.slot < n.slot) {
                        n = m;
                    }
                    if certified(&n, cache.rest) {
                        return Some(self.hit_of(p, &n, signed));
                    }
                }
            }
            start = Some(n);
        }
        let r = self.bvh.nearest_with_runner_up(p, bound2, start);
        let n = r.best?;
        *cache = Cache { slot: n.slot, second: r.second, margin: r.margin2.sqrt(), rest: r.rest2.sqrt(), at: p };
        Some(self.hit_of(p, &n, signed))
    }

    /// Distances of every point (flat (n, 3), finite) to the surface; see [`Query`].
    /// The points are queried in a coherent order ([`query_order`]), in fixed chunks of
    /// [`CHUNK`], in groups of [`GROUP`] (module docs).
    pub fn distances(&self, points: &[f64], q: &Query) -> Result<Distances> {
        // the finiteness check in the parallel pass that takes the points' bounds (one
        // read of the points instead of two, the first of them serial); the error, naming
        // the first bad point, from the plain check
        // and the coordinates' range from that box (beyond +-MAX_COORDINATE: a damaged
        // file or a wrong unit; beyond 1e154 the squares would overflow and the point would
        // pass for one beyond `max_distance`)
        let (lo, hi, finite) = bounds_finite(points);
        let inside = (0..3).all(|k| lo[k] >= -MAX_COORDINATE && hi[k] <= MAX_COORDINATE);
        if points.len() % 3 != 0 || !finite || !inside {
            check_coordinates(points, 3, "points")?;
        }
        let bound2 = match q.max_distance {
            Some(m) if m.is_nan() || m < 0.0 => {
                return Err(GkError::invalid(format!("max_distance must be zero or positive, got {m}")));
            }
            Some(m) => m * m,
            None => f64::INFINITY,
        };
        let signed = !q.unsigned && self.signed();
        let n = points.len() / 3;
        if n > u32::MAX as usize {
            return Err(GkError::invalid(format!("points: {n} points, more than 2^32 - 1 in one call; split the cloud")));
        }
        // None: the points' own order (no identity vector of n indices to fill and read)
        let order = query_order_in(points, (lo, hi));
        // per point in query order: the distance, the triangle and (if asked) the foot.
        // All zero bits, so allocated zeroed (fresh pages, no pass writing them): `work`
        // writes every element of its chunk (each k of 0..len, in groups of GROUP), and
        // the chunks cover the arrays, before any is read; on an error none is returned
        let mut distance = vec![0.0; n];
        let mut triangle = vec![0i64; n];
        let mut foot = if q.foot { vec![0.0; 3 * n] } else { Vec::new() };
        // each chunk's work returns how many of its points have no triangle (beyond
        // `max_distance`), summed over the chunks: no pass over the triangles afterwards
        let work = |c: usize, d: &mut [f64], t: &mut [i64], mut f: Option<&mut [f64]>| -> Result<usize> {
            let mut beyond = 0;
            if c % 64 == 0 {
                interrupt::check()?;
            }
            // the previous group's last nearest triangle starts each point's search (its
            // distance bounds it: neighbours in the order are neighbours in space). One
            // start, not the first and last lanes' two: 300 k points of the torus bench,
            // 505 M against 528 M instructions
            let mut hint = u32::MAX;
            for k0 in (0..d.len()).step_by(GROUP) {
                let ks = k0..(k0 + GROUP).min(d.len());
                let mut ps = [[0.0; 3]; GROUP];
                let mut best: [Option<Nearest>; GROUP] = [None; GROUP];
                for (j, k) in ks.clone().enumerate() {
                    let i = match &order {
                        Some(o) => o[c * CHUNK + k] as usize,
                        None => c * CHUNK + k,
                    };
                    // one bounds check a point instead of three
                    let q = &points[3 * i..3 * i + 3];
                    ps[j] = [q[0], q[1], q[2]];
                }
                let g = ks.len();
                let nh = (hint != u32::MAX) as usize;
                self.bvh.nearest_group_from(&ps[..g], bound2, &[hint][..nh], &mut best[..g]);
                for (j, k) in ks.clone().enumerate() {
                    let (dk, tk, fk) = match &best[j] {
                        Some(n) => {
                            let h = self.hit_of(ps[j], n, signed);
                            (h.distance, h.triangle as i64, h.foot)
                        }
                        None => {
                            beyond += 1;
                            (f64::NAN, -1, [f64::NAN; 3])
                        }
                    };
                    d[k] = dk;
                    t[k] = tk;
                    if let Some(f) = f.as_deref_mut() {
                        f[3 * k..3 * k + 3].copy_from_slice(&fk);
                    }
                }
                let found = |j: usize| best[j].map_or(u32::MAX, |n| n.slot);
                let (a, b) = (found(0), found(g - 1));
                if b != u32::MAX {
                    hint = b;
                } else if a != u32::MAX {
                    hint = a;
                }
            }
            Ok(beyond)
        };
        let beyond = if q.foot {
            distance
                .par_chunks_mut(CHUNK)
                .zip(triangle.par_chunks_mut(CHUNK))
                .zip(foot.par_chunks_mut(3 * CHUNK))
                .enumerate()
                .map(|(c, ((d, t), f))| work(c, d, t, Some(f)))
                .try_reduce(|| 0, |a, b| Ok(a + b))?
        } else {
            distance.par_chunks_mut(CHUNK).zip(triangle.par_chunks_mut(CHUNK)).enumerate().map(|(c, (d, t))| work(c, d, t, None)).try_reduce(|| 0, |a, b| Ok(a + b))?
        };
        if let Some(order) = order {
            // back to input order
            let mut rank = vec![0u32; n];
            for (k, &i) in order.iter().enumerate() {
                rank[i as usize] = k as u32;
            }
            drop(order);
            distance = rank.par_iter().map(|&k| distance[k as usize]).collect();
            triangle = rank.par_iter().map(|&k| triangle[k as usize]).collect();
            if q.foot {
                foot = rank.par_iter().flat_map_iter(|&k| [foot[3 * k as usize], foot[3 * k as usize + 1], foot[3 * k as usize + 2]]).collect();
            }
        }
        Ok(Distances { distance, triangle, foot, beyond, signed })
    }
}

/// The order to query the points in: their own (None) when the file's order is already
/// coherent (the median step between consecutive points, on 4096 evenly spaced pairs, is
/// below 1/100 of the cloud's extent: scan lines), else [`morton_order`]. Only the speed
/// depends on it. Their own order is None rather than the identity permutation: 4 bytes
/// a point less to allocate, fill and read (56 MB at 14 M points).
pub fn query_order(points: &[f64]) -> Option<Vec<u32>> {
    let (lo, hi, _) = bounds_finite(points);
    query_order_in(points, (lo, hi))
}

/// [`query_order`] of points whose bounding box is `(lo, hi)`.
fn query_order_in(points: &[f64], (lo, hi): (V3, V3)) -> Option<Vec<u32>> {
    let n = points.len() / 3;
    if n < 2 {
        return None;
    }
    let at = |i: usize| [points[3 * i], points[3 * i + 1], points[3 * i + 2]];
    let m = 4096.min(n - 1);
    let mut steps: Vec<f64> = (0..m)
        .map(|k| {
            let i = ((k as u128 * (n - 1) as u128) / m as u128) as usize;
            let (a, b) = (at(i), at(i + 1));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .collect();
    let mid = steps.len() / 2;
    let median = *steps.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if median < 1e-2 * ext {
        None
    } else {
        Some(morton_order(points))
    }
}

/// The bounding box of the points (flat (n, 3)) and whether every coordinate is finite
/// (the box of the finite ones when not: `f64::min` and `max` skip a NaN). Blocks of
/// 4096 points in parallel, each checked without a branch a value.
fn bounds_finite(points: &[f64]) -> (V3, V3, bool) {
    points
        .par_chunks(3 * 4096)
        .map(|c| {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            let mut ok = true;
            for p in c.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                    ok &= p[k].is_finite();
                }
            }
            (lo, hi, ok)
        })
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], true),
            |a, b| ([a.0[0].min(b.0[0]), a.0[1].min(b.0[1]), a.0[2].min(b.0[2])], [a.1[0].max(b.1[0]), a.1[1].max(b.1[1]), a.1[2].max(b.1[2])], a.2 & b.2),
        )
}

/// Spread the low 21 bits of `v` to every third bit.
#[inline]
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x1f00000000ffff;
    x = (x | x << 16) & 0x1f0000ff0000ff;
    x = (x | x << 8) & 0x100f00f00f00f00f;
    x = (x | x << 4) & 0x10c30c30c30c30c3;
    (x | x << 2) & 0x1249249249249249
}

/// The indices of the points (flat (n, 3), finite) sorted along a Morton (Z-order) curve
/// over their bounding cube, 21 bits per axis (ties: the input order). Neighbours on the
/// curve are neighbours in space, so each query starts from a near triangle and reads
/// the part of the tree its predecessor read; the order depends on the points only.
pub fn morton_order(points: &[f64]) -> Vec<u32> {
    let n = points.len() / 3;
    let (lo, hi, _) = bounds_finite(points);
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let scale = if ext > 0.0 { ((1u64 << 21) - 1) as f64 / ext } else { 0.0 };
    let mut keys: Vec<(u64, u32)> = points
        .par_chunks_exact(3)
        .enumerate()
        .map(|(i, p)| {
            let c = |k: usize| spread(((p[k] - lo[k]) * scale) as u64);
            (c(0) | c(1) << 1 | c(2) << 2, i as u32)
        })
        .collect();
    debug_assert_eq!(keys.len(), n);
    keys.par_sort_unstable();
    keys.into_iter().map(|(_, i)| i).collect()
}
