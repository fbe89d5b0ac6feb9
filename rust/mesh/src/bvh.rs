//! A bounding-volume hierarchy over a mesh's triangles and the nearest-triangle query.
//!
//! Build: binned surface-area heuristic (Wald, "On fast construction of SAH-based bounding
//! volume hierarchies", IEEE RT 2007): at each node the triangles' centroids are binned
//! into [`BINS`] slabs along the centroids' longest axis and the split with the least
//! `area(left) n(left) + area(right) n(right)` is taken; leaves hold at most [`LEAF`]
//! triangles. Nodes of at most [`SAH_MIN`] triangles, and levels below [`MAX_SAH_DEPTH`],
//! split at the object median, so
//! the depth stays below [`MAX_DEPTH`] whatever the triangles. Large subtrees (and the
//! binning of large nodes) run in parallel (rayon); bin counts and bounds are integers
//! and minima/maxima, so the tree depends on the triangles only, never on the thread
//! count. Each node stores the boxes of both its children (structure of arrays, one
//! cache-line pair per node), so a visit tests both children at once; nodes are in
//! depth-first order and the triangles' corners are copied into leaf order, so a query
//! reads memory front to back.
//!
//! Query: depth first, the nearer child first, the farther one pushed with its box's
//! squared distance (a lower bound of every triangle inside) and skipped when popped if
//! the best triangle so far is not farther than that bound. A starting bound (the
//! distance to a hinted triangle, e.g. the previous point's) prunes most of the tree for
//! coherent points. The pruning only ever skips boxes whose lower bound exceeds the best
//! squared distance found, so the result is the exact minimum over all triangles (tested
//! against a brute-force scan).
//!
//! The group query ([`Bvh::nearest_group_from`]) measures its start triangles for the
//! eight points at once ([`crate::closest::closest_lanes`], the same bits as one point at
//! a time), descends from the root by the box of the points' balls while only one child
//! meets it, and then walks with a box test per point.
//!
//! Before the exact closest point of a leaf's triangle is computed, a cheap lower bound
//! of its distance ([`Bound`]: the plane distance and the in-plane distance to the
//! farthest-out edge line, from planes precomputed per slot, in single precision) is
//! tested against the best distance so far; a triangle is skipped only when that bound,
//! reduced by a slack above its rounding, proves it farther than the best (never a
//! tie), so the answer is the one the exact test of every triangle gives, to the bit.

use crate::closest::{box_distance2, closest_lanes, closest_point, feature_of_code, Closest8, Feature, LANES};
use gagekit_gdt::vec3::{cross, dot, norm, scale, sub, V3};

/// Most triangles per leaf.
pub const LEAF: usize = 4;
/// Bins per axis of the SAH split.
pub const BINS: usize = 16;
/// Levels built by SAH; deeper subtrees split at the object median (depth <= MAX_DEPTH).
pub const MAX_SAH_DEPTH: usize = 40;
/// The deepest a leaf can be (MAX_SAH_DEPTH + log2 of 2^32 triangles), the stack's size.
pub const MAX_DEPTH: usize = MAX_SAH_DEPTH + 34;
/// Nodes of at most this many triangles split at the object median (cheaper than binning).
const SAH_MIN: usize = 32;
/// Triangles above which a subtree's halves (and a node's binning) run in parallel.
const PAR: usize = 4096;

/// A reference to a child: an inner node (`count == 0`, `index` = node) or a leaf
/// (`count` triangles from slot `index`; an empty slot has `count == 0` and an empty box).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Child {
    pub index: u32,
    pub count: u32,
}

/// An inner node: the boxes of its two children (per axis: child 0, child 1) and the children.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub struct Node {
    pub lo: [[f32; 2]; 3],
    pub hi: [[f32; 2]; 3],
    pub child: [Child; 2],
}

impl Node {
    /// A node of zeros: the place of one not yet written.
    const EMPTY: Node = Node { lo: [[0.0f32; 2]; 3], hi: [[0.0f32; 2]; 3], child: [Child { index: 0, count: 0 }; 2] };
}

/// `x` rounded down (`up == false`) or up to an f32: the box stored in single precision
/// still holds every corner exactly (a conservative box, so its distance is a lower bound).
#[inline]
fn f32_out(x: f64, up: bool) -> f32 {
    let f = x as f32;
    if up && (f as f64) < x {
        f.next_up()
    } else if !up && (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}

/// The hierarchy: nodes, the root's box and reference, and per slot (leaf order) the
/// triangle's corners and its index.
#[derive(Debug, Clone)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    pub root: Child,
    pub root_lo: V3,
    pub root_hi: V3,
    pub corners: Vec<[V3; 3]>,
    pub order: Vec<u32>,
    /// per slot: the data of the triangle's distance lower bound
    pub bounds: Vec<Bound>,
    /// the slack (mm) of the lower bounds' double-precision planes, far above their
    /// rounding error (the single-precision test reduces by more, [`SLACK32`] times it)
    pub slack: f64,
    /// the largest |coordinate| of the root's box (the scale of the rounding errors)
    pub size: f64,
}

/// Per triangle, the planes of its lower bound, stored in single precision (64 bytes a
/// slot, one cache line): `n` the unit normal and `m[k]` the unit in-plane outward normal
/// of edge k (`n x` the edge, pointing away from the opposite corner), each with its
/// offset (`w[0] = n . a`, `w[k + 1] = m[k] . corner k`). For any point x of the triangle
/// n . x = w[0] and m[k] . x <= w[k + 1]; since |p - x|^2 is the squared plane component
/// plus the squared in-plane part, and the in-plane part is at least m[k] . (p - x) for
/// each k (m[k] is a unit vector in the plane),
/// dist(p, T)^2 >= (n . p - w[0])^2 + max(0, max_k m[k] . p - w[k + 1])^2.
///
/// The planes are computed in double precision ([`Planes`]) and each number rounded to
/// the nearest single precision one; the test runs in single precision on the point
/// rounded to single precision ([`Bound::lower32`]), with each part reduced by a larger
/// slack ([`SLACK32`]) that covers that rounding, and compared with the best widened by
/// its own rounding ([`Bound::side32`]). It rejects a triangle only where the double
/// precision test of the same planes (`Planes::may_beat`, the test before the planes were
/// stored in single precision) rejects it, so it proves the triangle farther than the best
/// just as well; it may pass a few more, whose exact test then decides. The error analysis
/// is in [`Bound::lower32`]'s documentation.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub struct Bound {
    pub n: [f32; 3],
    pub m: [[f32; 3]; 3],
    pub w: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<Bound>() == 64, "a slot's bound is one cache line");

/// The double-precision planes of a triangle's lower bound ([`Bound`]'s, before their
/// rounding to single precision), and the double-precision test on them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Planes {
    pub(crate) n: V3,
    pub(crate) m: [V3; 3],
    pub(crate) w: [f64; 4],
}

impl Planes {
    /// No bound (never rejects): for triangles whose normal is ill-conditioned.
    const NONE: Planes = Planes { n: [0.0; 3], m: [[0.0; 3]; 3], w: [0.0; 4] };

    /// The bound's planes of triangle `c`. The normal is the cross product of the two
    /// edges at the corner with the largest sine of its angle; its direction is then exact
    /// to a few ulp over that sine. Below a sine of 1e-4 (slivers) the triangle gets
    /// [`Planes::NONE`]; above it every plane is within 1e-11 rad of the exact one, so the
    /// bound's error is below 1e-11 of the point's distance plus the coordinates'
    /// rounding, far inside [`Bvh::slack`].
    pub(crate) fn of(c: &[V3; 3]) -> Planes {
        // the edges' lengths, each edge taken by two corners (reversed, the same length)
        let len: [f64; 3] = std::array::from_fn(|k| norm(sub(c[(k + 1) % 3], c[k])));
        let mut best = (0.0f64, [0.0; 3], 0.0);
        for k in 0..3 {
            let (u, v) = (sub(c[(k + 1) % 3], c[k]), sub(c[(k + 2) % 3], c[k]));
            let x = cross(u, v);
            let nx = norm(x);
            let sine = nx / (len[k] * len[(k + 2) % 3]);
            if sine > best.0 {
                best = (sine, x, nx);
            }
        }
        if !(best.0 >= 1e-4) {
            return Planes::NONE;
        }
        let n = scale(best.1, 1.0 / best.2);
        let m = std::array::from_fn(|k| {
            let e = sub(c[(k + 1) % 3], c[k]);
            let mk = cross(e, n);
            let mk = scale(mk, 1.0 / norm(mk));
            // outward: away from the opposite corner
            if dot(mk, sub(c[(k + 2) % 3], c[k])) > 0.0 {
                scale(mk, -1.0)
            } else {
                mk
            }
        });
        let w = [dot(n, c[0]), dot(m[0], c[0]), dot(m[1], c[1]), dot(m[2], c[2])];
        Planes { n, m, w }
    }

    /// The double-precision test: may the triangle be as near to `p` as `best_d2`
    /// (squared)? False only when its lower bound, each part reduced by `slack`, exceeds
    /// `best_d2` by more than rounding: then the exact squared distance computed by
    /// [`closest_point`] is larger than `best_d2` too (the slack covers the rounding of the
    /// planes, of their evaluation and of the closest point; the margin 1e-12 covers the
    /// squares' rounding). `Bound::may_beat` rejects only where this rejects.
    #[cfg(test)]
    pub(crate) fn may_beat(&self, p: &V3, best_d2: f64, slack: f64) -> bool {
        self.lower(p, slack) <= best_d2 * (1.0 + 1e-12)
    }

    /// The squared lower bound, each part reduced by `slack` (the left side of
    /// `Planes::may_beat`).
    #[cfg(test)]
    pub(crate) fn lower(&self, p: &V3, slack: f64) -> f64 {
        let plane = (dot(self.n, *p) - self.w[0]).abs();
        let e0 = dot(self.m[0], *p) - self.w[1];
        let e1 = dot(self.m[1], *p) - self.w[2];
        let e2 = dot(self.m[2], *p) - self.w[3];
        let a = larger(plane - slack, 0.0);
        let b = larger(larger(larger(e0, e1), e2) - slack, 0.0);
        a * a + b * b
    }
}

/// The factor from a point's double-precision slack ([`Bvh::slack_at`], at least
/// 1e-9 (size + |p|_inf) with size the largest |coordinate| of the root's box) to the
/// reduction of the single-precision bound's parts: 1 + 11 * 2^-24 / 1e-9, so the
/// reduction is at least the slack plus 11 * 2^-24 (size + |p|_inf), the rounding
/// [`Bound::lower32`] is off by (its documentation).
pub(crate) const SLACK32: f64 = 1.0 + 11.0 / (1u64 << 24) as f64 / 1e-9;

impl Bound {
    /// The single-precision planes of triangle `c`: [`Planes::of`] rounded to nearest.
    fn of(c: &[V3; 3]) -> Bound {
        let p = Planes::of(c);
        let f = |v: V3| v.map(|x| x as f32);
        Bound { n: f(p.n), m: p.m.map(f), w: p.w.map(|x| x as f32) }
    }

    /// May the triangle be as near to `p` as `best_d2` (squared)? `slack`: the point's
    /// slack ([`Bvh::slack_at`]). False only where `Planes::may_beat` of the same
    /// triangle is false too (see [`Bound::lower32`]), so only for a triangle proved
    /// farther than `best_d2`. The tests' form: the queries call [`Bound::passes`] with
    /// the point rounded once and the two sides kept as the best changes.
    #[cfg(test)]
    pub(crate) fn may_beat(&self, p: &V3, best_d2: f64, slack: f64) -> bool {
        self.passes(&[p[0] as f32, p[1] as f32, p[2] as f32], Self::reach32(slack), Self::side32(best_d2))
    }

    /// `Bound::may_beat` of the point rounded to single precision `q`, with its
    /// reduction `r` ([`Bound::reach32`]) and right side `side` ([`Bound::side32`]).
    #[inline(always)]
    pub(crate) fn passes(&self, q: &[f32; 3], r: f32, side: f32) -> bool {
        self.lower32(q, r) <= side
    }

    /// The reduction of the bound's parts of a point whose double-precision slack is
    /// `slack`: `slack` times [`SLACK32`], rounded up to single precision (the product
    /// times 1 + 2^-22, then to nearest: never below it); infinity (no rejection) from a
    /// slack of 1e20 on (and for NaN), where the single-precision planes could overflow.
    #[inline(always)]
    pub(crate) fn reach32(slack: f64) -> f32 {
        if slack < 1e20 {
            (slack * (SLACK32 * (1.0 + 1.0 / (1u64 << 22) as f64))) as f32
        } else {
            f32::INFINITY
        }
    }

    /// The right side of the single-precision comparison for the best squared distance
    /// `best_d2`: the double-precision test's right side `best_d2 (1 + 1e-12)` times
    /// 1 + 2^-20, plus 1e-38, rounded to nearest single precision (see [`Bound::lower32`];
    /// NaN never arises: `best_d2` is a distance, infinity or, for unused lanes, minus
    /// infinity).
    #[inline(always)]
    pub(crate) fn side32(best_d2: f64) -> f32 {
        (best_d2 * ((1.0 + 1e-12) * (1.0 + 1.0 / (1u64 << 20) as f64)) + 1e-38) as f32
    }

    /// The squared lower bound in single precision at the point `q` (the point rounded to
    /// single precision), each part reduced by `r` ([`Bound::reach32`] of the point's
    /// slack): the left side of `Bound::may_beat`'s comparison.
    ///
    /// Error analysis, against `Planes::lower` (the double-precision bound) at the point p
    /// with the slack s (u = 2^-24, S = size + |p|_inf, every corner within the root's box
    /// so |w| <= sqrt(3) size):
    /// - a plane's value n'.q - w' (n', w' the stored numbers, q the point, left to right)
    ///   differs from n.p - w (the double-precision planes, exact arithmetic) by at most
    ///   gamma_6 (|n||p| + |w|) <= 6u / (1 - 6u) sqrt(3) S < 10.5 u S: each product carries
    ///   three roundings (n', q, the product) and the sum and difference three more;
    ///   below single precision's normal range each rounding adds at most 2^-150, far
    ///   inside the slack's absolute 1e-9. The double-precision evaluation of [`Planes`]
    ///   is off by under 2^-48 S. So with r >= s + 11 u S each reduced part here, before
    ///   its own rounding, is at most the double-precision one before its rounding;
    ///   after them (relative u here, 2^-53 there, and the max with 0 is monotone),
    ///   a <= a64 (1 + u) (1 + 2^-52) and the same for b.
    /// - The squares and their sum add three roundings: the bound here is at most the
    ///   double-precision one times (1 + u)^5 (1 + 2^-50) < 1 + 6u, plus 3 * 2^-150 below
    ///   the normal range. An overflow to infinity here means a bound above
    ///   (1 - 6u) f32::MAX there.
    /// - [`Bound::side32`] is at least the double-precision right side times
    ///   (1 + 2^-20)(1 - u)(1 - 2^-51) > 1 + 14u, plus 1e-38 (1 - u).
    ///
    /// So bound > side here implies bound > right side there: the triangles this test
    /// rejects are a subset of those the double-precision test rejects (tested), which are
    /// farther than the best. Overflow: a point or root box beyond 1e29 (slack 1e20 or
    /// more) gets r = infinity ([`Bound::reach32`]), so every part is 0 or NaN, and NaN
    /// becomes 0 ([`larger`]): such a point's triangles are never rejected. Below it no
    /// plane's value overflows, and a square that does is handled above.
    #[inline(always)]
    pub(crate) fn lower32(&self, q: &[f32; 3], r: f32) -> f32 {
        let d = |v: &[f32; 3]| v[0] * q[0] + v[1] * q[1] + v[2] * q[2];
        let plane = (d(&self.n) - self.w[0]).abs();
        let e0 = d(&self.m[0]) - self.w[1];
        let e1 = d(&self.m[1]) - self.w[2];
        let e2 = d(&self.m[2]) - self.w[3];
        let a = larger(plane - r, 0.0);
        let b = larger(larger(larger(e0, e1), e2) - r, 0.0);
        a * a + b * b
    }

    /// `Bound::may_beat` of the [`GROUP`] lanes of a group at once (coordinates by axis,
    /// each lane's best and slack): bit i set when lane i may beat. The same arithmetic
    /// lane by lane, so the same answers.
    #[cfg(test)]
    pub fn may_beat_lanes(&self, p: [&[f64; GROUP]; 3], best_d2: &[f64; GROUP], slack: &[f64; GROUP]) -> u32 {
        let q = p.map(|a| a.map(|x| x as f32));
        self.may_beat_lanes_in::<false>([&q[0], &q[1], &q[2]], &best_d2.map(Self::side32), &slack.map(Self::reach32))
    }

    /// [`Bound::lower32`] of the [`GROUP`] lanes (single-precision coordinates by axis,
    /// each lane's reduction `r`) against their right sides `side` ([`Bound::side32`] of
    /// their best, kept by the group query as the best changes): bit i set when lane i may
    /// beat. Written over arrays so it compiles to eight-lane vector instructions; `AVX`:
    /// the comparison by one AVX instruction ([`lanes_le32`], only in code compiled for AVX2).
    #[inline(always)]
    fn may_beat_lanes_in<const AVX: bool>(&self, q: [&[f32; GROUP]; 3], side: &[f32; GROUP], r: &[f32; GROUP]) -> u32 {
        let mut bound = [0.0f32; GROUP];
        for i in 0..GROUP {
            bound[i] = self.lower32(&[q[0][i], q[1][i], q[2][i]], r[i]);
        }
        lanes_le32::<AVX>(&bound, side)
    }
}

/// The nearest triangle found: its slot (leaf order), squared distance, closest point and feature.
#[derive(Debug, Clone, Copy)]
pub struct Nearest {
    pub slot: u32,
    pub d2: f64,
    pub foot: V3,
    pub feature: Feature,
}

/// A triangle during the build: its index, centroid and box (in the order low corner,
/// centroid, high corner: [`Binned::add`] reads two runs of six numbers).
#[derive(Clone, Copy)]
#[repr(C)]
pub(crate) struct Item {
    pub(crate) tri: u32,
    pub(crate) lo: V3,
    pub(crate) centroid: V3,
    pub(crate) hi: V3,
}

#[derive(Clone, Copy)]
struct Aabb {
    lo: V3,
    hi: V3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb { lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] };
    /// Grow by the box `lo`..`hi`. Plain comparisons (one min or max instruction each,
    /// where `f64::min` adds its NaN rule): the corners are finite ([`crate::TriMesh`]
    /// refuses others), and for numbers the result is `f64::min`'s and `f64::max`'s.
    #[inline]
    fn grow(&mut self, lo: &V3, hi: &V3) {
        for k in 0..3 {
            self.lo[k] = if lo[k] < self.lo[k] { lo[k] } else { self.lo[k] };
            self.hi[k] = if hi[k] > self.hi[k] { hi[k] } else { self.hi[k] };
        }
    }
    #[inline]
    fn join(mut self, o: &Aabb) -> Aabb {
        self.grow(&o.lo, &o.hi);
        self
    }
    /// Half the surface area (0 for an empty box).
    #[inline]
    fn half_area(&self) -> f64 {
        let e = [self.hi[0] - self.lo[0], self.hi[1] - self.lo[1], self.hi[2] - self.lo[2]];
        if e[0] < 0.0 {
            return 0.0;
        }
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }
}

/// Per bin along the split axis: the count, the triangles' box and their centroids' box
/// (the centroid boxes give the two sides' centroid bounds of any split plane, so the
/// children's bins are known before the partition, which fills them).
#[derive(Clone)]
struct Binned {
    count: [u32; BINS],
    /// the low corners of the triangles' box and of the centroids' box
    mins: [[f64; 6]; BINS],
    /// the high corners of the centroids' box and of the triangles' box
    maxs: [[f64; 6]; BINS],
}

impl Binned {
    fn new() -> Self {
        Self { count: [0; BINS], mins: [[f64::INFINITY; 6]; BINS], maxs: [[f64::NEG_INFINITY; 6]; BINS] }
    }
    /// Bin `b`'s triangles' box.
    #[inline]
    fn bound(&self, b: usize) -> Aabb {
        let (m, x) = (&self.mins[b], &self.maxs[b]);
        Aabb { lo: [m[0], m[1], m[2]], hi: [x[3], x[4], x[5]] }
    }
    /// Bin `b`'s centroids' box.
    #[inline]
    fn cent(&self, b: usize) -> Aabb {
        let (m, x) = (&self.mins[b], &self.maxs[b]);
        Aabb { lo: [m[3], m[4], m[5]], hi: [x[0], x[1], x[2]] }
    }
    /// Grow bin `b` by six low and six high values (the comparisons of [`Aabb::grow`]).
    #[inline(always)]
    fn grow(&mut self, b: usize, lo: &[f64; 6], hi: &[f64; 6]) {
        let (m, x) = (&mut self.mins[b], &mut self.maxs[b]);
        for q in 0..6 {
            m[q] = if lo[q] < m[q] { lo[q] } else { m[q] };
            x[q] = if hi[q] > x[q] { hi[q] } else { x[q] };
        }
    }

    /// [`Binned::grow`] by AVX's `vminpd` and `vmaxpd` (`a < b ? a : b` and `a > b ? a : b`,
    /// lane by lane: the same values) and whole stores. Written plainly, AVX2 code made
    /// masked stores of the rows (a store only where a value changes), which the next
    /// item's load of the same bin cannot take its data from.
    /// # Safety
    /// Only in code compiled for AVX (the AVX2 builds, after detection).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn grow_avx(&mut self, b: usize, it: &Item) {
        use std::arch::x86_64::*;
        let (m, x) = (self.mins[b].as_mut_ptr(), self.maxs[b].as_mut_ptr());
        // the item's low corner and centroid, and its centroid and high corner: six
        // consecutive numbers each (`repr(C)`, offsets checked below)
        let p = (it as *const Item).cast::<u8>();
        let (l, h) = (p.add(std::mem::offset_of!(Item, lo)).cast::<f64>(), p.add(std::mem::offset_of!(Item, centroid)).cast::<f64>());
        // SAFETY: unaligned loads and stores of lanes 0..4 and 4..6 of six-lane rows, and of
        // the item's six numbers from `l` and from `h` (within the item)
        unsafe {
            _mm256_storeu_pd(m, _mm256_min_pd(_mm256_loadu_pd(l), _mm256_loadu_pd(m)));
            _mm_storeu_pd(m.add(4), _mm_min_pd(_mm_loadu_pd(l.add(4)), _mm_loadu_pd(m.add(4))));
            _mm256_storeu_pd(x, _mm256_max_pd(_mm256_loadu_pd(h), _mm256_loadu_pd(x)));
            _mm_storeu_pd(x.add(4), _mm_max_pd(_mm_loadu_pd(h.add(4)), _mm_loadu_pd(x.add(4))));
        }
    }
    fn merge(mut self, o: &Binned) -> Self {
        for b in 0..BINS {
            self.count[b] += o.count[b];
            self.grow(b, &o.mins[b], &o.maxs[b]);
        }
        self
    }
    /// Add an item to its bin; `AVX`: by [`Binned::grow_avx`] (only in the AVX2 builds).
    #[inline(always)]
    fn add<const AVX: bool>(&mut self, it: &Item, k: usize, lo: f64, scale: f64) {
        let i = bin_of(it.centroid[k], lo, scale);
        self.count[i] += 1;
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is true only in the AVX2 builds, run after detection
            return unsafe { self.grow_avx(i, it) };
        }
        let (l, c, h) = (&it.lo, &it.centroid, &it.hi);
        self.grow(i, &[l[0], l[1], l[2], c[0], c[1], c[2]], &[c[0], c[1], c[2], h[0], h[1], h[2]]);
    }
}

/// How a node of `n` items with centroid bounds `cb` at `depth` splits: the centroids'
/// longest axis, its extent, and whether by SAH bins (else by the object median).
#[inline]
fn plan(cb: &Aabb, n: usize, depth: usize) -> (usize, f64, bool) {
    let ext = [cb.hi[0] - cb.lo[0], cb.hi[1] - cb.lo[1], cb.hi[2] - cb.lo[2]];
    let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] { 0 } else if ext[1] >= ext[2] { 1 } else { 2 };
    (axis, ext[axis], depth < MAX_SAH_DEPTH && n > SAH_MIN && ext[axis] > 0.0)
}

/// A node's bins along `axis`: (axis, low end, bins per unit).
#[inline]
fn bins_of(cb: &Aabb, axis: usize, ext: f64) -> (usize, f64, f64) {
    (axis, cb.lo[axis], BINS as f64 / ext)
}

/// What a node's parent found of it: its centroid bounds, and its bins when it splits by them.
pub(crate) struct Known {
    cb: Aabb,
    bins: Option<Box<Binned>>,
}

/// The bin of centroid coordinate `c`: `((c - lo) * scale) as usize` capped at the last
/// bin (0 for a negative or NaN product), clamped while still a float so that the
/// conversion needs no saturation (one instruction instead of a dozen).
#[inline]
pub(crate) fn bin_of(c: f64, lo: f64, scale: f64) -> usize {
    let x = (c - lo) * scale;
    let x = if x > 0.0 { x } else { 0.0 };
    let x = if x < (BINS - 1) as f64 { x } else { (BINS - 1) as f64 };
    // SAFETY: 0 <= x <= BINS - 1 (a NaN became 0 above), so it fits
    unsafe { x.to_int_unchecked::<u32>() as usize }
}

/// `f64`'s total order as integers (-0.0 just below +0.0), and back.
#[inline]
fn ordered(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | 1 << 63
    }
}

#[inline]
fn from_ordered(o: u64) -> f64 {
    f64::from_bits(if o >> 63 == 1 { o & !(1 << 63) } else { !o })
}

/// The least coordinate `t` of `lo_c..=hi_c` whose bin ([`bin_of`] of `lo`, `scale`) is
/// at least `b`, given that `hi_c`'s is: for every centroid coordinate `c` of the node
/// (all within `lo_c..=hi_c`), `bin_of(c, lo, scale) < b` exactly when `c < t`. `bin_of`
/// never decreases as `c` grows (the subtraction, the product by `scale >= 0` and the
/// clamps are monotone), and gives -0.0 and +0.0 the same bin, so one comparison replaces
/// it. Found by bisection over the coordinates between the two, started at the estimate
/// `lo + b / scale` (the bin's edge to within a few units in the last place).
pub(crate) fn bin_threshold(lo: f64, scale: f64, b: usize, lo_c: f64, hi_c: f64) -> f64 {
    let right = |o: u64| bin_of(from_ordered(o), lo, scale) >= b;
    // the answer is in (l, h]: l's bin is below b, h's is not
    let (mut l, mut h) = (ordered(lo_c), ordered(hi_c));
    if right(l) {
        return lo_c;
    }
    debug_assert!(right(h) && l < h);
    let e = lo + b as f64 / scale;
    if e.is_finite() {
        let o = ordered(e);
        if l < o && o < h {
            if right(o) {
                h = o;
                let p = o.saturating_sub(4);
                if l < p && !right(p) {
                    l = p;
                }
            } else {
                l = o;
                let p = o.saturating_add(4);
                if p < h && right(p) {
                    h = p;
                }
            }
        }
    }
    while l < h && h - l > 1 {
        let m = l + (h - l) / 2;
        if right(m) {
            h = m;
        } else {
            l = m;
        }
    }
    from_ordered(h)
}

fn bin_items(items: &[Item], k: usize, lo: f64, scale: f64) -> Binned {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the feature was detected on this processor
        return unsafe { bin_items_avx2(items, k, lo, scale) };
    }
    bin_items_in::<false>(items, k, lo, scale)
}

/// [`bin_items`] compiled for AVX2 (the same comparisons, wider: the same bins).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn bin_items_avx2(items: &[Item], k: usize, lo: f64, scale: f64) -> Binned {
    bin_items_in::<true>(items, k, lo, scale)
}

#[inline(always)]
fn bin_items_in<const AVX: bool>(items: &[Item], k: usize, lo: f64, scale: f64) -> Binned {
    let mut b = Binned::new();
    for it in items {
        b.add::<AVX>(it, k, lo, scale);
    }
    b
}

/// Two-pointer partition of `items` by bin `b` of (`k`, `lo`, `scale`), in place and
/// deterministic (each item is tested once, where its side is known), binning each item
/// into its side's bins (`L`, `R`: whether that side splits by bins, by `lp`, `rp`).
/// The side is one comparison with the bin's edge `t` ([`bin_threshold`]: the same side).
#[allow(clippy::too_many_arguments)]
fn partition<const L: bool, const R: bool>(items: &mut [Item], (k, t): (usize, f64), lp: (usize, f64, f64), rp: (usize, f64, f64), lb: &mut Binned, rb: &mut Binned) -> usize {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the feature was detected on this processor
        return unsafe { partition_avx2::<L, R>(items, (k, t), lp, rp, lb, rb) };
    }
    partition_in::<L, R, false>(items, (k, t), lp, rp, lb, rb)
}

/// [`partition`] compiled for AVX2 (the same comparisons and moves, wider).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn partition_avx2<const L: bool, const R: bool>(items: &mut [Item], kt: (usize, f64), lp: (usize, f64, f64), rp: (usize, f64, f64), lb: &mut Binned, rb: &mut Binned) -> usize {
    partition_in::<L, R, true>(items, kt, lp, rp, lb, rb)
}

#[inline(always)]
fn partition_in<const L: bool, const R: bool, const AVX: bool>(items: &mut [Item], (k, t): (usize, f64), lp: (usize, f64, f64), rp: (usize, f64, f64), lb: &mut Binned, rb: &mut Binned) -> usize {
    let (mut i, mut j) = (0usize, items.len());
    while i < j {
        let it = &items[i];
        if it.centroid[k] < t {
            if L {
                lb.add::<AVX>(it, lp.0, lp.1, lp.2);
            }
            i += 1;
        } else {
            if R {
                rb.add::<AVX>(it, rp.0, rp.1, rp.2);
            }
            j -= 1;
            items.swap(i, j);
        }
    }
    i
}

fn centroid_bounds(items: &[Item]) -> Aabb {
    let mut c = Aabb::EMPTY;
    for it in items {
        c.grow(&it.centroid, &it.centroid);
    }
    c
}

/// Split `items` into two non-empty parts: (the number on the left, and what the split
/// found of the two parts); SAH by bins, or the object median along the centroids'
/// longest axis (deep subtrees, coincident centroids). `known`: the items' centroid bounds
/// and bins if known.
fn split(items: &mut [Item], depth: usize, known: Option<Known>) -> (usize, Option<[Known; 2]>) {
    let n = items.len();
    let (cb, pre) = match known {
        Some(k) => (k.cb, k.bins),
        None if n > PAR => {
            let parts: Vec<Aabb> = {
                use rayon::prelude::*;
                items.par_chunks(PAR).map(centroid_bounds).collect()
            };
            (parts.iter().fold(Aabb::EMPTY, |a, b| a.join(b)), None)
        }
        None => (centroid_bounds(items), None),
    };
    let (axis, ext, sah) = plan(&cb, n, depth);
    if sah {
        // bins along the centroids' longest axis
        let (k, lo, scale) = bins_of(&cb, axis, ext);
        let binned = match pre {
            Some(b) => *b,
            None if n > PAR => {
                use rayon::prelude::*;
                let parts: Vec<Binned> = items.par_chunks(PAR).map(|c| bin_items(c, k, lo, scale)).collect();
                parts.iter().fold(Binned::new(), |a, b| a.merge(b))
            }
            None => bin_items(items, k, lo, scale),
        };
        // the cheapest split plane (ties: the lowest plane)
        let mut best: Option<(f64, usize)> = None;
        let mut right_area = [0.0; BINS];
        let mut acc = Aabb::EMPTY;
        for b in (1..BINS).rev() {
            acc = acc.join(&binned.bound(b));
            right_area[b] = acc.half_area();
        }
        let mut left = Aabb::EMPTY;
        let mut nl = 0u64;
        for b in 1..BINS {
            left = left.join(&binned.bound(b - 1));
            nl += binned.count[b - 1] as u64;
            let nr = n as u64 - nl;
            if nl == 0 || nr == 0 {
                continue;
            }
            let cost = left.half_area() * nl as f64 + right_area[b] * nr as f64;
            if best.map_or(true, |(c, _)| cost < c) {
                best = Some((cost, b));
            }
        }
        if let Some((_, b)) = best {
            // the two sides' centroid bounds and sizes from the bins, then their own bins
            // filled during the partition
            let lcb = (0..b).fold(Aabb::EMPTY, |a, c| a.join(&binned.cent(c)));
            let rcb = (b..BINS).fold(Aabb::EMPTY, |a, c| a.join(&binned.cent(c)));
            let nl = binned.count[..b].iter().map(|&c| c as usize).sum::<usize>();
            let (la, le, ls) = plan(&lcb, nl, depth + 1);
            let (ra, re, rs) = plan(&rcb, n - nl, depth + 1);
            let (lp, rp) = (if ls { bins_of(&lcb, la, le) } else { (0, 0.0, 0.0) }, if rs { bins_of(&rcb, ra, re) } else { (0, 0.0, 0.0) });
            let kt = (k, bin_threshold(lo, scale, b, cb.lo[k], cb.hi[k]));
            let (mut lb, mut rb) = (Box::new(Binned::new()), Box::new(Binned::new()));
            let (l, r) = (&mut *lb, &mut *rb);
            let i = match (ls, rs) {
                (true, true) => partition::<true, true>(items, kt, lp, rp, l, r),
                (true, false) => partition::<true, false>(items, kt, lp, rp, l, r),
                (false, true) => partition::<false, true>(items, kt, lp, rp, l, r),
                (false, false) => partition::<false, false>(items, kt, lp, rp, l, r),
            };
            debug_assert_eq!(i, nl);
            if i > 0 && i < n {
                let l = Known { cb: lcb, bins: ls.then_some(lb) };
                let r = Known { cb: rcb, bins: rs.then_some(rb) };
                return (i, Some([l, r]));
            }
        }
    }
    let mid = n / 2;
    if n <= SMALL_SORT {
        sort_small(items, axis);
    } else {
        items.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]).then(a.tri.cmp(&b.tri)));
    }
    (mid, None)
}

/// Items up to which a median split sorts them all (by keys, cheaper than moving the
/// items in `select_nth_unstable_by`'s small sort).
pub(crate) const SMALL_SORT: usize = 32;

/// Sort `items` (at most [`SMALL_SORT`]) by their centroid along `axis`, then by triangle
/// (`total_cmp`, then the index: a total order, so one result). The median split's
/// `select_nth_unstable_by` sorts slices of up to 16 items entirely, and of a node of up
/// to 32 only the two halves' sets matter (each half, of 8 to 16 items, is sorted again
/// by its own split): the same tree.
pub(crate) fn sort_small(items: &mut [Item], axis: usize) {
    let n = items.len();
    debug_assert!(n <= SMALL_SORT);
    // total_cmp's order as an unsigned integer, then the triangle, then the position
    let key = |it: &Item, pos: usize| {
        let b = it.centroid[axis].to_bits() as i64;
        let t = (b ^ ((((b >> 63) as u64) >> 1) as i64)) as u64 ^ (1 << 63);
        ((t as u128) << 64) | ((it.tri as u128) << 32) | pos as u128
    };
    let mut keys = [0u128; SMALL_SORT];
    for (pos, it) in items.iter().enumerate() {
        keys[pos] = key(it, pos);
    }
    let keys = &mut keys[..n];
    keys.sort_unstable();
    // the items copied aside: only the n there are (not an array of 32 filled first)
    let mut tmp = [std::mem::MaybeUninit::<Item>::uninit(); SMALL_SORT];
    for (t, it) in tmp.iter_mut().zip(items.iter()) {
        t.write(*it);
    }
    for (it, k) in items.iter_mut().zip(keys.iter()) {
        // SAFETY: a key's low bits are its item's position, below n, and tmp[..n] is written
        *it = unsafe { tmp[(*k as u32) as usize].assume_init() };
    }
}

fn node_of(lb: &Aabb, rb: &Aabb, lc: Child, rc: Child) -> Node {
    let (d, u) = (|x| f32_out(x, false), |x| f32_out(x, true));
    Node {
        lo: [[d(lb.lo[0]), d(rb.lo[0])], [d(lb.lo[1]), d(rb.lo[1])], [d(lb.lo[2]), d(rb.lo[2])]],
        hi: [[u(lb.hi[0]), u(rb.hi[0])], [u(lb.hi[1]), u(rb.hi[1])], [u(lb.hi[2]), u(rb.hi[2])]],
        child: [lc, rc],
    }
}

fn leaf(items: &[Item], first: u32) -> (Aabb, Child) {
    let mut b = Aabb::EMPTY;
    for it in items {
        b.grow(&it.lo, &it.hi);
    }
    (b, Child { index: first, count: items.len() as u32 })
}

/// Build the subtree of `items` (slots from `first`) into `out`, depth first: its box and reference.
fn build_seq(items: &mut [Item], first: u32, depth: usize, known: Option<Known>, out: &mut Vec<Node>) -> (Aabb, Child) {
    if items.len() <= LEAF {
        return leaf(items, first);
    }
    let (mid, parts) = split(items, depth, known);
    let (left, right) = items.split_at_mut(mid);
    let at = out.len();
    out.push(Node::EMPTY);
    let (lk, rk) = match parts {
        Some([l, r]) => (Some(l), Some(r)),
        None => (None, None),
    };
    let (lb, lc) = build_seq(left, first, depth + 1, lk, out);
    let (rb, rc) = build_seq(right, first + mid as u32, depth + 1, rk, out);
    out[at] = node_of(&lb, &rb, lc, rc);
    (lb.join(&rb), Child { index: at as u32, count: 0 })
}

/// A subtree built in parallel: built sequentially (nodes indexed from 0), or split in two.
#[cfg_attr(test, derive(Clone))]
enum Part {
    Seq(Aabb, Child, Vec<Node>),
    Split(Aabb, Box<Part>, Box<Part>),
}

fn build_par(items: &mut [Item], first: u32, depth: usize, known: Option<Known>) -> Part {
    if items.len() <= PAR {
        // room for the nodes of leaves of 2.7 triangles on average (the torus's are 3.1:
        // 0.32 nodes a triangle), so that the vector rarely grows (copies, fresh pages)
        let mut out = Vec::with_capacity(items.len() * 3 / 8);
        let (b, c) = build_seq(items, first, depth, known, &mut out);
        return Part::Seq(b, c, out);
    }
    let (mid, parts) = split(items, depth, known);
    let (left, right) = items.split_at_mut(mid);
    let (lk, rk) = match parts {
        Some([l, r]) => (Some(l), Some(r)),
        None => (None, None),
    };
    let (l, r) = rayon::join(|| build_par(left, first, depth + 1, lk), || build_par(right, first + mid as u32, depth + 1, rk));
    let b = l.bounds().join(&r.bounds());
    Part::Split(b, Box::new(l), Box::new(r))
}

impl Part {
    fn bounds(&self) -> Aabb {
        match self {
            Part::Seq(b, _, _) | Part::Split(b, _, _) => *b,
        }
    }
    /// The number of nodes of the subtree.
    fn len(&self) -> usize {
        match self {
            Part::Seq(_, _, nodes) => nodes.len(),
            Part::Split(_, l, r) => 1 + l.len() + r.len(),
        }
    }

    /// The tree's nodes, depth first (the order and nodes of [`Part::flatten`]), written
    /// once each, in parallel by subtrees, into a vector not filled before (the pages'
    /// first touch is in the parallel writes, not in a serial fill of 20 MB at 1 M
    /// triangles); and the root's reference.
    fn flatten_all(self) -> (Vec<Node>, Child) {
        let n = self.len();
        let mut nodes = Vec::with_capacity(n);
        let root = self.flatten_into(&mut nodes.spare_capacity_mut()[..n], 0);
        // SAFETY: flatten_into wrote each of the n places (its slice is split exactly
        // among the subtrees, each of which writes all of its own, lengths asserted)
        unsafe { nodes.set_len(n) };
        (nodes, root)
    }

    /// Write the subtree's nodes into `out` (exactly [`Part::len`] of them, the first at
    /// index `at` of the tree, each written once), depth first: the order and nodes of
    /// [`Part::flatten`], the two halves of a split written in parallel; its reference.
    fn flatten_into(self, out: &mut [std::mem::MaybeUninit<Node>], at: u32) -> Child {
        assert_eq!(out.len(), self.len());
        match self {
            Part::Seq(_, c, nodes) => {
                let shift = |c: Child| if c.count == 0 { Child { index: c.index + at, count: 0 } } else { c };
                for (o, n) in out.iter_mut().zip(&nodes) {
                    o.write(Node { child: [shift(n.child[0]), shift(n.child[1])], ..*n });
                }
                shift(c)
            }
            Part::Split(_, l, r) => {
                let (lb, rb) = (l.bounds(), r.bounds());
                let nl = l.len();
                let (head, rest) = out.split_at_mut(1);
                let (lo, ro) = rest.split_at_mut(nl);
                let (lc, rc) = rayon::join(|| l.flatten_into(lo, at + 1), || r.flatten_into(ro, at + 1 + nl as u32));
                head[0].write(node_of(&lb, &rb, lc, rc));
                Child { index: at, count: 0 }
            }
        }
    }

    /// Append the subtree's nodes to `out` (depth first); its reference.
    #[cfg(test)]
    fn flatten(self, out: &mut Vec<Node>) -> Child {
        match self {
            Part::Seq(_, c, nodes) => {
                let by = out.len() as u32;
                let shift = |c: Child| if c.count == 0 { Child { index: c.index + by, count: 0 } } else { c };
                out.extend(nodes.iter().map(|n| Node { child: [shift(n.child[0]), shift(n.child[1])], ..*n }));
                shift(c)
            }
            Part::Split(_, l, r) => {
                let (lb, rb) = (l.bounds(), r.bounds());
                let at = out.len();
                out.push(Node::EMPTY);
                let lc = l.flatten(out);
                let rc = r.flatten(out);
                out[at] = node_of(&lb, &rb, lc, rc);
                Child { index: at as u32, count: 0 }
            }
        }
    }
}

/// Squared distances from `p` to both child boxes of a node.
#[inline(always)]
fn child_distances2(p: &V3, n: &Node) -> [f64; 2] {
    let mut d = [0.0; 2];
    for k in 0..3 {
        for c in 0..2 {
            let v = (n.lo[k][c] as f64 - p[k]).max(p[k] - n.hi[k][c] as f64).max(0.0);
            d[c] += v * v;
        }
    }
    d
}

/// The build item of triangle `i` with corners `c`: its index, box and centroid.
#[inline(always)]
fn item_of(i: usize, c: &[V3; 3]) -> Item {
    let mut lo = c[0];
    let mut hi = c[0];
    for v in &c[1..] {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let centroid = [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0, (c[0][2] + c[1][2] + c[2][2]) / 3.0];
    Item { tri: i as u32, centroid, lo, hi }
}

/// The build's items of `n` triangles (corners `corner(i)`): index, box and centroid.
/// Their buffer's capacity is a multiple of 9 items (720 bytes, 10 slots' corners), so
/// that [`corners_over_items`] can reuse it.
fn build_items(n: usize, corner: impl Fn(usize) -> [V3; 3] + Sync) -> Vec<Item> {
    use rayon::prelude::*;
    // `with_capacity` gives exactly the capacity asked for, and `par_extend` of an
    // exact-length iterator within it does not reallocate
    let mut items = Vec::with_capacity(n.div_ceil(9) * 9);
    items.par_extend((0..n).into_par_iter().map(|i| item_of(i, &corner(i))));
    items
}

const _: () = assert!(std::mem::size_of::<Item>() == 80 && std::mem::size_of::<[V3; 3]>() == 72 && std::mem::align_of::<Item>() == std::mem::align_of::<[V3; 3]>());
// Binned::grow_avx reads the low corner and centroid, and the centroid and high corner, as six numbers each
const _: () = assert!(std::mem::offset_of!(Item, centroid) == std::mem::offset_of!(Item, lo) + 24 && std::mem::offset_of!(Item, hi) == std::mem::offset_of!(Item, centroid) + 24);

/// The slots' corners (`corner(order[s])` for slot s) written over the items' buffer,
/// which the build no longer reads: 72 of each item's 80 bytes, front to back, in
/// parallel. Saves a fresh 72 MB at 1 M triangles (18 k page faults, each a kernel
/// entry and a page cleared) and the release of the items' 80 MB. When the buffer's
/// size is not a whole number of corner triples (not from [`build_items`]), a new
/// vector, the same values.
fn corners_over_items(items: Vec<Item>, order: &[u32], corner: &(impl Fn(usize) -> [V3; 3] + Sync)) -> Vec<[V3; 3]> {
    use rayon::prelude::*;
    let n = order.len();
    let bytes = items.capacity() * std::mem::size_of::<Item>();
    if items.len() != n || bytes % std::mem::size_of::<[V3; 3]>() != 0 {
        return order.par_iter().map(|&t| corner(t as usize)).collect();
    }
    let cap = bytes / std::mem::size_of::<[V3; 3]>();
    let mut items = std::mem::ManuallyDrop::new(items);
    let ptr = items.as_mut_ptr() as *mut std::mem::MaybeUninit<[V3; 3]>;
    // SAFETY: the buffer holds `cap` >= n corner triples (its bytes, aligned alike, checked
    // above); the items are `Copy` (nothing to drop) and never read again (`items` is
    // forgotten); each element is written once, through a `MaybeUninit` (the items'
    // padding bytes are not read)
    let out = unsafe { std::slice::from_raw_parts_mut(ptr, n) };
    out.par_iter_mut().zip(order.par_iter()).for_each(|(o, &t)| {
        o.write(corner(t as usize));
    });
    // SAFETY: the first n elements are written; the allocation's size is cap * 72 bytes
    // and its alignment that of the corners (the same as the items')
    unsafe { Vec::from_raw_parts(ptr as *mut [V3; 3], n, cap) }
}

/// (The items' former collection, kept for the in-place test.)
#[cfg(test)]
fn build_items_plain(n: usize, corner: impl Fn(usize) -> [V3; 3] + Sync) -> Vec<Item> {
    use rayon::prelude::*;
    (0..n)
        .into_par_iter()
        .map(|i| item_of(i, &corner(i)))
        .collect()
}

impl Bvh {
    /// The hierarchy of the triangles `corners` (at least one).
    pub fn new(corners: &[[V3; 3]]) -> Self {
        Self::build(corners.len(), |i| corners[i])
    }

    /// The hierarchy of `n` triangles (at least one), triangle `i` having the corners
    /// `corner(i)` (read from a mesh's vertices and triangles, without a copy of all
    /// corners in triangle order).
    pub fn build(n: usize, corner: impl Fn(usize) -> [V3; 3] + Sync) -> Self {
        use rayon::prelude::*;
        let mut items = build_items(n, &corner);
        let part = build_par(&mut items, 0, 0, None);
        let b = part.bounds();
        // the nodes written in place by subtrees in parallel
        let (nodes, root) = part.flatten_all();
        let order: Vec<u32> = items.par_iter().map(|it| it.tri).collect();
        let corners = corners_over_items(items, &order, &corner);
        let bounds = corners.par_iter().map(Bound::of).collect();
        // the bound's data and evaluation are exact to about 1e-15 of the coordinates'
        // size (points are compared within the same size, see `slack_at`)
        let size = b.lo.iter().chain(b.hi.iter()).fold(0.0f64, |s, x| s.max(x.abs()));
        Self { nodes, root, root_lo: b.lo, root_hi: b.hi, corners, order, bounds, slack: 1e-9 * (1.0 + size), size }
    }

    /// The depth of the deepest leaf (the root is at depth 0).
    pub fn depth(&self) -> usize {
        fn walk(b: &Bvh, c: Child) -> usize {
            if c.count > 0 {
                return 0;
            }
            let n = &b.nodes[c.index as usize];
            1 + walk(b, n.child[0]).max(walk(b, n.child[1]))
        }
        walk(self, self.root)
    }

    /// Squared distance from `p` to the triangle in `slot`, with the closest point and feature.
    #[inline]
    pub fn to_slot(&self, p: V3, slot: u32) -> Nearest {
        let c = &self.corners[slot as usize];
        let (foot, feature) = closest_point(p, c[0], c[1], c[2]);
        let v = sub(p, foot);
        Nearest { slot, d2: dot(v, v), foot, feature }
    }

    /// The nearest triangle to `p` not farther than `sqrt(bound2)` (None if there is
    /// none); of triangles at exactly the same squared distance, the lowest slot, so the
    /// answer depends on `p` only, never on the hint or the order of the queries.
    /// `hint`: a slot to try first (its distance starts the bound).
    #[inline]
    pub fn nearest(&self, p: V3, bound2: f64, hint: Option<u32>) -> Option<Nearest> {
        let start = hint.filter(|&h| (h as usize) < self.corners.len()).map(|h| self.to_slot(p, h));
        self.search::<false>(p, bound2, start).best
    }

    /// [`Bvh::nearest`] from a triangle already measured (`start`, e.g. [`Bvh::to_slot`]
    /// of a hint), and the margin: a lower bound of the squared distance from `p` of
    /// every triangle but the one returned (the least bound the search pruned by: a box
    /// it did not open, a triangle it did not keep). The margin certifies later queries
    /// near `p` without a search (see [`crate::distance::Cache`]).
    #[inline]
    pub fn nearest_with_margin(&self, p: V3, bound2: f64, start: Option<Nearest>) -> (Option<Nearest>, f64) {
        let r = self.search::<true>(p, bound2, start);
        (r.best, r.margin2)
    }

    /// [`Bvh::nearest_with_margin`] with the runner-up: the nearest of the triangles the
    /// search measured and did not keep, and the margin of every triangle but those two.
    /// Where two triangles tie (a point whose closest point is on their shared edge) the
    /// margin of the nearest alone is its own distance, and certifies nothing; the pair's
    /// margin still does ([`crate::distance::Cache`]).
    #[inline]
    pub fn nearest_with_runner_up(&self, p: V3, bound2: f64, start: Option<Nearest>) -> Searched {
        self.search::<true>(p, bound2, start)
    }

    /// The slack of the lower bounds for a point `p`: [`Bvh::slack`] grown with the
    /// point's own size (a far point's coordinates round on a coarser grid); at least
    /// 1e-9 (size + |p|_inf), which [`SLACK32`] relies on.
    #[inline(always)]
    pub(crate) fn slack_at(&self, p: &V3) -> f64 {
        self.slack_of(p[0].abs().max(p[1].abs()).max(p[2].abs()))
    }

    /// [`Bvh::slack_at`] of a point whose largest |coordinate| is `inf`.
    #[inline(always)]
    fn slack_of(&self, inf: f64) -> f64 {
        self.slack + 1e-9 * inf
    }

    #[inline(always)]
    fn search<const MARGIN: bool>(&self, p: V3, bound2: f64, start: Option<Nearest>) -> Searched {
        let mut best: Option<Nearest> = None;
        let mut best_d2 = bound2;
        let mut skip = u32::MAX;
        let mut margin = f64::INFINITY;
        // the runner-up (slot, squared distance): kept out of `margin`
        let mut second: (u32, f64) = (u32::MAX, f64::INFINITY);
        // record a lower bound of something pruned (compiled out without MARGIN)
        macro_rules! pruned {
            ($d:expr) => {
                if MARGIN {
                    margin = margin.min($d);
                }
            };
        }
        // a triangle measured and not kept: the runner-up if nearer than the last one
        // (which then goes to the margin), else to the margin
        macro_rules! passed {
            ($slot:expr, $d:expr) => {
                if MARGIN {
                    if $d < second.1 {
                        margin = margin.min(second.1);
                        second = ($slot, $d);
                    } else {
                        margin = margin.min($d);
                    }
                }
            };
        }
        macro_rules! done {
            () => {
                return Searched { best, margin2: margin.min(second.1), second: second.0, rest2: margin }
            };
        }
        if let Some(n) = start {
            if n.d2 <= best_d2 {
                best_d2 = n.d2;
                best = Some(n);
                skip = n.slot;
            } else {
                pruned!(n.d2);
            }
        }
        // open: a box at squared distance d may hold something better (a triangle at
        // the best distance with a lower slot wins the tie)
        macro_rules! open {
            ($d:expr) => {
                $d <= best_d2
            };
        }
        let d_root = box_distance2(&p, &self.root_lo, &self.root_hi);
        if !open!(d_root) {
            pruned!(d_root);
            done!();
        }
        let mut stack = [(Child { index: 0, count: 0 }, 0.0f64); MAX_DEPTH + 2];
        let mut sp = 0usize;
        let mut cur = self.root;
        // the point and its reduction in single precision for the triangles' lower bounds,
        // and the bounds' right side (kept as the best changes)
        let (q, reach) = ([p[0] as f32, p[1] as f32, p[2] as f32], Bound::reach32(self.slack_at(&p)));
        let mut side = Bound::side32(best_d2);
        loop {
            if cur.count > 0 {
                for slot in cur.index..cur.index + cur.count {
                    if slot == skip {
                        continue;
                    }
                    // a triangle proved farther than the best is not measured (without
                    // margins only: the margins need every triangle's distance)
                    if !MARGIN && !self.bounds[slot as usize].passes(&q, reach, side) {
                        continue;
                    }
                    let c = &self.corners[slot as usize];
                    let (foot, feature) = closest_point(p, c[0], c[1], c[2]);
                    let v = sub(p, foot);
                    let d2 = dot(v, v);
                    if better(d2, slot, best_d2, best.as_ref().map(|b| b.slot)) {
                        if let Some(b) = &best {
                            passed!(b.slot, b.d2);
                        }
                        best_d2 = d2;
                        side = Bound::side32(d2);
                        best = Some(Nearest { slot, d2, foot, feature });
                    } else {
                        passed!(slot, d2);
                    }
                }
            } else {
                let n = &self.nodes[cur.index as usize];
                let d = child_distances2(&p, n);
                let (near, dn, far, df) = if d[0] <= d[1] { (n.child[0], d[0], n.child[1], d[1]) } else { (n.child[1], d[1], n.child[0], d[0]) };
                if open!(dn) {
                    if open!(df) {
                        stack[sp] = (far, df);
                        sp += 1;
                    } else {
                        pruned!(df);
                    }
                    cur = near;
                    continue;
                }
                pruned!(dn);
            }
            // pop the next subtree still worth visiting
            loop {
                if sp == 0 {
                    done!();
                }
                sp -= 1;
                let (c, d) = stack[sp];
                if open!(d) {
                    cur = c;
                    break;
                }
                pruned!(d);
            }
        }
    }

    /// [`Bvh::nearest`] of up to [`GROUP`] points at once: the points walk the tree
    /// together (a node is read once for the group and opened for the points its
    /// boxes may improve), so coherent points (neighbours along a scan line or a Morton
    /// curve) share the path from the root. `best[i]` holds point i's start on entry (a
    /// triangle measured with [`Bvh::to_slot`]; None: no start) and its nearest triangle
    /// within `sqrt(bound2)` on return. Each answer is [`Bvh::nearest`]'s, to the bit.
    ///
    /// On x86-64 processors with AVX2 the same code is run compiled for AVX2 (chosen at
    /// run time): wider vectors for the per-lane box distances, and one instruction
    /// where the lanes' masks are counted (`count_ones`, `is_power_of_two`) instead of
    /// about a dozen; the eight lanes' single-precision triangle lower bounds
    /// ([`Bound::lower32`]) are one vector either way. With AVX-512 (F and VL) it is
    /// compiled for that: the eight lanes' f64 exact tests in one vector instead of two,
    /// and a node's two children's box tests in one 16-lane vector (`child_boxes16`).
    /// Rust never fuses a multiply and an add unless told to (`mul_add`; AVX-512 enables
    /// the FMA instructions, none is emitted here), so every build gives the same bits
    /// (tested: each build the processor runs against the others).
    pub fn nearest_group(&self, ps: &[V3], bound2: f64, best: &mut [Option<Nearest>]) {
        self.nearest_group_from(ps, bound2, &[], best)
    }

    /// [`Bvh::nearest_group`] that first measures the triangles in the slots `hints` (out
    /// of range: ignored) for every lane at once ([`closest_lanes`], the same bits as
    /// [`Bvh::to_slot`]): each lane starts from the nearest of its entry in `best` and the
    /// hints (the lowest slot among exact ties). The answers are [`Bvh::nearest`]'s.
    pub fn nearest_group_from(&self, ps: &[V3], bound2: f64, hints: &[u32], best: &mut [Option<Nearest>]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl") && std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("bmi1") && std::is_x86_feature_detected!("popcnt") {
            // SAFETY: the features were detected on this processor
            return unsafe { self.nearest_group_avx512(ps, bound2, hints, best) };
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("bmi1") && std::is_x86_feature_detected!("popcnt") {
            // SAFETY: the features were detected on this processor
            return unsafe { self.nearest_group_avx2(ps, bound2, hints, best) };
        }
        self.nearest_group_impl::<false, false>(ps, bound2, hints, best)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,popcnt")]
    unsafe fn nearest_group_avx2(&self, ps: &[V3], bound2: f64, hints: &[u32], best: &mut [Option<Nearest>]) {
        self.nearest_group_impl::<true, false>(ps, bound2, hints, best)
    }

    /// [`Bvh::nearest_group_impl`] compiled for AVX-512: a node's two children's box
    /// tests in one 16-lane single-precision vector ([`child_boxes16`]), the descent's box
    /// test in two ([`boxes_meet16`]); the other lanes' masks by AVX2's comparisons
    /// ([`lanes_le32`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx2,bmi1,popcnt")]
    unsafe fn nearest_group_avx512(&self, ps: &[V3], bound2: f64, hints: &[u32], best: &mut [Option<Nearest>]) {
        self.nearest_group_impl::<true, true>(ps, bound2, hints, best)
    }

    /// [`Bvh::nearest_group_from`]'s answers from every build this processor runs (plain,
    /// AVX2, AVX-512), each from the starts `best`: the tests check they agree to the bit.
    #[cfg(test)]
    pub(crate) fn nearest_group_every_build(&self, ps: &[V3], bound2: f64, hints: &[u32], best: &[Option<Nearest>]) -> Vec<Vec<Option<Nearest>>> {
        let mut out = vec![best.to_vec()];
        self.nearest_group_impl::<false, false>(ps, bound2, hints, &mut out[0]);
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("bmi1") && std::is_x86_feature_detected!("popcnt") {
            let mut b = best.to_vec();
            // SAFETY: the features were detected on this processor
            unsafe { self.nearest_group_avx2(ps, bound2, hints, &mut b) };
            out.push(b);
            if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl") {
                let mut b = best.to_vec();
                // SAFETY: as above
                unsafe { self.nearest_group_avx512(ps, bound2, hints, &mut b) };
                out.push(b);
            }
        }
        out
    }

    /// `AVX`: compiled for AVX2 (see [`lanes_le32`]); `W16`: compiled for AVX-512, the
    /// node's box tests by [`child_boxes16`].
    #[inline(always)]
    fn nearest_group_impl<const AVX: bool, const W16: bool>(&self, ps: &[V3], bound2: f64, hints: &[u32], best: &mut [Option<Nearest>]) {
        let g = ps.len();
        assert!(g <= GROUP && best.len() == g);
        // per lane: coordinates (SoA), the best squared distance, the start's slot
        let (mut px, mut py, mut pz) = ([0.0f64; GROUP], [0.0f64; GROUP], [0.0f64; GROUP]);
        let mut bd = [f64::NEG_INFINITY; GROUP];
        // per lane: `Bound::side32` of `bd` and `Bound::reach32` of the slack, the leaf
        // bounds' right side and reduction
        let mut side = [f32::NEG_INFINITY; GROUP];
        let mut reach = [0.0f32; GROUP];
        let mut skip = [u32::MAX; GROUP];
        let mut slack = [0.0f64; GROUP];
        // the lanes in single precision for the box tests (see `widen`)
        let (mut qx, mut qy, mut qz) = ([0.0f32; GROUP], [0.0f32; GROUP], [0.0f32; GROUP]);
        let mut err2 = [0.0f64; GROUP];
        let mut bw = [f32::NEG_INFINITY; GROUP];
        // the lanes in single precision twice over (lanes 0-7 against child 0, 8-15
        // against child 1: [`child_boxes16`])
        let mut q16 = [[0.0f32; 2 * GROUP]; 3];
        let size = self.size;
        let mut all = 0u32;
        for i in 0..g {
            (px[i], py[i], pz[i]) = (ps[i][0], ps[i][1], ps[i][2]);
        }
        // the exact tests of the lanes, eight at once (lanes past `g` are never read)
        let mut cl = Closest8 { d2: [0.0; LANES], foot: [[0.0; LANES]; 3], code: [0; LANES] };
        for &h in hints {
            let Some(c) = self.corners.get(h as usize) else { continue };
            closest_lanes([&px, &py, &pz], c[0], c[1], c[2], &mut cl);
            for i in 0..g {
                let d2 = cl.d2[i];
                if best[i].map_or(true, |b| d2 < b.d2 || (d2 == b.d2 && h < b.slot)) {
                    best[i] = Some(Nearest { slot: h, d2, foot: [cl.foot[0][i], cl.foot[1][i], cl.foot[2][i]], feature: feature_of_code(cl.code[i]) });
                }
            }
        }
        for i in 0..g {
            bd[i] = bound2;
            match best[i] {
                Some(n) if n.d2 <= bound2 => {
                    bd[i] = n.d2;
                    skip[i] = n.slot;
                }
                _ => best[i] = None,
            }
            all |= 1 << i;
        }
        // the lanes' numbers for the tests, over all GROUP lanes without a branch (they
        // compile to vector instructions; lanes past `g` have the point 0 and `bd` minus
        // infinity, so `side` and `bw` minus infinity, and are never in a mask)
        for i in 0..GROUP {
            // |p|_inf, taken once for the slack and the box tests' rounding
            let m = px[i].abs().max(py[i].abs()).max(pz[i].abs());
            slack[i] = self.slack_of(m);
            (qx[i], qy[i], qz[i]) = (px[i] as f32, py[i] as f32, pz[i] as f32);
            side[i] = Bound::side32(bd[i]);
            reach[i] = Bound::reach32(slack[i]);
            err2[i] = widen_err2(F32_ERR * (size + m));
            bw[i] = widen(bd[i], err2[i]);
        }
        for (q, v) in q16.iter_mut().zip([&qx, &qy, &qz]) {
            q[..GROUP].copy_from_slice(v);
            q[GROUP..].copy_from_slice(v);
        }
        // lanes of `m` whose squared box distance in `d` may hold something better
        let open = |d: &[f64; GROUP], bd: &[f64; GROUP], m: u32| -> u32 {
            let mut o = 0u32;
            for i in 0..GROUP {
                o |= ((d[i] <= bd[i]) as u32) << i;
            }
            o & m
        };
        let mut d = [0.0f64; GROUP];
        for i in 0..g {
            d[i] = box_distance2(&ps[i], &self.root_lo, &self.root_hi);
        }
        let mut mask = open(&d, &bd, all);
        if mask == 0 {
            return;
        }
        // lanes of `m` whose single-precision box distance in `d` is within the widened best
        let open32 = |d: &[f32; GROUP], bw: &[f32; GROUP], m: u32| -> u32 { lanes_le32::<AVX>(d, bw) & m };
        // the subtrees still to visit: (reference, lanes, the lanes' box distances); left
        // uninitialised (3 KB of zeros a group cost more than the search of a near group):
        // entries below `sp` are always written before they are read
        let mut stack = [const { std::mem::MaybeUninit::<(Child, u32, [f32; GROUP])>::uninit() }; MAX_DEPTH + 2];
        let mut sp = 0usize;
        let mut cur = self.root;
        // the descent from the root by the box of the open lanes' balls (radius the best
        // distance plus the slack, far above the rounding of a triangle's distance; the
        // box rounded outwards to single precision): one test a child instead of one a
        // lane, as long as a single child's box meets it. A child whose box misses that
        // box holds no triangle any lane's search would keep, so the answers are the
        // walk's from the root. (The box alone is no walk: a ball touching the surface
        // meets few boxes, its bounding box many.)
        {
            // the open lanes' radii, minus infinity for the others (their ends are then
            // plus and minus infinity, which change no end); the ends kept by plain
            // comparisons, one instruction each, which pass over a NaN (none arises from
            // finite points) as `min` and `max` did
            let mut r = [f64::NEG_INFINITY; GROUP];
            for i in 0..GROUP {
                let ri = bd[i].sqrt() + slack[i];
                r[i] = if mask & (1 << i) != 0 { ri } else { f64::NEG_INFINITY };
            }
            let (mut glo, mut ghi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for (k, pk) in [&px, &py, &pz].into_iter().enumerate() {
                for i in 0..GROUP {
                    let (l, h) = (pk[i] - r[i], pk[i] + r[i]);
                    if l < glo[k] {
                        glo[k] = l;
                    }
                    if h > ghi[k] {
                        ghi[k] = h;
                    }
                }
            }
            let (glo, ghi) = (glo.map(|x| f32_out(x, false)), ghi.map(|x| f32_out(x, true)));
            // the box's ends as one vector: lanes 0-5 the high ends against the nodes'
            // low bounds, lanes 6-11 the low ends against their high bounds (the node's layout)
            let g16: [f32; 16] = [ghi[0], ghi[0], ghi[1], ghi[1], ghi[2], ghi[2], glo[0], glo[0], glo[1], glo[1], glo[2], glo[2], 0.0, 0.0, 0.0, 0.0];
            while cur.count == 0 {
                let n = &self.nodes[cur.index as usize];
                let (m0, m1) = if W16 {
                    // SAFETY: W16 is set only in the build compiled for AVX-512 F
                    unsafe { boxes_meet16(n, &g16) }
                } else {
                    // every comparison made (no short cut): no branch to mispredict
                    let meets = |c: usize| (0..3).fold(true, |a, k| a & (n.lo[k][c] <= ghi[k]) & (n.hi[k][c] >= glo[k]));
                    (meets(0), meets(1))
                };
                match (m0, m1) {
                    (true, true) => break,
                    (true, false) => cur = n.child[0],
                    (false, true) => cur = n.child[1],
                    (false, false) => return,
                }
            }
        }
        loop {
            if cur.count > 0 {
                for slot in cur.index..cur.index + cur.count {
                    // the lanes whose start this slot is measured it already (each lane
                    // meets a slot once in the walk): not again, and not counted towards
                    // the eight-lane exact test (all lanes mostly start from the same
                    // triangle; 1 M scan points: 5.2 of the 12.8 lanes a group passing
                    // the lower bounds were these)
                    let open = mask & !lanes_eq::<AVX>(&skip, slot);
                    if open == 0 {
                        continue;
                    }
                    let c = &self.corners[slot as usize];
                    // the lanes the triangle's lower bound does not rule out (all lanes
                    // at once; a lane's best changes only by its own test of this slot)
                    let mut m = if !W16 && open.is_power_of_two() {
                        // one lane (an outlier's search, mostly): its bound alone, the same
                        // bits. Not in the AVX-512 build, where the eight lanes' test is a
                        // few instructions more and the branch on the lane count goes (one
                        // thread, 3 M points of the bench's scan, ten alternated runs, load
                        // 0.6-0.8: 0.515 s median, min 0.505, against 0.522 and 0.514)
                        let i = open.trailing_zeros() as usize;
                        if self.bounds[slot as usize].passes(&[qx[i], qy[i], qz[i]], reach[i], side[i]) { open } else { 0 }
                    } else {
                        open & self.bounds[slot as usize].may_beat_lanes_in::<AVX>([&qx, &qy, &qz], &side, &reach)
                    };
                    if m.count_ones() >= VECTOR_EXACT {
                        // many lanes: their exact tests at once, the same bits
                        closest_lanes([&px, &py, &pz], c[0], c[1], c[2], &mut cl);
                        while m != 0 {
                            let i = m.trailing_zeros() as usize;
                            m &= m - 1;
                            let d2 = cl.d2[i];
                            if better(d2, slot, bd[i], best[i].as_ref().map(|b| b.slot)) {
                                bd[i] = d2;
                                side[i] = Bound::side32(d2);
                                bw[i] = widen(d2, err2[i]);
                                best[i] = Some(Nearest { slot, d2, foot: [cl.foot[0][i], cl.foot[1][i], cl.foot[2][i]], feature: feature_of_code(cl.code[i]) });
                            }
                        }
                    }
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let (foot, feature) = closest_point(ps[i], c[0], c[1], c[2]);
                        let v = sub(ps[i], foot);
                        let d2 = dot(v, v);
                        if better(d2, slot, bd[i], best[i].as_ref().map(|b| b.slot)) {
                            bd[i] = d2;
                            side[i] = Bound::side32(d2);
                            bw[i] = widen(d2, err2[i]);
                            best[i] = Some(Nearest { slot, d2, foot, feature });
                        }
                    }
                }
            } else {
                let n = &self.nodes[cur.index as usize];
                let (mut d0, mut d1) = ([0.0f32; GROUP], [0.0f32; GROUP]);
                let (m0, m1);
                if W16 {
                    // SAFETY: W16 is set only in the build compiled for AVX-512 F and VL,
                    // run only where the processor has them
                    let m = unsafe { child_boxes16(n, &q16, &bw, &mut d0, &mut d1) };
                    (m0, m1) = (m & mask, (m >> GROUP) & mask);
                } else {
                    for i in 0..GROUP {
                        let q = [qx[i], qy[i], qz[i]];
                        let (mut a, mut b) = (0.0f32, 0.0f32);
                        for k in 0..3 {
                            let u = larger(larger(n.lo[k][0] - q[k], q[k] - n.hi[k][0]), 0.0);
                            let w = larger(larger(n.lo[k][1] - q[k], q[k] - n.hi[k][1]), 0.0);
                            a += u * u;
                            b += w * w;
                        }
                        d0[i] = a;
                        d1[i] = b;
                    }
                    (m0, m1) = (open32(&d0, &bw, mask), open32(&d1, &bw, mask));
                }
                if m0 != 0 || m1 != 0 {
                    // the nearer child first: the one nearer to most of the open lanes (not
                    // to the first open lane: 300 k points of the torus bench, 522 M against
                    // 528 M instructions)
                    let near1 = !lanes_le32::<AVX>(&d0, &d1) & (m0 | m1);
                    let first = if m0 == 0 || (m1 != 0 && 2 * near1.count_ones() > (m0 | m1).count_ones()) { 1 } else { 0 };
                    let (mf, ms, ds) = if first == 0 { (m0, m1, d1) } else { (m1, m0, d0) };
                    if ms != 0 {
                        stack[sp].write((n.child[1 - first], ms, ds));
                        sp += 1;
                    }
                    if mf != 0 {
                        cur = n.child[first];
                        mask = mf;
                        continue;
                    }
                }
            }
            // pop the next subtree still worth visiting for some lane
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: every entry below the old `sp` was written by a push
                let (c, m, ds) = unsafe { stack[sp].assume_init() };
                let o = open32(&ds, &bw, m);
                if o != 0 {
                    cur = c;
                    mask = o;
                    break;
                }
            }
        }
    }
}

/// A node's two children's squared single-precision box distances for the [`GROUP`]
/// lanes in one 16-lane AVX-512 vector (lanes 0-7 the lanes against child 0, 8-15 against
/// child 1; `q` each coordinate of the lanes twice over): written to `d0` and `d1`, and
/// the mask of those within the lanes' widened best `bw` (bits 0-7 child 0, 8-15 child 1).
/// The arithmetic of the eight-lane loop it replaces, operation for operation
/// (`max(max(lo - q, q - hi), 0)` squared, summed over x, y, z from 0, no fused
/// multiply-add; `vmaxps` is [`larger`]), so the same bits: half the vector instructions.
///
/// # Safety
/// The processor has AVX-512 F and VL (the caller runs compiled for them).
#[inline(always)]
#[allow(unused_variables)]
unsafe fn child_boxes16(n: &Node, q: &[[f32; 2 * GROUP]; 3], bw: &[f32; GROUP], d0: &mut [f32; GROUP], d1: &mut [f32; GROUP]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // the node's 64 bytes: lo (x0 x1 y0 y1 z0 z1), hi (the same), the children
        let raw = _mm512_load_ps(n as *const Node as *const f32);
        let zero = _mm512_setzero_ps();
        let mut d = zero;
        for k in 0..3 {
            let (l, h) = (2 * k as i32, 6 + 2 * k as i32);
            // child 0's value in lanes 0-7, child 1's in lanes 8-15
            let lo = _mm512_permutexvar_ps(_mm512_set_epi32(l + 1, l + 1, l + 1, l + 1, l + 1, l + 1, l + 1, l + 1, l, l, l, l, l, l, l, l), raw);
            let hi = _mm512_permutexvar_ps(_mm512_set_epi32(h + 1, h + 1, h + 1, h + 1, h + 1, h + 1, h + 1, h + 1, h, h, h, h, h, h, h, h), raw);
            let qk = _mm512_loadu_ps(q[k].as_ptr());
            let u = _mm512_max_ps(_mm512_max_ps(_mm512_sub_ps(lo, qk), _mm512_sub_ps(qk, hi)), zero);
            d = _mm512_add_ps(d, _mm512_mul_ps(u, u));
        }
        let w = _mm256_loadu_ps(bw.as_ptr());
        let w16 = _mm512_castpd_ps(_mm512_broadcast_f64x4(_mm256_castps_pd(w)));
        let m = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(d, w16) as u32;
        _mm256_storeu_ps(d0.as_mut_ptr(), _mm512_castps512_ps256(d));
        _mm256_storeu_ps(d1.as_mut_ptr(), _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(d))));
        m
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("the 16-lane box test runs only in the AVX-512 build")
}

/// Does each child's box of `n` meet the box whose ends are `g` (lanes 0-5: the high
/// ends x x y y z z, lanes 6-11: the low ends)? All 12 comparisons of the plain test
/// (`lo <= high end`, `hi >= low end`, per axis and child) by two AVX-512 comparisons of
/// the node loaded as one vector: (child 0, child 1).
///
/// # Safety
/// The processor has AVX-512 F.
#[inline(always)]
#[allow(unused_variables)]
unsafe fn boxes_meet16(n: &Node, g: &[f32; 16]) -> (bool, bool) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let raw = _mm512_load_ps(n as *const Node as *const f32);
        let gv = _mm512_loadu_ps(g.as_ptr());
        let le = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(raw, gv) as u32;
        let ge = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(raw, gv) as u32;
        let m = (le & 0x03f) | (ge & 0xfc0);
        (m & 0x555 == 0x555, m & 0xaaa == 0xaaa)
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("only in the AVX-512 build")
}

const _: () = assert!(std::mem::size_of::<Node>() == 64 && std::mem::align_of::<Node>() == 64, "child_boxes16 loads a node as one aligned vector");

/// Relative rounding of a coordinate to single precision, with room: the lanes' box
/// tests of [`Bvh::nearest_group`] run on the point rounded to f32 (the boxes are f32
/// already), each axis's gap then off by at most `F32_ERR * (size of the coordinates)`.
const F32_ERR: f64 = 1.0 / (1u64 << 22) as f64;

/// The single-precision threshold a lane's f32 squared box distance is compared with:
/// a box whose exact squared distance is at most `bd` has an f32 distance at most
/// (x c + s)^2 with x = sqrt(bd), c = 1 + 2^-21, s = sqrt(3) err (each of the three gaps
/// is off by at most `err` from the point's rounding and the subtraction, the squares and
/// the sum by a relative 2^-22). Without the square root: 2 x c s <= t x^2 c^2 + s^2 / t
/// for any t > 0 (the square (sqrt(t) x c - s / sqrt(t))^2 is not negative), so
/// (x c + s)^2 <= bd c^2 (1 + t) + 3 err^2 (1 + 1 / t); with t = 2^-10 the threshold
/// grows by under 0.05 % of the distance and the rounding term by a factor 32 of the
/// distance (both only open a few more boxes). That sum ([`WIDEN_BD`] times `bd` plus
/// [`widen_err2`] of `err`, both with the room 1e-5) is rounded to the nearest single
/// precision number: the room covers the sum's few f64 roundings (relative 2^-53 each)
/// and that last one (relative 2^-24 in the normal range; the 1e-38 in [`widen_err2`]
/// covers its absolute 2^-150 below it), so no branch is needed to round up. So the boxes opened
/// are a superset of those the exact test opens: only the speed depends on it, never
/// the answer.
#[inline(always)]
pub(crate) fn widen(bd: f64, err2: f64) -> f32 {
    if !(bd >= 0.0) {
        return f32::NEG_INFINITY;
    }
    (bd * WIDEN_BD + err2) as f32
}

/// The factor t of [`widen`]'s bound 2 x c s <= t x^2 c^2 + s^2 / t.
const WIDEN_T: f64 = 1.0 / 1024.0;
/// [`widen`]'s factor of `bd`: c^2 (1 + t) with c = 1 + 2^-21, and the room 1e-5.
const WIDEN_BD: f64 = (1.0 + 1.0 / (1u64 << 21) as f64) * (1.0 + 1.0 / (1u64 << 21) as f64) * (1.0 + WIDEN_T) * (1.0 + 1e-5);

/// [`widen`]'s rounding term of a lane whose gaps are off by at most `err`:
/// 3 err^2 (1 + 1 / t), with the room 1e-5, plus 1e-38 (for the rounding to single
/// precision below its normal range).
#[inline(always)]
pub(crate) fn widen_err2(err: f64) -> f64 {
    3.0 * err * err * (1.0 + 1.0 / WIDEN_T) * (1.0 + 1e-5) + 1e-38
}

/// The larger of `a` and `b`; `b` when either is NaN. The same value as `a.max(b)` for
/// numbers, and one max instruction where `max` needs three (its NaN rule). In the lower
/// bounds and box distances a NaN (none arises from finite data) can then only drop a
/// term or turn a part into 0 (`larger(NaN, 0.0)` is 0): a smaller bound, which opens
/// more, so the answers stay exact.
#[inline(always)]
fn larger<T: PartialOrd>(a: T, b: T) -> T {
    if a > b {
        a
    } else {
        b
    }
}

/// Bit i set where `a[i] <= b[i]` (false for a NaN, as `<=`), for the [`GROUP`] lanes.
/// `AVX`: by one vector comparison and its sign mask, which compilers do not find for
/// the loop; only to be set in code compiled for AVX2 ([`Bvh::nearest_group`] checks the
/// processor before running it).
#[inline(always)]
pub(crate) fn lanes_le32<const AVX: bool>(a: &[f32; GROUP], b: &[f32; GROUP]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::{_mm256_cmp_ps, _mm256_loadu_ps, _mm256_movemask_ps, _CMP_LE_OQ};
        // SAFETY: AVX is there (the caller runs compiled for AVX2, chosen at run time);
        // the loads read the arrays' 8 lanes
        return unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_loadu_ps(a.as_ptr()), _mm256_loadu_ps(b.as_ptr()))) as u32 };
    }
    let mut o = 0u32;
    for i in 0..GROUP {
        o |= ((a[i] <= b[i]) as u32) << i;
    }
    o
}

/// Lanes of a leaf's triangle from which their exact tests are made eight at once (one
/// vector pass costs about five single tests in instructions; 300 k points of the torus
/// bench: 3 lanes 728 M instructions, 5 lanes 717 M, never 728 M).
const VECTOR_EXACT: u32 = 5;

const _: () = assert!(GROUP == 8 && LANES == GROUP, "lanes_le32 compares eight lanes");

/// Bit i set where `a[i] == b`, for the [`GROUP`] lanes. `AVX`: by one vector comparison
/// and its sign mask, as [`lanes_le32`] (only in code compiled for AVX2).
#[inline(always)]
pub(crate) fn lanes_eq<const AVX: bool>(a: &[u32; GROUP], b: u32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::{_mm256_castsi256_ps, _mm256_cmpeq_epi32, _mm256_loadu_si256, _mm256_movemask_ps, _mm256_set1_epi32};
        // SAFETY: AVX2 is there (the caller runs compiled for it, chosen at run time); the
        // load reads the array's 8 lanes
        return unsafe { _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_loadu_si256(a.as_ptr().cast()), _mm256_set1_epi32(b as i32)))) as u32 };
    }
    a.iter().enumerate().fold(0u32, |o, (i, &x)| o | ((x == b) as u32) << i)
}

/// Points per group of [`Bvh::nearest_group`].
pub const GROUP: usize = 8;

/// What a search with margins found: the nearest triangle (None: none within the
/// bound), `margin2` the least squared distance any other triangle can have, `second`
/// the runner-up's slot (`u32::MAX`: none measured) and `rest2` the least squared
/// distance of any triangle but those two.
#[derive(Debug, Clone, Copy)]
pub struct Searched {
    pub best: Option<Nearest>,
    pub margin2: f64,
    pub second: u32,
    pub rest2: f64,
}

/// Does a triangle (`slot`, squared distance `d2`) beat the best so far (`best_d2`, the
/// bound when there is none yet; `best` its slot)? Nearer, or as near with a lower slot.
#[inline(always)]
fn better(d2: f64, slot: u32, best_d2: f64, best: Option<u32>) -> bool {
    match best {
        None => d2 <= best_d2,
        Some(b) => d2 < best_d2 || (d2 == best_d2 && slot < b),
    }
}

#[cfg(test)]
mod flatten_tests {
    use super::*;

    /// The partition and the binning compiled for AVX2 (vminpd/vmaxpd rows) give the plain
    /// code's items, order and bins, to the bit: slivers, coincident and signed-zero
    /// coordinates among them, each side binned or not.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_partition_and_bins_equal_the_plain_ones() {
        use rand::{Rng, SeedableRng};
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let same = |a: &Binned, b: &Binned| a.count == b.count && a.mins.iter().chain(&a.maxs).flatten().map(|x| x.to_bits()).eq(b.mins.iter().chain(&b.maxs).flatten().map(|x| x.to_bits()));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for case in 0..40 {
            let n = [1, 2, 7, 33, 300, 5000][case % 6];
            let corners: Vec<[V3; 3]> = (0..n)
                .map(|_| {
                    let a: V3 = std::array::from_fn(|_| [0.0, -0.0, 1.0, rng.random_range(-50.0..50.0)][rng.random_range(0..4)]);
                    std::array::from_fn(|_| std::array::from_fn(|k| if rng.random_range(0..3) == 0 { a[k] } else { a[k] + rng.random_range(-1.0..1.0) }))
                })
                .collect();
            let items = build_items(n, |i| corners[i]);
            let cb = centroid_bounds(&items);
            let (axis, ext, _) = plan(&cb, n, 0);
            if !(ext > 0.0) {
                continue;
            }
            let (k, lo, scale) = bins_of(&cb, axis, ext);
            // SAFETY: AVX2 detected above
            let (plain, wide) = (bin_items_in::<false>(&items, k, lo, scale), unsafe { bin_items_avx2(&items, k, lo, scale) });
            assert!(same(&plain, &wide), "case {case}: bins");
            let b = 1 + case % (BINS - 1);
            if bin_of(cb.hi[k], lo, scale) < b {
                continue;
            }
            let t = bin_threshold(lo, scale, b, cb.lo[k], cb.hi[k]);
            let (lp, rp) = ((case % 3, lo, scale), ((case + 1) % 3, lo, scale));
            let (mut a, mut w) = (items.clone(), items.clone());
            let (mut la, mut ra, mut lw, mut rw) = (Binned::new(), Binned::new(), Binned::new(), Binned::new());
            let ia = partition_in::<true, true, false>(&mut a, (k, t), lp, rp, &mut la, &mut ra);
            // SAFETY: AVX2 detected above
            let iw = unsafe { partition_avx2::<true, true>(&mut w, (k, t), lp, rp, &mut lw, &mut rw) };
            assert_eq!(ia, iw, "case {case}");
            assert!(a.iter().map(|it| it.tri).eq(w.iter().map(|it| it.tri)), "case {case}: order");
            assert!(same(&la, &lw) && same(&ra, &rw), "case {case}: the sides' bins");
            assert_eq!(ia, items.iter().filter(|it| bin_of(it.centroid[k], lo, scale) < b).count());
        }
    }

    /// The nodes written in parallel in place ([`Part::flatten_into`]) are those appended
    /// one subtree after another ([`Part::flatten`]): the same nodes in the same order.
    #[test]
    fn the_parallel_flatten_writes_the_serial_one() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 20 * PAR + 37;
        let corners: Vec<[V3; 3]> = (0..n)
            .map(|_| {
                let a: V3 = std::array::from_fn(|_| rng.random_range(-50.0..50.0));
                std::array::from_fn(|_| std::array::from_fn(|k| a[k] + rng.random_range(-1.0..1.0)))
            })
            .collect();
        let mut items = build_items(n, |i| corners[i]);
        let part = build_par(&mut items, 0, 0, None);
        let mut serial = Vec::new();
        let root_serial = part.clone().flatten(&mut serial);
        let (par, root_par) = part.flatten_all();
        assert!(matches!(build_par(&mut build_items(n, |i| corners[i]), 0, 0, None), Part::Split(..)));
        // the corners written over the items' buffer are the plainly collected ones, the
        // items the same whichever way collected; a buffer of another size gets a new vector
        let order: Vec<u32> = items.iter().map(|it| it.tri).collect();
        let want: Vec<[V3; 3]> = order.iter().map(|&t| corners[t as usize]).collect();
        for m in [n, 1, 8, 9, 10, 17, 18, 1000] {
            let plain = build_items_plain(m, |i| corners[i]);
            let fresh = build_items(m, |i| corners[i]);
            assert_eq!(fresh.capacity() % 9, 0);
            assert!(plain.iter().zip(&fresh).all(|(a, b)| a.tri == b.tri && a.lo == b.lo && a.hi == b.hi && a.centroid == b.centroid));
            let ord: Vec<u32> = (0..m as u32).rev().collect();
            let w: Vec<[V3; 3]> = ord.iter().map(|&t| corners[t as usize]).collect();
            assert_eq!(corners_over_items(fresh, &ord, &|i| corners[i]), w);
            assert_eq!(corners_over_items(plain, &ord, &|i| corners[i]), w);
        }
        assert_eq!(corners_over_items(items.clone(), &order, &|i| corners[i]), want);
        assert_eq!(root_serial, root_par);
        assert_eq!(serial.len(), par.len());
        for (a, b) in serial.iter().zip(&par) {
            assert_eq!(a.child, b.child);
            assert_eq!(a.lo.map(|x| x.map(f32::to_bits)), b.lo.map(|x| x.map(f32::to_bits)));
            assert_eq!(a.hi.map(|x| x.map(f32::to_bits)), b.hi.map(|x| x.map(f32::to_bits)));
        }
    }
}
