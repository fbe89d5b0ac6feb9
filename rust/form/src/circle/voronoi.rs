//! Nearest- and farthest-point Voronoi diagrams of a centred 2-D point set.
//!
//! The nearest diagram is the dual of spade's Delaunay triangulation. The farthest
//! diagram (not in spade) is the dual of the farthest-point Delaunay triangulation of
//! the strictly convex hull vertices (only they own farthest regions), built by
//! randomized incremental insertion with edge flips (Chew's scheme for convex
//! polygons; a triangle is legal when its circumcircle contains every hull vertex).
//!
//! Voronoi edges are stored on the bisector of their two sites `a`, `b` as
//! `c(t) = m + t n` with `m` the midpoint, `n` the unit normal of `b - a` and
//! `t in [tlo, thi]` (infinite for rays). On the edge both sites are at distance
//! `sqrt(h^2 + t^2)`, `h = |b - a| / 2`.

use super::{circumcenter, coord, dist};
use gagekit_core::{GkError, Result};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

#[derive(Clone, Copy, Debug)]
pub(crate) struct Site {
    pos: Point2<f64>,
    idx: usize,
}

impl HasPosition for Site {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// A Voronoi vertex: centre equidistant (`rad`) from three sites.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VVert {
    pub c: [f64; 2],
    pub sites: [usize; 3],
    pub rad: f64,
}

/// A Voronoi edge (segment or ray) on the bisector of sites `a` and `b`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VEdge {
    pub a: usize,
    pub b: usize,
    pub m: [f64; 2],
    pub n: [f64; 2],
    pub h: f64,
    pub tlo: f64,
    pub thi: f64,
}

impl VEdge {
    fn new(a: usize, b: usize, pa: [f64; 2], pb: [f64; 2]) -> Self {
        let m = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
        let len = dist(pa, pb);
        let n = [-(pb[1] - pa[1]) / len, (pb[0] - pa[0]) / len];
        Self {
            a,
            b,
            m,
            n,
            h: 0.5 * len,
            tlo: f64::NEG_INFINITY,
            thi: f64::INFINITY,
        }
    }
    fn param(&self, c: [f64; 2]) -> f64 {
        (c[0] - self.m[0]) * self.n[0] + (c[1] - self.m[1]) * self.n[1]
    }
    /// Segment between two Voronoi vertices.
    fn segment(mut self, c0: [f64; 2], c1: [f64; 2]) -> Self {
        let (t0, t1) = (self.param(c0), self.param(c1));
        self.tlo = t0.min(t1);
        self.thi = t0.max(t1);
        self
    }
    /// Ray from a Voronoi vertex in direction `d`.
    fn ray(mut self, c0: [f64; 2], d: [f64; 2]) -> Self {
        let t0 = self.param(c0);
        if d[0] * self.n[0] + d[1] * self.n[1] > 0.0 {
            self.tlo = t0;
        } else {
            self.thi = t0;
        }
        self
    }
    pub fn at(&self, t: f64) -> [f64; 2] {
        [self.m[0] + t * self.n[0], self.m[1] + t * self.n[1]]
    }
    /// Distance of the sites from the point at parameter t.
    pub fn rad(&self, t: f64) -> f64 {
        (self.h * self.h + t * t).sqrt()
    }
    /// Largest site distance over the edge (infinite for rays).
    pub fn rad_max(&self) -> f64 {
        self.h.hypot(self.tlo.abs().max(self.thi.abs()))
    }
    /// Smallest site distance over the edge.
    pub fn rad_min(&self) -> f64 {
        self.h.hypot(0f64.clamp(self.tlo, self.thi))
    }
    /// Restrict the edge to where `psi(t) = A t + B - 2 w sqrt(t^2 + 2 beta t + gamma) < 0`
    /// can hold (`|A| > 2w` makes psi strictly monotone, so that set is a half-line),
    /// widened by `margin`. Returns false if nothing is left.
    pub fn clip(&mut self, a: f64, b: f64, w: f64, beta: f64, gamma: f64, margin: f64) -> bool {
        if a.abs() <= 2.0 * w * (1.0 + 1e-9) {
            return true;
        }
        let sq = |t: f64| (t * t + 2.0 * beta * t + gamma).max(0.0).sqrt();
        // nothing to clip when psi < 0 already at the end that would move (less the
        // margin): the root lies beyond it (the usual case; saves the Newton steps)
        let end = if a > 0.0 { self.thi - margin } else { self.tlo + margin };
        if end.is_finite() && a * end + b - 2.0 * w * sq(end) < 0.0 {
            return self.tlo <= self.thi;
        }
        // psi is strictly monotone and nearly linear: Newton from the linear root
        // (solving the squared equation instead loses half the digits when w is tiny)
        let mut root = -b / a;
        for _ in 0..8 {
            let r = sq(root);
            let psi = a * root + b - 2.0 * w * r;
            let dpsi = a - if r > 0.0 {
                2.0 * w * (root + beta) / r
            } else {
                0.0
            };
            let step = psi / dpsi;
            root -= step;
            if step.is_nan() || step.abs() <= 1e-16 * (1.0 + root.abs()) {
                break;
            }
        }
        if !root.is_finite() {
            return true;
        }
        if a > 0.0 {
            self.thi = self.thi.min(root + margin);
        } else {
            self.tlo = self.tlo.max(root - margin);
        }
        self.tlo <= self.thi
    }

    /// Clip a nearest-Voronoi edge (sites at `rad(t)`) to where
    /// `|c(t) - q| - rad(t) < w`, a necessary condition for a zone narrower than `w` when
    /// `q` is any input point (the farthest point is at least that far).
    pub fn clip_nearest(&mut self, q: [f64; 2], w: f64, margin: f64) -> bool {
        let d = [self.m[0] - q[0], self.m[1] - q[1]];
        let (qq, qn) = (
            d[0] * d[0] + d[1] * d[1],
            d[0] * self.n[0] + d[1] * self.n[1],
        );
        self.clip(
            2.0 * qn,
            qq - self.h * self.h - w * w,
            w,
            0.0,
            self.h * self.h,
            margin,
        )
    }

    /// Clip a farthest-Voronoi edge (sites at `rad(t)`) to where
    /// `rad(t) - |c(t) - q| < w` (the nearest point is at most that far).
    pub fn clip_farthest(&mut self, q: [f64; 2], w: f64, margin: f64) -> bool {
        let d = [self.m[0] - q[0], self.m[1] - q[1]];
        let (qq, qn) = (
            d[0] * d[0] + d[1] * d[1],
            d[0] * self.n[0] + d[1] * self.n[1],
        );
        self.clip(-2.0 * qn, self.h * self.h - qq - w * w, w, qn, qq, margin)
    }

    pub fn contains(&self, t: f64, tol: f64) -> bool {
        t >= self.tlo - tol && t <= self.thi + tol
    }
}

/// Intersection of the supporting lines of two edges: parameters (t on e, s on f).
pub(crate) fn intersect(e: &VEdge, f: &VEdge) -> Option<(f64, f64)> {
    // e.m + t e.n = f.m + s f.n
    let det = e.n[0] * (-f.n[1]) - e.n[1] * (-f.n[0]);
    if det.abs() < 1e-14 {
        return None;
    }
    let (rx, ry) = (f.m[0] - e.m[0], f.m[1] - e.m[1]);
    let t = (rx * (-f.n[1]) - ry * (-f.n[0])) / det;
    let s = (e.n[0] * ry - e.n[1] * rx) / det;
    Some((t, s))
}

/// Nearest-point Voronoi diagram (and the Delaunay triangulation for queries).
pub(crate) struct Nearest {
    dt: DelaunayTriangulation<Site>,
    /// Triangulation vertex of each input point (None for merged duplicates).
    handle_of: Vec<Option<FixedVertexHandle>>,
    pub verts: Vec<VVert>,
    pub edges: Vec<VEdge>,
}

impl Nearest {
    /// Delaunay triangulation of centred points; errors if they are collinear or
    /// coincide. The diagram itself is filled in by [`Nearest::extract`].
    pub fn build(p: &[[f64; 2]], what: &str) -> Result<Self> {
        // spade rejects non-zero coordinates below ~1e-43; such values are zero for any
        // measurement
        let snap = |x: f64| if x.abs() < 1e-40 { 0.0 } else { x };
        let sites: Vec<Site> = p
            .iter()
            .enumerate()
            .map(|(idx, q)| Site {
                pos: Point2::new(snap(q[0]), snap(q[1])),
                idx,
            })
            .collect();
        let dt = DelaunayTriangulation::<Site>::bulk_load(sites).map_err(|e| match e {
            spade::InsertionError::TooLarge => GkError::invalid(format!(
                "{what}: coordinates too large to triangulate (the points span more than 1e60 mm)"
            )),
            e => GkError::invalid(format!("{what}: cannot triangulate the points ({e:?})")),
        })?;
        if dt.num_inner_faces() == 0 {
            return Err(GkError::degenerate(format!(
                "{what}: the points are collinear or coincide; no circle fits them"
            )));
        }
        let mut handle_of = vec![None; p.len()];
        for v in dt.vertices() {
            handle_of[v.data().idx] = Some(v.fix());
        }
        Ok(Self {
            dt,
            handle_of,
            verts: Vec::new(),
            edges: Vec::new(),
        })
    }

    /// Keep the part of the diagram where the empty circle is at least `thr`: the
    /// vertices of radius >= `thr`, the edges reaching such a vertex, and all rays
    /// (every other edge has its sites closer than `thr` all along).
    pub fn extract(&mut self, p: &[[f64; 2]], thr: f64) {
        let dt = &self.dt;
        let center = |f: spade::handles::FaceHandle<'_, InnerTag, Site, (), (), ()>| {
            let [a, b, c] = f.positions().map(|q| [q.x, q.y]);
            circumcenter(a, b, c).map(|u| (u, dist(u, a)))
        };
        let faces: Vec<FixedFaceHandle<InnerTag>> = dt.fixed_inner_faces().collect();
        let big: Vec<(FixedFaceHandle<InnerTag>, [f64; 2], f64)> = faces
            .into_par_iter()
            .with_min_len(4096)
            .filter_map(|h| {
                let (u, rad) = center(dt.face(h))?;
                (rad >= thr).then_some((h, u, rad))
            })
            .collect();
        let mut face_vert = vec![usize::MAX; dt.num_all_faces()];
        let mut verts = Vec::with_capacity(big.len());
        for &(h, u, rad) in &big {
            face_vert[h.index()] = verts.len();
            let f = dt.face(h);
            verts.push(VVert {
                c: u,
                sites: f.vertices().map(|v| v.data().idx),
                rad,
            });
        }
        let mut edges = Vec::new();
        let mut push = |e: spade::handles::DirectedEdgeHandle<'_, Site, (), (), ()>,
                        c0: [f64; 2],
                        other: Option<[f64; 2]>| {
            let (ia, ib) = (e.from().data().idx, e.to().data().idx);
            let base = VEdge::new(ia, ib, p[ia], p[ib]);
            edges.push(match other {
                Some(c1) => base.segment(c0, c1),
                None => {
                    // hull edge: ray away from the opposite vertex of the inner face
                    let o = p[e.opposite_vertex().map(|v| v.data().idx).unwrap_or(ia)];
                    let side = (o[0] - base.m[0]) * base.n[0] + (o[1] - base.m[1]) * base.n[1];
                    base.ray(c0, [-side * base.n[0], -side * base.n[1]])
                }
            });
        };
        for (fi, &(h, _, _)) in big.iter().enumerate() {
            let (f, i) = (dt.face(h), h.index());
            for e in f.adjacent_edges() {
                let Some(g) = e.rev().face().as_inner() else {
                    continue;
                };
                let gi = face_vert[g.fix().index()];
                if gi != usize::MAX {
                    if g.fix().index() > i {
                        push(e, verts[fi].c, Some(verts[gi].c));
                    }
                } else if let Some((u, _)) = center(g) {
                    push(e, verts[fi].c, Some(u));
                }
            }
        }
        for h in dt.convex_hull() {
            let e = if h.face().is_outer() { h.rev() } else { h };
            if let Some((u, _)) = e.face().as_inner().and_then(center) {
                push(e, u, None);
            }
        }
        self.verts = verts;
        self.edges = edges;
    }

    /// Nearest input point to `c` by a greedy walk on the Delaunay graph from input point
    /// `start` (exact: a vertex with no neighbour closer to `c` is the nearest).
    pub fn walk(&self, p: &[[f64; 2]], start: usize, c: [f64; 2]) -> (usize, f64) {
        let Some(mut v) = self.handle_of.get(start).copied().flatten() else {
            return self.nearest(p, c);
        };
        let mut best = super::dist2(p[self.dt.vertex(v).data().idx], c);
        loop {
            let mut next = None;
            for e in self.dt.vertex(v).out_edges() {
                let w = e.to();
                let d = super::dist2(p[w.data().idx], c);
                if d < best {
                    best = d;
                    next = Some(w.fix());
                }
            }
            match next {
                Some(w) => v = w,
                None => break,
            }
        }
        (self.dt.vertex(v).data().idx, best.sqrt())
    }

    /// Index of and distance to the input point nearest to `c`.
    pub fn nearest(&self, p: &[[f64; 2]], c: [f64; 2]) -> (usize, f64) {
        let v = self
            .dt
            .nearest_neighbor(Point2::new(c[0], c[1]))
            .expect("non-empty");
        let i = v.data().idx;
        (i, dist(p[i], c))
    }
}

/// Strictly convex vertices of the convex hull, counter-clockwise
/// (`gagekit_geometry::hull_2d`: Andrew's monotone chain with the exact predicate).
pub(crate) fn convex_hull(p: &[[f64; 2]]) -> Vec<usize> {
    gagekit_geometry::hull_2d(p)
}

/// Farthest-point Voronoi diagram.
pub(crate) struct Farthest {
    /// Strictly convex hull vertices (input indices), counter-clockwise.
    pub hull: Vec<usize>,
    pub verts: Vec<VVert>,
    pub edges: Vec<VEdge>,
}

impl Farthest {
    pub fn new(p: &[[f64; 2]], hull_ccw: &[usize]) -> Self {
        let k = hull_ccw.len();
        let hull: Vec<usize> = (0..k)
            .filter(|&i| {
                let (a, b, c) = (
                    hull_ccw[(i + k - 1) % k],
                    hull_ccw[i],
                    hull_ccw[(i + 1) % k],
                );
                robust::orient2d(coord(p[a]), coord(p[b]), coord(p[c])) > 0.0
            })
            .map(|i| hull_ccw[i])
            .collect();
        let q: Vec<[f64; 2]> = hull.iter().map(|&i| p[i]).collect();
        let tris = farthest_delaunay(&q);
        let mut verts = Vec::with_capacity(tris.len());
        let mut edge_tri: HashMap<(usize, usize), usize> =
            HashMap::with_capacity_and_hasher(3 * tris.len(), Default::default());
        for (t, tri) in tris.iter().enumerate() {
            let [a, b, c] = tri.map(|i| q[i]);
            let u = circumcenter(a, b, c)
                .unwrap_or([(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]);
            verts.push(VVert {
                c: u,
                sites: tri.map(|i| hull[i]),
                rad: dist(u, a),
            });
            for e in 0..3 {
                edge_tri.insert((tri[e], tri[(e + 1) % 3]), t);
            }
        }
        let mut edges = Vec::new();
        for (t, tri) in tris.iter().enumerate() {
            for e in 0..3 {
                let (u, v) = (tri[e], tri[(e + 1) % 3]);
                let base = VEdge::new(hull[u], hull[v], q[u], q[v]);
                match edge_tri.get(&(v, u)) {
                    Some(&t2) => {
                        if u < v {
                            edges.push(base.segment(verts[t].c, verts[t2].c));
                        }
                    }
                    // hull edge u -> v (interior on the left): ray towards the interior,
                    // which is +n for (a, b) = (u, v)
                    None => edges.push(base.ray(verts[t].c, base.n)),
                }
            }
        }
        Self { hull, verts, edges }
    }

    /// Index of and distance to the input point farthest from `c`.
    pub fn farthest(&self, p: &[[f64; 2]], c: [f64; 2]) -> (usize, f64) {
        let mut best = (self.hull[0], -1.0);
        for &i in &self.hull {
            let d = super::dist2(p[i], c);
            if d > best.1 {
                best = (i, d);
            }
        }
        (best.0, best.1.sqrt())
    }
}

/// Farthest-point Delaunay triangulation of a strictly convex polygon given
/// counter-clockwise; triangles as CCW index triples into `q`.
pub(crate) fn farthest_delaunay(q: &[[f64; 2]]) -> Vec<[usize; 3]> {
    let k = q.len();
    if k < 3 {
        return Vec::new();
    }
    // delete vertices in a fixed random order, remembering their neighbours
    let mut order: Vec<usize> = (0..k).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(0x66_64_74));
    let mut prev: Vec<usize> = (0..k).map(|i| (i + k - 1) % k).collect();
    let mut next: Vec<usize> = (0..k).map(|i| (i + 1) % k).collect();
    let mut removed = Vec::with_capacity(k);
    for &v in &order[..k - 3] {
        let (a, b) = (prev[v], next[v]);
        removed.push((v, a, b));
        next[a] = b;
        prev[b] = a;
    }
    let first = order[k - 3];
    let t0 = [first, next[first], next[next[first]]];
    let mut tris: Vec<[usize; 3]> = vec![t0];
    let mut alive = vec![true];
    let mut edge: HashMap<(usize, usize), usize> =
        HashMap::with_capacity_and_hasher(6 * k, Default::default());
    for e in 0..3 {
        edge.insert((t0[e], t0[(e + 1) % 3]), 0);
    }
    let add = |tris: &mut Vec<[usize; 3]>,
               alive: &mut Vec<bool>,
               edge: &mut HashMap<(usize, usize), usize>,
               t: [usize; 3]| {
        let id = tris.len();
        tris.push(t);
        alive.push(true);
        for e in 0..3 {
            edge.insert((t[e], t[(e + 1) % 3]), id);
        }
    };
    for &(v, a, b) in removed.iter().rev() {
        // v lies outside the current polygon edge a -> b
        add(&mut tris, &mut alive, &mut edge, [a, v, b]);
        let mut stack = vec![(b, a, v)];
        while let Some((x, y, pv)) = stack.pop() {
            // triangle (x, y, pv) CCW; neighbour across x -> y is (y, x, s)
            let Some(&tn) = edge.get(&(y, x)) else {
                continue;
            };
            if !alive[tn] {
                continue;
            }
            let Some(&tc) = edge.get(&(x, y)) else {
                continue;
            };
            let t = tris[tn];
            #[allow(clippy::unwrap_used, reason = "tn was found as the triangle of the directed edge (y, x), so y is one of its corners")]
            let s = t[(t.iter().position(|&w| w == y).unwrap() + 2) % 3];
            let inc = robust::incircle(coord(q[x]), coord(q[y]), coord(q[pv]), coord(q[s]));
            if inc < 0.0 {
                // s outside the circle of (x, y, pv): flip x-y to pv-s
                alive[tn] = false;
                alive[tc] = false;
                edge.remove(&(x, y));
                edge.remove(&(y, x));
                add(&mut tris, &mut alive, &mut edge, [x, s, pv]);
                add(&mut tris, &mut alive, &mut edge, [s, y, pv]);
                stack.push((x, s, pv));
                stack.push((s, y, pv));
            }
        }
    }
    tris.into_iter()
        .zip(alive)
        .filter(|(_, a)| *a)
        .map(|(t, _)| t)
        .collect()
}
