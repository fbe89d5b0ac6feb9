//! Akl–Toussaint prefilter, run in parallel with rayon.
//!
//! 1. A frame from the covariance of a sample of the points (heuristic only),
//!    so that directions adapt to thin sets such as a scanned face.
//! 2. The extreme input points along a set of directions in that frame (first
//!    round: extremes of the sample only, which is cheap).
//! 3. Their exact hull `P` (checked convex, exactly); every point strictly
//!    inside `P` is discarded. A point is first tried against boxes proven to
//!    lie inside `P` ([`InnerGrid`]); otherwise it is located by a cube map
//!    from an interior centre `c` to the face of `P` its ray `c -> x` crosses,
//!    then decided exactly: `x` lies in the cone from `c` over that face (three
//!    orientation signs) and strictly below the face's plane, hence strictly
//!    inside `P` and not a vertex of the hull of the input. Signs come from a
//!    semi-static floating-point filter with Shewchuk's error bound, falling
//!    back to the adaptive exact predicate. Any doubt (failed location) keeps
//!    the point, so the filter is exact whatever the heuristics do.
//!
//! Rounds repeat on the survivors with more directions while that pays off.

use super::exact::{cross, dot, orient3d, pt, sub, P3};
use super::inner::{InnerGrid, MAX_SIDE};
use super::quickhull::hull3d;
use super::{distinct, simplex, Simplex};
use rayon::prelude::*;
use std::ops::Range;

const CHUNK: usize = 16 * 1024;
/// Cube-map resolution (cells per cube-face side).
const GRID: usize = 16;
/// Steps of the face walk before a point is kept undecided.
const MAX_WALK: usize = 24;
/// Stop prefiltering once this few points survive.
const ENOUGH: usize = 2_000;
/// Size of the sample behind the frame and the first polytope.
const SAMPLE: usize = 16_384;

/// Indices (ascending) of the points not discarded.
pub fn survivors(points: &[f64]) -> Vec<usize> {
    let n = points.len() / 3;
    let (frame, sample) = Frame::new(points);
    // Round 1: a polytope from the extremes of the sample only (cheap), used on
    // every point. Later rounds: exact extremes of the survivors.
    let mut ids: Option<Vec<usize>> = None;
    for (round, k) in [(0, 120usize), (1, 60), (2, 240)] {
        let len = ids.as_ref().map_or(n, |v| v.len());
        if len <= ENOUGH {
            break;
        }
        let dirs: Vec<P3> = directions(k)
            .into_iter()
            .map(|u| frame.to_world_normal(u))
            .collect();
        let (ext, bbox) = if round == 0 {
            (
                extremes(points, Some(&sample), &dirs).0,
                bounding_box(points),
            )
        } else {
            extremes(points, ids.as_deref(), &dirs)
        };
        let Some(poly) = Polytope::new(points, ext, &frame, bbox, inner_side(round, len)) else {
            break;
        };
        let kept = poly.filter(points, ids.as_deref());
        let done = round > 0 && kept.len() * 2 > len; // less than half removed: stop
        ids = Some(kept);
        if done {
            break;
        }
    }
    ids.unwrap_or_else(|| (0..n).collect())
}

/// Cells per side of the inner grid: about 1000 points per cell, worth its
/// set-up from 16 x 16 cells on; first round only (later rounds test points
/// near the boundary, which the grid misses).
fn inner_side(round: usize, len: usize) -> usize {
    let side = ((len as f64 / 1000.0).sqrt() as usize).min(MAX_SIDE);
    if round == 0 && side >= 16 {
        side
    } else {
        0
    }
}

fn par_chunks<T: Send>(len: usize, f: impl Fn(Range<usize>) -> T + Sync + Send) -> Vec<T> {
    (0..len.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| f(c * CHUNK..((c + 1) * CHUNK).min(len)))
        .collect()
}

/// Unit directions: the 13 of a cube (axes, face and body diagonals) or a
/// Fibonacci sphere of `k` directions (each used both ways).
fn directions(k: usize) -> Vec<P3> {
    let norm = |v: P3| {
        let l = dot(v, v).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    if k == 13 {
        let mut d = Vec::new();
        for x in -1i32..=1 {
            for y in -1i32..=1 {
                for z in -1i32..=1 {
                    let v = [x, y, z];
                    // one of each antipodal pair: first non-zero component positive
                    if v.iter().find(|&&c| c != 0).is_some_and(|&c| c > 0) {
                        d.push(norm([x as f64, y as f64, z as f64]));
                    }
                }
            }
        }
        return d;
    }
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..k)
        .map(|i| {
            let z = 1.0 - (i as f64 + 0.5) / k as f64; // upper hemisphere only
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            [r * t.cos(), r * t.sin(), z]
        })
        .collect()
}

/// Principal frame of a sample: `w = S^-1 Q^T (x - mean)`.
struct Frame {
    q: [P3; 3],  // rows: principal axes
    s: P3,       // standard deviations along them (floored)
    qs: [P3; 3], // rows q[k] / s[k]
}

impl Frame {
    /// The frame and the indices of the sample it was computed from.
    fn new(points: &[f64]) -> (Self, Vec<usize>) {
        let n = points.len() / 3;
        let stride = (n / SAMPLE).max(1);
        let ids: Vec<usize> = (0..n).step_by(stride).collect();
        let sample: Vec<P3> = ids.iter().map(|&i| pt(points, i)).collect();
        let m = sample.len() as f64;
        let mut mean = [0.0; 3];
        for p in &sample {
            for k in 0..3 {
                mean[k] += p[k] / m;
            }
        }
        let mut cov = [[0.0; 3]; 3];
        for p in &sample {
            let d = sub(*p, mean);
            for r in 0..3 {
                for c in 0..3 {
                    cov[r][c] += d[r] * d[c] / m;
                }
            }
        }
        let (vals, q) = jacobi_eigen(cov);
        let top = vals.iter().cloned().fold(0.0, f64::max);
        let floor = (top * 1e-12).max(f64::MIN_POSITIVE);
        let s = vals.map(|v| v.max(floor).sqrt());
        let qs = [0, 1, 2].map(|k| q[k].map(|c| c / s[k]));
        (Frame { q, s, qs }, ids)
    }

    /// The coordinate axis closest to the direction of least spread.
    fn flat_axis(&self) -> usize {
        let k = (0..3)
            .min_by(|&a, &b| self.s[a].total_cmp(&self.s[b]))
            .unwrap_or(2);
        (0..3)
            .max_by(|&a, &b| self.q[k][a].abs().total_cmp(&self.q[k][b].abs()))
            .unwrap_or(2)
    }

    /// World vector whose dot product with `x` ranks points as `u . w(x)` does.
    fn to_world_normal(&self, u: P3) -> P3 {
        let a = [u[0] / self.s[0], u[1] / self.s[1], u[2] / self.s[2]];
        self.mat_q(a)
    }

    /// World direction of the whitened direction `w`.
    fn to_world_dir(&self, w: P3) -> P3 {
        self.mat_q([w[0] * self.s[0], w[1] * self.s[1], w[2] * self.s[2]])
    }

    fn mat_q(&self, a: P3) -> P3 {
        let q = &self.q;
        [
            q[0][0] * a[0] + q[1][0] * a[1] + q[2][0] * a[2],
            q[0][1] * a[0] + q[1][1] * a[1] + q[2][1] * a[2],
            q[0][2] * a[0] + q[1][2] * a[1] + q[2][2] * a[2],
        ]
    }

    /// Whitened coordinates of a world vector.
    #[inline]
    fn whiten(&self, d: P3) -> P3 {
        [dot(self.qs[0], d), dot(self.qs[1], d), dot(self.qs[2], d)]
    }
}

/// Eigenvalues and eigenvectors (as rows = columns of Q) of a symmetric 3x3
/// matrix by cyclic Jacobi rotations.
#[allow(clippy::needless_range_loop)]
pub(super) fn jacobi_eigen(mut a: [[f64; 3]; 3]) -> (P3, [P3; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= 1e-300 {
            break;
        }
        for (p, r) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][r] == 0.0 {
                continue;
            }
            let theta = (a[r][r] - a[p][p]) / (2.0 * a[p][r]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with J the rotation in the (p, r) plane
            for k in 0..3 {
                let (akp, akr) = (a[k][p], a[k][r]);
                a[k][p] = c * akp - s * akr;
                a[k][r] = s * akp + c * akr;
            }
            for k in 0..3 {
                let (apk, ark) = (a[p][k], a[r][k]);
                a[p][k] = c * apk - s * ark;
                a[r][k] = s * apk + c * ark;
            }
            for row in v.iter_mut() {
                let (vp, vr) = (row[p], row[r]);
                row[p] = c * vp - s * vr;
                row[r] = s * vp + c * vr;
            }
        }
    }
    // columns of v are eigenvectors; return them as rows of q
    let q = [0, 1, 2].map(|k| [v[0][k], v[1][k], v[2][k]]);
    ([a[0][0], a[1][1], a[2][2]], q)
}

/// Indices of the points with the largest and smallest `d . x` for each `d`,
/// and the bounding box of the points.
fn extremes(points: &[f64], ids: Option<&[usize]>, dirs: &[P3]) -> (Vec<usize>, Bbox) {
    let len = ids.map_or(points.len() / 3, |v| v.len());
    let k = dirs.len();
    let parts = par_chunks(len, |r| {
        let mut best = vec![(f64::NEG_INFINITY, 0usize); 2 * k];
        let mut bb = Bbox::empty();
        for pos in r {
            let i = ids.map_or(pos, |v| v[pos]);
            let x = pt(points, i);
            bb.add(x);
            for (j, d) in dirs.iter().enumerate() {
                let s = dot(*d, x);
                if s > best[2 * j].0 {
                    best[2 * j] = (s, i);
                }
                if -s > best[2 * j + 1].0 {
                    best[2 * j + 1] = (-s, i);
                }
            }
        }
        (best, bb)
    });
    let mut best = vec![(f64::NEG_INFINITY, 0usize); 2 * k];
    let mut bb = Bbox::empty();
    for (part, pb) in parts {
        bb.add(pb.lo);
        bb.add(pb.hi);
        for (b, p) in best.iter_mut().zip(part) {
            if p.0 > b.0 {
                *b = p;
            }
        }
    }
    (
        best.into_iter()
            .filter(|b| b.0 > f64::NEG_INFINITY)
            .map(|b| b.1)
            .collect(),
        bb,
    )
}

fn bounding_box(points: &[f64]) -> Bbox {
    let parts = par_chunks(points.len() / 3, |r| {
        let mut bb = Bbox::empty();
        for x in points[3 * r.start..3 * r.end].chunks_exact(3) {
            bb.add([x[0], x[1], x[2]]);
        }
        bb
    });
    let mut bb = Bbox::empty();
    for pb in parts {
        bb.add(pb.lo);
        bb.add(pb.hi);
    }
    bb
}

#[derive(Clone, Copy)]
struct Bbox {
    lo: P3,
    hi: P3,
}

impl Bbox {
    fn empty() -> Self {
        Bbox {
            lo: [f64::INFINITY; 3],
            hi: [f64::NEG_INFINITY; 3],
        }
    }
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn add(&mut self, x: P3) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(x[k]);
            self.hi[k] = self.hi[k].max(x[k]);
        }
    }
}

/// The exact hull of some input points, with a point-location cube map.
struct Polytope<'f> {
    frame: &'f Frame,
    centre: P3,
    faces: Vec<[P3; 3]>,
    nbrs: Vec<[u32; 3]>,
    cells: Vec<u32>,
    /// Per face: the planes through the centre and each edge, then the face plane.
    planes: Vec<[Plane; 4]>,
    /// Proven inner boxes (first round only).
    inner: Option<InnerGrid>,
}

/// `orient3d` with three fixed points, `a` being the reference: the floating
/// value `(x - a) . n` with `n = (b - a) x (c - a)` has the structure of
/// Shewchuk's `orient3d(x, b, c, a)` (a sum of three rounded differences times
/// 2x2 minors of rounded differences), so his stage-A bound
/// `|error| <= o3derrboundA * permanent` applies. The permanent is bounded once
/// for all points of the bounding box (a semi-static filter); points within the
/// bound go to the exact adaptive predicate.
#[derive(Clone, Copy)]
struct Plane {
    a: P3,
    n: P3,
    bound: f64,
}

/// Shewchuk's `o3derrboundA = (7 + 56 eps) eps`, eps = 2^-53.
const O3D_ERR_A: f64 = (7.0 + 56.0 * f64::EPSILON / 2.0) * (f64::EPSILON / 2.0);

impl Plane {
    fn new(a: P3, b: P3, c: P3, bbox: &Bbox) -> Self {
        let (u, v) = (sub(b, a), sub(c, a));
        let n = cross(u, v);
        let perm = [
            (u[1] * v[2]).abs() + (u[2] * v[1]).abs(),
            (u[2] * v[0]).abs() + (u[0] * v[2]).abs(),
            (u[0] * v[1]).abs() + (u[1] * v[0]).abs(),
        ];
        // |fl(x - a)| <= max(|fl(lo - a)|, |fl(hi - a)|) (rounding is monotone)
        let w: P3 = [0, 1, 2].map(|k| (bbox.lo[k] - a[k]).abs().max((bbox.hi[k] - a[k]).abs()));
        // The margin covers the rounding of this permanent bound itself.
        let bound = O3D_ERR_A * dot(w, perm) * (1.0 + 1e-9);
        Plane { a, n, bound }
    }

    /// Sign of `(x - a) . ((b - a) x (c - a))`: `Some(true)` when certainly
    /// negative (`orient3d(a, b, c, x) > 0`), `Some(false)` when certainly
    /// positive, `None` when the floating-point value cannot tell (then ask the
    /// exact predicate).
    #[inline(always)]
    fn below(&self, x: P3) -> Option<bool> {
        let w = sub(x, self.a);
        let det = w[0] * self.n[0] + w[1] * self.n[1] + w[2] * self.n[2];
        let bound = self.bound;
        if det < -bound {
            Some(true)
        } else if det > bound {
            Some(false)
        } else {
            None
        }
    }
}

impl<'f> Polytope<'f> {
    fn new(
        points: &[f64],
        ext: Vec<usize>,
        frame: &'f Frame,
        bbox: Bbox,
        inner_side: usize,
    ) -> Option<Self> {
        let ids = distinct(points, ext);
        if ids.len() < 4 {
            return None;
        }
        let p: Vec<P3> = ids.iter().map(|&i| pt(points, i)).collect();
        let Simplex::Solid(init) = simplex(&p) else {
            return None;
        };
        let hull = hull3d(&p, init).ok()?;
        let faces: Vec<[P3; 3]> = hull
            .faces
            .iter()
            .map(|f| f.map(|i| p[i as usize]))
            .collect();
        let mut used: Vec<u32> = hull.faces.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        let mut centre = [0.0; 3];
        for &i in &used {
            for k in 0..3 {
                centre[k] += p[i as usize][k] / used.len() as f64;
            }
        }
        // Safety net, decided exactly: the polytope is convex (no vertex above
        // any face plane) and the centre strictly inside. Otherwise no filtering.
        let below_all = |x: P3, strict: bool| {
            faces.iter().all(|f| {
                let o = orient3d(f[0], f[1], f[2], x);
                o > 0.0 || (!strict && o == 0.0)
            })
        };
        if !used.iter().all(|&i| below_all(p[i as usize], false)) || !below_all(centre, true) {
            return None;
        }
        let planes = faces
            .iter()
            .map(|f| {
                [
                    (centre, f[0], f[1]),
                    (centre, f[1], f[2]),
                    (centre, f[2], f[0]),
                    (f[0], f[1], f[2]),
                ]
                .map(|(a, b, c)| Plane::new(a, b, c, &bbox))
            })
            .collect();
        let mut poly = Polytope {
            frame,
            centre,
            faces,
            nbrs: hull.nbrs,
            cells: Vec::new(),
            planes,
            inner: None,
        };
        poly.cells = poly.cell_table();
        if inner_side > 0 {
            let axis = frame.flat_axis();
            let inside = |x: P3| {
                poly.planes.iter().zip(&poly.faces).all(|(pl, f)| {
                    pl[3]
                        .below(x)
                        .unwrap_or_else(|| orient3d(f[0], f[1], f[2], x) > 0.0)
                })
            };
            poly.inner = InnerGrid::build(inner_side, &poly.faces, inside, axis, bbox.lo, bbox.hi);
        }
        Some(poly)
    }

    /// For each cube-map cell, the face through which the ray from the centre
    /// along the cell's central direction leaves (floating point: a hint only).
    fn cell_table(&self) -> Vec<u32> {
        // outward normal n and n . (a - centre) of every face
        let nh: Vec<(P3, f64)> = self
            .faces
            .iter()
            .map(|v| {
                let n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
                (n, dot(n, sub(v[0], self.centre)))
            })
            .collect();
        (0..6 * GRID * GRID)
            .map(|c| {
                let d = self.frame.to_world_dir(cell_dir(c));
                let mut best = (f64::INFINITY, 0u32);
                for (f, &(n, h)) in nh.iter().enumerate() {
                    let den = dot(n, d);
                    if den > 0.0 && h < best.0 * den {
                        best = (h / den, f as u32);
                    }
                }
                best.1
            })
            .collect()
    }

    /// True only if `x` is strictly inside the polytope (exact).
    #[inline]
    fn strictly_inside(&self, x: P3) -> bool {
        if self.inner.as_ref().is_some_and(|g| g.contains(x)) {
            return true;
        }
        let c = self.centre;
        let wc = sub(x, c);
        let mut f = self.cells[cell_of(self.frame.whiten(wc))] as usize;
        // Fast path, straight-line: all four filtered signs certain and right.
        let pl = &self.planes[f];
        let wa = sub(x, pl[3].a);
        let d = [
            dot(wc, pl[0].n),
            dot(wc, pl[1].n),
            dot(wc, pl[2].n),
            dot(wa, pl[3].n),
        ];
        if (d[3] < -pl[3].bound)
            & (d[0] > pl[0].bound)
            & (d[1] > pl[1].bound)
            & (d[2] > pl[2].bound)
        {
            return true;
        }

        'walk: for _ in 0..MAX_WALK {
            let [a, b, e] = self.faces[f];
            let pl = &self.planes[f];
            // Strictly below the face plane?  orient3d(a, b, e, x) > 0.
            let below = pl[3].below(x).unwrap_or_else(|| orient3d(a, b, e, x) > 0.0);
            if !below {
                return false;
            }
            // In the cone from the centre over the face?  Leave through the
            // first edge where orient3d(c, v_i, v_i+1, x) > 0.
            for (i, (u, v)) in [(a, b), (b, e), (e, a)].into_iter().enumerate() {
                if pl[i].below(x).unwrap_or_else(|| orient3d(c, u, v, x) > 0.0) {
                    f = self.nbrs[f][i] as usize;
                    continue 'walk;
                }
            }
            return true;
        }
        false
    }

    fn filter(&self, points: &[f64], ids: Option<&[usize]>) -> Vec<usize> {
        let len = ids.map_or(points.len() / 3, |v| v.len());
        let parts = par_chunks(len, |r| {
            r.map(|pos| ids.map_or(pos, |v| v[pos]))
                .filter(|&i| !self.strictly_inside(pt(points, i)))
                .collect::<Vec<usize>>()
        });
        parts.concat()
    }
}

/// Cube-map cell of a (whitened) direction.
#[inline]
fn cell_of(w: P3) -> usize {
    let ab = [w[0].abs(), w[1].abs(), w[2].abs()];
    // the dominant axis, the coordinate along it, and the other two in cyclic order
    let (m, wm, a, b) = if ab[0] >= ab[1] && ab[0] >= ab[2] {
        (0, w[0], w[1], w[2])
    } else if ab[1] >= ab[2] {
        (1, w[1], w[2], w[0])
    } else {
        (2, w[2], w[0], w[1])
    };
    let am = wm.abs();
    if !(am > 0.0 && am < f64::INFINITY) {
        return 0; // zero, infinite or NaN
    }
    let side = 2 * m + usize::from(wm < 0.0);
    let r = 1.0 / am;
    let (u, v) = (a * r, b * r);
    // t is within [-1, 1] up to rounding: the i32 conversion truncates as the usize one
    // did (toward zero, a tiny negative to 0), with fewer instructions
    let g = |t: f64| (((t + 1.0) * 0.5 * GRID as f64) as i32).clamp(0, GRID as i32 - 1) as usize;
    (side * GRID + g(u)) * GRID + g(v)
}

/// Whitened direction through the centre of cell `c` (inverse of [`cell_of`]).
fn cell_dir(c: usize) -> P3 {
    let (side, rest) = (c / (GRID * GRID), c % (GRID * GRID));
    let (i, j) = (rest / GRID, rest % GRID);
    let m = side / 2;
    let sign = if side % 2 == 1 { -1.0 } else { 1.0 };
    let mid = |k: usize| (k as f64 + 0.5) / GRID as f64 * 2.0 - 1.0;
    let mut w = [0.0; 3];
    w[m] = sign;
    w[(m + 1) % 3] = mid(i);
    w[(m + 2) % 3] = mid(j);
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The semi-static filter never contradicts the exact predicate, also for
    /// points within rounding distance of the plane.
    #[test]
    fn plane_filter_agrees_with_exact_orientation() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut decided = 0;
        for _ in 0..200 {
            let scale = 10f64.powi(rng.random_range(-3..4));
            let mut r = || [0, 1, 2].map(|_| (rng.random::<f64>() - 0.5) * scale);
            let (a, b, c) = (r(), r(), r());
            let xs: Vec<P3> = (0..200)
                .map(|k| {
                    let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
                    let off = if k % 2 == 0 {
                        0.0
                    } else {
                        (rng.random::<f64>() - 0.5) * scale * 1e-13
                    };
                    [0, 1, 2].map(|i| a[i] + s * (b[i] - a[i]) + t * (c[i] - a[i]) + off)
                })
                .collect();
            let mut bbox = Bbox::empty();
            xs.iter().for_each(|&x| bbox.add(x));
            let plane = Plane::new(a, b, c, &bbox);
            for &x in &xs {
                let exact = orient3d(a, b, c, x);
                match plane.below(x) {
                    Some(true) => assert!(exact > 0.0),
                    Some(false) => assert!(exact < 0.0),
                    None => continue,
                }
                decided += 1;
            }
        }
        assert!(decided > 1000, "the filter decides most points ({decided})");
    }

    /// Every point the inner grid claims is strictly inside every face (exact),
    /// for a flat patch and a ball.
    #[test]
    fn inner_grid_is_sound() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for flat in [true, false] {
            let n = 40_000;
            let points: Vec<f64> = (0..n)
                .flat_map(|_| {
                    let z = (rng.random::<f64>() - 0.5) * if flat { 0.05 } else { 100.0 };
                    [rng.random::<f64>() * 200.0, rng.random::<f64>() * 150.0, z]
                })
                .collect();
            let (frame, sample) = Frame::new(&points);
            let dirs: Vec<P3> = directions(120)
                .into_iter()
                .map(|u| frame.to_world_normal(u))
                .collect();
            let ext = extremes(&points, Some(&sample), &dirs).0;
            let poly =
                Polytope::new(&points, ext, &frame, bounding_box(&points), 16).expect("polytope");
            let grid = poly.inner.as_ref().expect("inner grid");
            let mut claimed = 0;
            for i in 0..n {
                let x = pt(&points, i);
                if grid.contains(x) {
                    claimed += 1;
                    assert!(poly
                        .faces
                        .iter()
                        .all(|f| orient3d(f[0], f[1], f[2], x) > 0.0));
                }
                // and the whole filter agrees with brute force where it decides
                if poly.strictly_inside(x) {
                    assert!(poly
                        .faces
                        .iter()
                        .all(|f| orient3d(f[0], f[1], f[2], x) > 0.0));
                }
            }
            assert!(claimed > n / 10, "the grid covers a good share ({claimed})");
        }
    }

    /// The cube-map cell of a cell's own central direction is that cell; a direction
    /// on a cell's border (a cube face's edge, a corner) lands in a cell of the map;
    /// no direction (zero, NaN, infinite) gives cell 0.
    #[test]
    fn cell_of_inverts_cell_dir() {
        for c in 0..6 * GRID * GRID {
            let w = cell_dir(c);
            assert_eq!(cell_of(w), c);
            assert_eq!(cell_of(w.map(|x| x * 1e-200)), c);
            assert_eq!(cell_of(w.map(|x| x * 1e200)), c);
        }
        for w in [[1.0, 1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, -1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 1.0 + 1e-16, -1.0]] {
            assert!(cell_of(w) < 6 * GRID * GRID);
        }
        assert_eq!(cell_of([1.0, 1.0, 1.0]), (GRID - 1) * GRID + GRID - 1);
        assert_eq!(cell_of([-1.0, -1.0, -1.0]), GRID * GRID);
        for w in [[0.0; 3], [0.0, f64::INFINITY, 1.0], [f64::NAN; 3]] {
            assert_eq!(cell_of(w), 0);
        }
    }

    /// A thin plate tilted off every coordinate axis leaves no cell of the grid proven:
    /// no grid (its lookup would cost every point and decide none), and the filter
    /// still discards most points, exactly.
    #[test]
    fn no_inner_grid_for_a_tilted_plate() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let n = 40_000;
        let points: Vec<f64> = (0..n)
            .flat_map(|_| {
                let (u, v, w) = (rng.random::<f64>() * 200.0, rng.random::<f64>() * 150.0, (rng.random::<f64>() - 0.5) * 0.01);
                // about x by 0.3 rad, then about z by 0.3 rad
                let (y, z) = (c * v - s * w, s * v + c * w);
                [c * u - s * y, s * u + c * y, z]
            })
            .collect();
        let (frame, sample) = Frame::new(&points);
        let dirs: Vec<P3> = directions(120).into_iter().map(|u| frame.to_world_normal(u)).collect();
        let ext = extremes(&points, Some(&sample), &dirs).0;
        let poly = Polytope::new(&points, ext, &frame, bounding_box(&points), 16).expect("polytope");
        assert!(poly.inner.is_none(), "no cell can be proven inside a tilted plate");
        let mut inside = 0;
        for i in 0..n {
            let x = pt(&points, i);
            if poly.strictly_inside(x) {
                inside += 1;
                assert!(poly.faces.iter().all(|f| orient3d(f[0], f[1], f[2], x) > 0.0));
            }
        }
        assert!(inside > n / 2, "most points discarded ({inside})");
        // the whole prefilter keeps every hull vertex
        let kept = survivors(&points);
        let all: Vec<usize> = (0..n).collect();
        let mut a = super::super::hull_of(&points, kept).expect("hull");
        let mut b = super::super::hull_of(&points, all).expect("hull");
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
    }
}

