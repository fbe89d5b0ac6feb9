//! Oriented boxes: the sampling volumes of Sec. 5.4.1.
//!
//! A box has a centre, a full size along each of its own axes and a rotation
//! vector (axis times angle, radians) that turns the part axes onto the box
//! axes. A point p is inside when every component of R^T (p - c) lies within
//! half the size (boundary included).

use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Points handled per parallel task; large enough to amortise scheduling.
const CHUNK: usize = 16 * 1024;

#[derive(Debug, Clone, PartialEq)]
pub struct OrientedBox {
    pub center: [f64; 3],
    pub size: [f64; 3],
    /// Rotation vector (axis * angle, rad) of the box axes in the cloud frame.
    pub rotation: [f64; 3],
}

pub use gagekit_core::rotation_from_vector as rotation_matrix;

impl OrientedBox {
    /// Validate the box: finite numbers and a positive size on every axis.
    pub fn validate(&self, name: &str) -> Result<()> {
        for (what, v) in [("center", &self.center), ("size", &self.size), ("rotation", &self.rotation)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(GkError::config(format!("region '{name}': {what} must be finite, got {v:?}")));
            }
        }
        if let Some(axis) = self.size.iter().position(|&s| s <= 0.0) {
            return Err(GkError::config(format!(
                "region '{name}': size along its {} axis is {} but must be positive",
                ["x", "y", "z"][axis],
                self.size[axis]
            )));
        }
        Ok(())
    }

    /// Half the extent of the box along each cloud axis: sum over k of |R_ik| size_k / 2.
    pub fn half_extents(&self) -> [f64; 3] {
        let r = rotation_matrix(self.rotation);
        let half = [self.size[0] / 2.0, self.size[1] / 2.0, self.size[2] / 2.0];
        std::array::from_fn(|i| (0..3).map(|k| r[i][k].abs() * half[k]).sum())
    }

    /// The axis-aligned bounding box (cloud frame) of the box, widened by a relative
    /// 1e-9 so that rounding never puts a point of the box outside it.
    pub fn aabb(&self) -> ([f64; 3], [f64; 3]) {
        let ext = self.half_extents();
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for i in 0..3 {
            let e = ext[i];
            let pad = 1e-9 * (e + self.center[i].abs()) + f64::MIN_POSITIVE;
            lo[i] = self.center[i] - e - pad;
            hi[i] = self.center[i] + e + pad;
        }
        (lo, hi)
    }

    /// A membership test with the rotation precomputed. Points outside the box's
    /// axis-aligned bounding box are rejected by three comparisons (most points of a
    /// scan lie outside a sampling region); the others get the exact test.
    pub(crate) fn tester(&self) -> impl Fn(&[f64]) -> bool + Sync + '_ {
        let r = rotation_matrix(self.rotation);
        let half = [self.size[0] / 2.0, self.size[1] / 2.0, self.size[2] / 2.0];
        let c = self.center;
        let (lo, hi) = self.aabb();
        move |p: &[f64]| {
            // `&` (not `&&`): six comparisons without branches, then one well-predicted branch
            let near = (p[0] >= lo[0]) & (p[0] <= hi[0]) & (p[1] >= lo[1]) & (p[1] <= hi[1]) & (p[2] >= lo[2]) & (p[2] <= hi[2]);
            if !near {
                return false;
            }
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            // local = R^T d: column k of R dotted with d.
            (0..3).all(|k| {
                let l = r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2];
                l.abs() <= half[k]
            })
        }
    }
}

fn check_points(points: &[f64]) -> Result<()> {
    gagekit_core::check_finite(points, 3, "point cloud")
}

/// Indices (ascending) of the points inside `b`. `points` is row-major (n, 3).
pub fn select(points: &[f64], b: &OrientedBox) -> Result<Vec<usize>> {
    check_points(points)?;
    b.validate("region")?;
    let inside = b.tester();
    let parts: Vec<Vec<usize>> = points
        .par_chunks(3 * CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            chunk
                .chunks_exact(3)
                .enumerate()
                .filter(|(_, p)| inside(p))
                .map(|(i, _)| ci * CHUNK + i)
                .collect()
        })
        .collect();
    Ok(parts.concat())
}

/// The bin (0..n) of the coordinate `v` on bins of width 1/inv from `lo`, clamped; the
/// same monotone formula for box limits and points.
#[inline(always)]
fn bin_of(v: f64, lo: f64, inv: f64, n: usize) -> usize {
    let f = (v - lo) * inv;
    // truncation is the floor for the positive values; no libm call in the hot loop
    if f > 0.0 {
        (f as usize).min(n - 1)
    } else {
        0
    }
}

/// Whether `p` lies within [lo, hi] (six comparisons, no branch).
#[inline(always)]
fn within(p: &[f64], lo: &[f64; 3], hi: &[f64; 3]) -> bool {
    (p[0] >= lo[0]) & (p[0] <= hi[0]) & (p[1] >= lo[1]) & (p[1] <= hi[1]) & (p[2] >= lo[2]) & (p[2] <= hi[2])
}

/// The bounding box (lo, hi) of the union of axis-aligned boxes; (+inf, -inf) for none.
fn union_aabb<'a>(aabbs: impl IntoIterator<Item = &'a ([f64; 3], [f64; 3])>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (l, h) in aabbs {
        for i in 0..3 {
            lo[i] = lo[i].min(l[i]);
            hi[i] = hi[i].max(h[i]);
        }
    }
    (lo, hi)
}

/// The boxes' bounding boxes binned on a coarse x-y grid over their union: a point
/// is tested only against the boxes whose bin it falls in (a few of the many regions
/// of a spec), and a point outside the union against none. Bins are found with the
/// same monotone formula for box limits and points, so no box that holds a point is
/// ever left out.
struct BoxBins {
    lo: [f64; 3],
    hi: [f64; 3],
    inv: [f64; 2],
    n: [usize; 2],
    start: Vec<usize>,
    items: Vec<usize>,
}

const BINS: usize = 32;

impl BoxBins {
    fn new(boxes: &[OrientedBox]) -> Self {
        let aabbs: Vec<_> = boxes.iter().map(|b| b.aabb()).collect();
        let (lo, hi) = union_aabb(&aabbs);
        let mut n = [1usize; 2];
        let mut inv = [0.0; 2];
        for i in 0..2 {
            let span = hi[i] - lo[i];
            if span > 0.0 && span.is_finite() {
                n[i] = BINS;
                inv[i] = BINS as f64 / span;
            }
        }
        let mut lists = vec![Vec::new(); n[0] * n[1]];
        let bins = Self { lo, hi, inv, n, start: Vec::new(), items: Vec::new() };
        for (k, (l, h)) in aabbs.iter().enumerate() {
            let (x0, y0) = (bins.bin(0, l[0]), bins.bin(1, l[1]));
            let (x1, y1) = (bins.bin(0, h[0]), bins.bin(1, h[1]));
            for x in x0..=x1 {
                for y in y0..=y1 {
                    lists[x * n[1] + y].push(k);
                }
            }
        }
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        for l in lists {
            start.push(items.len());
            items.extend(l);
        }
        start.push(items.len());
        Self { start, items, ..bins }
    }

    #[inline]
    fn bin(&self, axis: usize, v: f64) -> usize {
        bin_of(v, self.lo[axis], self.inv[axis], self.n[axis])
    }

    /// Whether `p` is inside the union's bounding box (no box outside it can hold `p`).
    #[inline(always)]
    fn in_union(&self, p: &[f64]) -> bool {
        within(p, &self.lo, &self.hi)
    }

    /// The boxes (ascending) whose bounding boxes may hold `p`, a point inside the union's
    /// bounding box ([`BoxBins::in_union`]).
    #[inline]
    fn candidates_in_union(&self, p: &[f64]) -> &[usize] {
        let b = self.bin(0, p[0]) * self.n[1] + self.bin(1, p[1]);
        &self.items[self.start[b]..self.start[b + 1]]
    }
}


/// The boxes on a uniform 3-D grid over their union's bounding box (up to [`GRID`] cells
/// an axis, fewer for a small chunk): each cell holds two bit masks of the boxes, those
/// that surely hold every point the cell can receive, and those that may hold some (the
/// exact test decides). A point costs one cell lookup and the exact tests of the few
/// boxes whose faces cross its cell; the many cells inside no box cost nothing more.
/// Membership is the exact test's: a cell is "sure" for a box only when the cell, widened
/// by far more than the rounding of a point's cell index, lies inside the box by a margin
/// far above the rounding of the exact test; "maybe" is a conservative overlap (the
/// separating axes of the box and of the cell), widened the same way.
struct BoxGrid {
    lo: [f64; 3],
    hi: [f64; 3],
    inv: [f64; 3],
    n: [usize; 3],
    /// (sure, maybe) masks, cell (x, y, z) at (x n_y + y) n_z + z.
    cells: Vec<(u32, u32)>,
}

/// Most cells of the grid along an axis.
const GRID: usize = 64;

/// Most boxes a [`BoxGrid`] holds (the bits of its masks).
const GRID_BOXES: usize = 32;

impl BoxGrid {
    fn new(boxes: &[OrientedBox], npts: usize) -> Self {
        assert!(boxes.len() <= GRID_BOXES);
        let (lo, hi) = union_aabb(&boxes.iter().map(|b| b.aabb()).collect::<Vec<_>>());
        // about 8 points a cell at least: the grid's build stays below the chunk's cost
        let per_axis = ((npts / 8) as f64).cbrt().floor().clamp(1.0, GRID as f64) as usize;
        let mut n = [1usize; 3];
        let mut inv = [0.0; 3];
        let mut width = [0.0; 3];
        for i in 0..3 {
            let span = hi[i] - lo[i];
            width[i] = span;
            if span > 0.0 && span.is_finite() {
                n[i] = per_axis;
                inv[i] = per_axis as f64 / span;
                width[i] = span / per_axis as f64;
            }
        }
        let frames: Vec<_> = boxes
            .iter()
            .map(|b| (rotation_matrix(b.rotation), [b.size[0] / 2.0, b.size[1] / 2.0, b.size[2] / 2.0], b.center, b.aabb()))
            .collect();
        let mut cells = vec![(0u32, 0u32); n[0] * n[1] * n[2]];
        for x in 0..n[0] {
            for y in 0..n[1] {
                for z in 0..n[2] {
                    let ix = [x, y, z];
                    // the cell widened by 1e-6 of its width and 1e-9 of its coordinates
                    let mut clo = [0.0; 3];
                    let mut chi = [0.0; 3];
                    for i in 0..3 {
                        let a = lo[i] + ix[i] as f64 * width[i];
                        let b = if ix[i] + 1 == n[i] { hi[i] } else { lo[i] + (ix[i] + 1) as f64 * width[i] };
                        let pad = 1e-6 * width[i] + 1e-9 * (a.abs() + b.abs()) + f64::MIN_POSITIVE;
                        clo[i] = a - pad;
                        chi[i] = b + pad;
                    }
                    let m: [f64; 3] = std::array::from_fn(|i| 0.5 * (clo[i] + chi[i]));
                    let h: [f64; 3] = std::array::from_fn(|i| 0.5 * (chi[i] - clo[i]));
                    let (mut sure, mut maybe) = (0u32, 0u32);
                    for (k, (r, half, c, (blo, bhi))) in frames.iter().enumerate() {
                        if (0..3).any(|i| chi[i] < blo[i] || clo[i] > bhi[i]) {
                            continue;
                        }
                        let d = [m[0] - c[0], m[1] - c[1], m[2] - c[2]];
                        let scale = d[0].abs() + d[1].abs() + d[2].abs() + h[0] + h[1] + h[2];
                        let mut inside = true;
                        let mut apart = false;
                        for a in 0..3 {
                            let l = r[0][a] * d[0] + r[1][a] * d[1] + r[2][a] * d[2];
                            let e = r[0][a].abs() * h[0] + r[1][a].abs() * h[1] + r[2][a].abs() * h[2];
                            let margin = 1e-9 * (scale + half[a]) + f64::MIN_POSITIVE;
                            apart |= l.abs() - e > half[a] + margin;
                            inside &= l.abs() + e < half[a] - margin;
                        }
                        if inside {
                            sure |= 1 << k;
                        } else if !apart {
                            maybe |= 1 << k;
                        }
                    }
                    cells[(x * n[1] + y) * n[2] + z] = (sure, maybe);
                }
            }
        }
        Self { lo, hi, inv, n, cells }
    }

    #[inline(always)]
    fn bin(&self, axis: usize, v: f64) -> usize {
        bin_of(v, self.lo[axis], self.inv[axis], self.n[axis])
    }

    /// Whether `p` is inside the union's bounding box (no box outside it can hold `p`).
    #[inline(always)]
    fn in_union(&self, p: &[f64]) -> bool {
        within(p, &self.lo, &self.hi)
    }

    /// The (sure, maybe) masks of the cell of `p`, a point inside the union's bounding box.
    #[inline(always)]
    fn masks(&self, p: &[f64]) -> (u32, u32) {
        let c = (self.bin(0, p[0]) * self.n[1] + self.bin(1, p[1])) * self.n[2] + self.bin(2, p[2]);
        self.cells[c]
    }
}

/// For each box, the ascending indices of the points inside it. A point may
/// fall in several boxes. One parallel pass over the points.
pub fn classify(points: &[f64], boxes: &[OrientedBox]) -> Result<Vec<Vec<usize>>> {
    check_points(points)?;
    for (i, b) in boxes.iter().enumerate() {
        b.validate(&format!("#{i}"))?;
    }
    if boxes.len() > GRID_BOXES {
        return Ok(classify_binned(points, boxes));
    }
    let nb = boxes.len();
    if nb == 0 {
        return Ok(Vec::new());
    }
    let testers: Vec<_> = boxes.iter().map(|b| b.tester()).collect();
    let grid = BoxGrid::new(boxes, points.len() / 3);
    Ok(classify_near(points, nb, |p| grid.in_union(p), |p, i, out| {
        let (mut sure, mut maybe) = grid.masks(p);
        while maybe != 0 {
            let k = maybe.trailing_zeros() as usize;
            maybe &= maybe - 1;
            if testers[k](p) {
                sure |= 1 << k;
            }
        }
        while sure != 0 {
            let k = sure.trailing_zeros() as usize;
            sure &= sure - 1;
            out[k].push(i);
        }
    }))
}

/// The points of each box, in order: `visit(p, i, out)` pushes i onto the lists of the
/// boxes that hold the point p (number i), a point inside the union's bounding box
/// (`in_union`). One parallel pass; whether each point is inside the union first (six
/// comparisons, no branch: most points of a scan are outside), then eight points at a
/// time skipped where none is.
fn classify_near<U, V>(points: &[f64], nb: usize, in_union: U, visit: V) -> Vec<Vec<usize>>
where
    U: Fn(&[f64]) -> bool + Sync,
    V: Fn(&[f64], usize, &mut [Vec<usize>]) + Sync,
{
    let parts: Vec<Vec<Vec<usize>>> = points
        .par_chunks(3 * CHUNK)
        .enumerate()
        .map_init(Vec::new, |near: &mut Vec<u8>, (ci, chunk)| {
            let mut out = vec![Vec::new(); nb];
            let npts = chunk.len() / 3;
            near.clear();
            near.extend(chunk.chunks_exact(3).map(|p| u8::from(in_union(p))));
            near.resize(npts.div_ceil(8) * 8, 0);
            for (w, word) in near.chunks_exact(8).enumerate() {
                if u64::from_ne_bytes(word.try_into().unwrap()) == 0 {
                    continue;
                }
                for (j, &b) in word.iter().enumerate() {
                    if b != 0 {
                        let i = 8 * w + j;
                        visit(&chunk[3 * i..3 * i + 3], ci * CHUNK + i, &mut out);
                    }
                }
            }
            out
        })
        .collect();
    merge_parts(parts, nb)
}

fn merge_parts(parts: Vec<Vec<Vec<usize>>>, nb: usize) -> Vec<Vec<usize>> {
    let mut result = vec![Vec::new(); nb];
    for part in parts {
        for (k, v) in part.into_iter().enumerate() {
            result[k].extend(v);
        }
    }
    result
}

/// [`classify`] by the x-y bins of [`BoxBins`] (validated input): for more boxes than a
/// [`BoxGrid`] holds.
fn classify_binned(points: &[f64], boxes: &[OrientedBox]) -> Vec<Vec<usize>> {
    let nb = boxes.len();
    let testers: Vec<_> = boxes.iter().map(|b| b.tester()).collect();
    let bins = BoxBins::new(boxes);
    classify_near(points, nb, |p| bins.in_union(p), |p, i, out| {
        for &k in bins.candidates_in_union(p) {
            if testers[k](p) {
                out[k].push(i);
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<f64> {
        let mut pts = Vec::new();
        for i in -10..=10 {
            for j in -10..=10 {
                for k in -10..=10 {
                    pts.extend([i as f64, j as f64, k as f64]);
                }
            }
        }
        pts
    }

    #[test]
    fn axis_aligned_box_counts_boundary() {
        let pts = grid();
        let b = OrientedBox { center: [0.0; 3], size: [4.0, 2.0, 0.5], rotation: [0.0; 3] };
        let idx = select(&pts, &b).unwrap();
        assert_eq!(idx.len(), 5 * 3 * 1);
        for &i in &idx {
            let p = &pts[3 * i..3 * i + 3];
            assert!(p[0].abs() <= 2.0 && p[1].abs() <= 1.0 && p[2] == 0.0);
        }
    }

    #[test]
    fn rotated_box_by_quarter_turn_swaps_axes() {
        let pts = grid();
        let rot = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        let a = OrientedBox { center: [1.0, 2.0, 0.0], size: [6.1, 2.1, 1.0], rotation: rot };
        let b = OrientedBox { center: [1.0, 2.0, 0.0], size: [2.1, 6.1, 1.0], rotation: [0.0; 3] };
        assert_eq!(select(&pts, &a).unwrap(), select(&pts, &b).unwrap());
    }

    #[test]
    fn classify_matches_select() {
        let pts = grid();
        let boxes = vec![
            OrientedBox { center: [0.0; 3], size: [3.0; 3], rotation: [0.1, 0.2, 0.3] },
            OrientedBox { center: [5.0, 5.0, 5.0], size: [4.0, 1.0, 9.0], rotation: [0.0; 3] },
        ];
        let all = classify(&pts, &boxes).unwrap();
        for (b, got) in boxes.iter().zip(all) {
            assert_eq!(select(&pts, b).unwrap(), got);
        }
    }

    #[test]
    fn bounding_box_prefilter_changes_no_answer() {
        // points on and just beside the faces of rotated boxes: the prefiltered test
        // must agree with the plain one (R^T (p - c) within half the size) everywhere
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        };
        for _ in 0..200 {
            let b = OrientedBox {
                center: [100.0 * rnd(), 100.0 * rnd(), 1e3 * rnd()],
                size: [1.0 + 5.0 * rnd().abs(), 0.1 + rnd().abs(), 2.0 + rnd().abs()],
                rotation: [3.0 * rnd(), 3.0 * rnd(), 3.0 * rnd()],
            };
            let r = rotation_matrix(b.rotation);
            let t = b.tester();
            for _ in 0..500 {
                // a point given in box coordinates, near a face or a corner
                let mut l = [0.0; 3];
                for k in 0..3 {
                    let h = b.size[k] / 2.0;
                    l[k] = if rnd() > 0.0 { h * rnd().signum() * (1.0 + 1e-12 * rnd()) } else { h * rnd() };
                }
                let p: Vec<f64> = (0..3).map(|i| b.center[i] + (0..3).map(|k| r[i][k] * l[k]).sum::<f64>()).collect();
                let d = [p[0] - b.center[0], p[1] - b.center[1], p[2] - b.center[2]];
                let plain = (0..3).all(|k| (r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2]).abs() <= b.size[k] / 2.0);
                assert_eq!(t(&p), plain, "{b:?} {p:?}");
            }
        }
    }

    #[test]
    fn binned_classify_matches_select_for_many_boxes() {
        let mut seed = 99u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64)
        };
        let mut pts = Vec::new();
        for _ in 0..20_000 {
            // on a lattice, so many points sit exactly on box faces and bin edges
            pts.extend([(40.0 * rnd()).round() / 4.0, (40.0 * rnd()).round() / 4.0, (8.0 * rnd()).round() / 4.0]);
        }
        let mut boxes: Vec<OrientedBox> = (0..25)
            .map(|_| OrientedBox {
                center: [(10.0 * rnd() * 4.0).round() / 4.0, (10.0 * rnd() * 4.0).round() / 4.0, 1.0],
                size: [(8.0 * rnd()).round() / 2.0 + 0.5, (8.0 * rnd()).round() / 2.0 + 0.5, 2.0],
                rotation: if rnd() < 0.5 { [0.0; 3] } else { [0.0, 0.0, rnd()] },
            })
            .collect();
        boxes.push(OrientedBox { center: [5.0, 5.0, 1.0], size: [0.5, 0.5, 0.5], rotation: [0.0; 3] });
        let all = classify(&pts, &boxes).unwrap();
        for (b, got) in boxes.iter().zip(&all) {
            assert_eq!(&select(&pts, b).unwrap(), got);
        }
        assert!(all.iter().map(|v| v.len()).sum::<usize>() > 1000);
        assert!(classify(&pts, &[]).unwrap().is_empty());
    }

    #[test]
    fn bad_input_is_an_error() {
        let b = OrientedBox { center: [0.0; 3], size: [1.0, 0.0, 1.0], rotation: [0.0; 3] };
        let e = select(&[0.0; 3], &b).unwrap_err();
        assert!(e.message.contains("y axis"), "{}", e.message);
        let good = OrientedBox { center: [0.0; 3], size: [1.0; 3], rotation: [0.0; 3] };
        assert!(select(&[0.0, f64::NAN, 0.0], &good).is_err());
        assert!(select(&[], &good).unwrap().is_empty());
    }

    #[test]
    fn rodrigues_is_orthonormal() {
        let r = rotation_matrix([0.3, -0.2, 0.9]);
        for i in 0..3 {
            for j in 0..3 {
                let d: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }
}

#[cfg(test)]
mod grid_props {
    use super::*;
    use proptest::prelude::*;

    /// The plain membership test: R^T (p - c) within half the size on every axis.
    fn plain(b: &OrientedBox, p: &[f64]) -> bool {
        let r = rotation_matrix(b.rotation);
        let d = [p[0] - b.center[0], p[1] - b.center[1], p[2] - b.center[2]];
        (0..3).all(|k| (r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2]).abs() <= b.size[k] / 2.0)
    }

    fn a_box() -> impl Strategy<Value = OrientedBox> {
        (
            prop::array::uniform3(-5i32..6),
            prop::array::uniform3(1i32..12),
            prop::array::uniform3(-30i32..31),
            0u8..3,
        )
            .prop_map(|(c, s, r, kind)| OrientedBox {
                center: c.map(|v| v as f64 * 0.5),
                size: s.map(|v| v as f64 * 0.5),
                // axis-aligned (faces on the points' lattice), turned about z, or any turn
                rotation: match kind {
                    0 => [0.0; 3],
                    1 => [0.0, 0.0, r[2] as f64 * 0.05],
                    _ => r.map(|v| v as f64 * 0.05),
                },
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
        /// The grid's classification (sure cells, exact tests where faces cross a cell)
        /// gives every box exactly the points of the plain test, also for points on the
        /// faces, on cell edges and just beside them, and for the x-y binned path.
        #[test]
        fn grid_classification_equals_the_direct_test(
            boxes in prop::collection::vec(a_box(), 1..12),
            raw in prop::collection::vec((prop::array::uniform3(-32i32..33), 0u8..4), 200..3000),
        ) {
            let mut pts = Vec::with_capacity(3 * raw.len());
            for (q, nudge) in &raw {
                let e = match nudge { 0 => 0.0, 1 => 1e-13, 2 => -1e-13, _ => 0.37 };
                pts.extend(q.map(|v| v as f64 * 0.25 + e));
            }
            let got = classify(&pts, &boxes).unwrap();
            let binned = classify_binned(&pts, &boxes);
            for (k, b) in boxes.iter().enumerate() {
                let want: Vec<usize> = pts.chunks_exact(3).enumerate().filter(|(_, p)| plain(b, p)).map(|(i, _)| i).collect();
                prop_assert_eq!(&got[k], &want, "box {}", k);
                prop_assert_eq!(&binned[k], &want, "binned, box {}", k);
            }
        }
    }
}
