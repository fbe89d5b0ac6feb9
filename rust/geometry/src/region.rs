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
    /// One bit a cell, set where either mask is not empty: 32 KiB for 64^3 cells, which
    /// stay in the core's cache while the 2 MiB of masks do not. Always [`OCCUPIED`]
    /// words (the most cells a grid has), so that a cell's word is found without a
    /// bounds check, in a vectorised loop.
    occupied: Box<[u64; OCCUPIED]>,
    /// n_i - 1 as a float: a point's bin is its scaled coordinate clamped to [0, n_i - 1].
    last: [f64; 3],
}

/// Most cells of the grid along an axis.
const GRID: usize = 64;

/// Words of [`BoxGrid::occupied`]: one bit for each of the most cells a grid has.
const OCCUPIED: usize = GRID * GRID * GRID / 64;

/// Most boxes a [`BoxGrid`] holds (the bits of its masks).
const GRID_BOXES: usize = 32;

/// The cells a [`BoxGrid`] has along an axis for a call on `npts` points: about 8 points
/// a cell at least, so that building the grid costs less than the call.
fn cells_per_axis(npts: usize) -> usize {
    ((npts / 8) as f64).cbrt().floor().clamp(1.0, GRID as f64) as usize
}

/// The grid of the last [`classify`] call: its boxes (bit patterns) and cells an axis.
type GridKey = (Vec<[u64; 9]>, usize);

static LAST_GRID: std::sync::Mutex<Option<(GridKey, std::sync::Arc<BoxGrid>)>> = std::sync::Mutex::new(None);

impl BoxGrid {
    /// The grid of `boxes` with `per_axis` cells an axis ([`cells_per_axis`]), built once
    /// for the calls of a streamed pass: a pass classifies chunk after chunk into the same
    /// boxes, and each chunk of the same size gets the grid the last one built (the same
    /// boxes to the bit and the same cells, hence the same grid).
    fn shared(boxes: &[OrientedBox], per_axis: usize) -> std::sync::Arc<BoxGrid> {
        let key: GridKey = (
            boxes.iter().map(|b| std::array::from_fn(|i| [b.center, b.size, b.rotation][i / 3][i % 3].to_bits())).collect(),
            per_axis,
        );
        let last = LAST_GRID.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, grid)) = last.as_ref().filter(|(k, _)| *k == key) {
            return grid.clone();
        }
        drop(last); // another thread's call need not wait for this build
        let grid = std::sync::Arc::new(BoxGrid::new(boxes, per_axis));
        *LAST_GRID.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, grid.clone()));
        grid
    }

    fn new(boxes: &[OrientedBox], per_axis: usize) -> Self {
        assert!(boxes.len() <= GRID_BOXES);
        let (lo, hi) = union_aabb(&boxes.iter().map(|b| b.aabb()).collect::<Vec<_>>());
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
        let mut occupied = Box::new([0u64; OCCUPIED]);
        for (c, &(sure, maybe)) in cells.iter().enumerate() {
            occupied[c / 64] |= u64::from(sure | maybe != 0) << (c % 64);
        }
        let last = n.map(|k| (k - 1) as f64);
        Self { lo, hi, inv, n, cells, occupied, last }
    }

    /// The cell number of `p`, a point inside the union's bounding box (the plain form of
    /// [`BoxGrid::codes`]' cells, for the tests). The bin along each axis is [`bin_of`]'s: the scaled
    /// coordinate clamped to [0, n - 1] then truncated is min(floor(f), n - 1) for f > 0
    /// and 0 otherwise.
    #[cfg(test)]
    fn cell_of(&self, p: &[f64]) -> u32 {
        let b: [u32; 3] = std::array::from_fn(|i| ((p[i] - self.lo[i]) * self.inv[i]).max(0.0).min(self.last[i]) as u32);
        (b[0] * self.n[1] as u32 + b[1]) * self.n[2] as u32 + b[2]
    }

    /// Whether the cell `c` has a box in a mask.
    #[inline(always)]
    fn is_occupied(&self, c: u32) -> bool {
        // c < GRID^3, so the word's index is below OCCUPIED (the mask only tells the compiler)
        (self.occupied[(c as usize / 64) & (OCCUPIED - 1)] >> (c % 64)) & 1 != 0
    }

    /// The first step of a [`classify_grid`] block: for each point of `block` (row-major,
    /// `codes.len()` points), its cell number when the point is inside the union's bounding
    /// box and its cell holds a box (`OCC`; else only inside the union, the cell's bit to be
    /// looked up after), [`NO_CELL`] otherwise; and whether every coordinate is finite.
    /// One branch-free loop, vectorised: the points' coordinates four or eight at a time in
    /// the AVX2 and AVX-512 builds ([`BoxGrid::codes`]). A point inside the union gets
    /// [`BoxGrid::cell_of`]'s cell: the same clamped scaled coordinate (its clamp written so
    /// that the conversion needs no range check).
    #[inline(always)]
    fn codes_impl<const OCC: bool>(&self, block: &[f64], codes: &mut [u32]) -> bool {
        let (lo, hi, inv, last) = (self.lo, self.hi, self.inv, self.last);
        let (n1, n2) = (self.n[1] as u32, self.n[2] as u32);
        let occupied: &[u64; OCCUPIED] = &self.occupied;
        for (code, p) in codes.iter_mut().zip(block.chunks_exact(3)) {
            let q = [p[0], p[1], p[2]];
            let inside = (q[0] >= lo[0]) & (q[0] <= hi[0]) & (q[1] >= lo[1]) & (q[1] <= hi[1]) & (q[2] >= lo[2]) & (q[2] <= hi[2]);
            let b: [u32; 3] = std::array::from_fn(|i| {
                let f = (q[i] - lo[i]) * inv[i];
                // f clamped to [0, n_i - 1] (a NaN to 0): what cell_of's max and min give for
                // any f of a point inside the union
                let f = if f > 0.0 { f } else { 0.0 };
                let f = if f < last[i] { f } else { last[i] };
                // SAFETY: f is a number in [0, n_i - 1], n_i <= GRID: it fits an i32
                unsafe { f.to_int_unchecked::<i32>() as u32 }
            });
            let cell = (b[0] * n1 + b[1]) * n2 + b[2];
            let keep = if OCC { inside & ((occupied[(cell as usize >> 6) & (OCCUPIED - 1)] >> (cell & 63)) & 1 != 0) } else { inside };
            *code = if keep { cell } else { NO_CELL };
        }
        block.iter().fold(true, |ok, v| ok & v.is_finite())
    }

    /// [`BoxGrid::codes_impl`] in the widest build this processor runs; whether the cells
    /// given are only those that hold a box (else the caller looks their bits up).
    #[inline]
    fn codes(&self, block: &[f64], codes: &mut [u32], finite: &mut bool) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl") && std::is_x86_feature_detected!("avx2") {
            // SAFETY: the features were detected on this processor
            *finite &= unsafe { self.codes_avx512(block, codes) };
            return true;
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above
            *finite &= unsafe { self.codes_avx2(block, codes) };
            return true;
        }
        *finite &= self.codes_impl::<false>(block, codes);
        false
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn codes_avx2(&self, block: &[f64], codes: &mut [u32]) -> bool {
        self.codes_impl::<true>(block, codes)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx2")]
    unsafe fn codes_avx512(&self, block: &[f64], codes: &mut [u32]) -> bool {
        self.codes_impl::<true>(block, codes)
    }

    /// Whether `p` is inside the union's bounding box (no box outside it can hold `p`).
    #[cfg(test)]
    fn in_union(&self, p: &[f64]) -> bool {
        within(p, &self.lo, &self.hi)
    }
}

/// For each box, the ascending indices of the points inside it. A point may
/// fall in several boxes. One parallel pass over the points.
pub fn classify(points: &[f64], boxes: &[OrientedBox]) -> Result<Vec<Vec<usize>>> {
    if points.len() % 3 != 0 || boxes.is_empty() || boxes.len() > GRID_BOXES {
        check_points(points)?;
    }
    for (i, b) in boxes.iter().enumerate() {
        if let Err(e) = b.validate(&format!("#{i}")) {
            check_points(points)?; // a bad point is reported first, as always
            return Err(e);
        }
    }
    if boxes.len() > GRID_BOXES {
        return Ok(classify_binned(points, boxes));
    }
    if boxes.is_empty() {
        return Ok(Vec::new());
    }
    let grid = BoxGrid::shared(boxes, cells_per_axis(points.len() / 3));
    // the points' finiteness is checked in the same pass (no pass of its own over the
    // chunk); a non-finite point is in no box, and its error is the one check_points words
    match classify_grid(points, boxes, &grid) {
        Some(inside) => Ok(inside),
        None => check_points(points).and(Err(GkError::invalid("point cloud: a non-finite coordinate".to_string()))),
    }
}

/// Points a [`classify_grid`] block handles in each of its steps.
const BLOCK: usize = 256;

/// [`classify`] on the cells of `grid` (validated input, at most [`GRID_BOXES`] boxes), a
/// block of points at a time in steps that each do one thing, without the branches and
/// the cache misses of one point's work delaying the next's: every point's cell number,
/// kept where the point is inside the union and its cell holds a box by the one-bit-a-cell
/// table (most points of a scan are in empty cells or outside the union), in one
/// branch-free vectorised loop ([`BoxGrid::codes`]); those cells' masks (the
/// loads independent of each other, so their cache misses overlap); then the exact tests
/// of the "maybe" boxes and the pushes. The same membership as a point-by-point walk.
/// `None` when a point is not finite (checked in the first step).
fn classify_grid(points: &[f64], boxes: &[OrientedBox], grid: &BoxGrid) -> Option<Vec<Vec<usize>>> {
    let nb = boxes.len();
    let testers: Vec<_> = boxes.iter().map(|b| b.tester()).collect();
    let parts: Vec<Option<Vec<Vec<usize>>>> = points
        .par_chunks(3 * CHUNK)
        .enumerate()
        .map_init(Vec::new, |last: &mut Vec<usize>, (ci, chunk)| {
            let mut finite = true;
            // each box's list sized by what this thread's last task found (a scan's
            // density changes slowly along the file): few regrowths, each a copy
            last.resize(nb, 0);
            let mut out: Vec<Vec<usize>> = last.iter().map(|&c| Vec::with_capacity(c + c / 4 + 16)).collect();
            let mut codes = [0u32; BLOCK];
            let mut cell = [0u32; BLOCK];
            let mut hit = [0u16; BLOCK];
            let mut masks = [(0u32, 0u32); BLOCK];
            for (bi, block) in chunk.chunks(3 * BLOCK).enumerate() {
                let base = ci * CHUNK + bi * BLOCK;
                let codes = &mut codes[..block.len() / 3];
                let occupied_only = grid.codes(block, codes, &mut finite);
                let mut hits = 0;
                for (j, &c) in codes.iter().enumerate() {
                    cell[hits] = c;
                    hit[hits] = j as u16;
                    hits += usize::from(c != NO_CELL && (occupied_only || grid.is_occupied(c)));
                }
                for (mk, &c) in masks.iter_mut().zip(&cell[..hits]) {
                    *mk = grid.cells[c as usize];
                }
                for (&mk, &j) in masks.iter().zip(&hit[..hits]) {
                    let j = j as usize;
                    push_members(&block[3 * j..3 * j + 3], mk, &testers, base + j, &mut out);
                }
            }
            for (c, v) in last.iter_mut().zip(&out) {
                *c = v.len();
            }
            finite.then_some(out)
        })
        .collect();
    Some(merge_parts(parts.into_iter().collect::<Option<Vec<_>>>()?, nb))
}

/// The code of a point in no cell that holds a box ([`BoxGrid::codes`]).
const NO_CELL: u32 = u32::MAX;

/// Push the point `p` (number `i`) onto the lists of the boxes of its cell's masks (sure,
/// maybe) that hold it: every sure box, and each maybe box whose exact test says so.
#[inline(always)]
fn push_members<T: Fn(&[f64]) -> bool>(p: &[f64], (mut sure, mut maybe): (u32, u32), testers: &[T], i: usize, out: &mut [Vec<usize>]) {
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
    // each list allocated once at its final size (no regrowth, no copy of what it holds)
    let mut result: Vec<Vec<usize>> = (0..nb).map(|k| Vec::with_capacity(parts.iter().map(|p| p[k].len()).sum())).collect();
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
    fn a_non_finite_point_is_the_error_of_check_points_in_every_path() {
        // the grid path checks finiteness in its own pass: the same error as the check
        // before it, wherever the point sits (first, past a block, past a task, last)
        let good = OrientedBox { center: [0.0; 3], size: [1.0; 3], rotation: [0.1, 0.0, 0.0] };
        let bad_box = OrientedBox { center: [0.0; 3], size: [1.0, -1.0, 1.0], rotation: [0.0; 3] };
        let n = CHUNK + 3 * BLOCK + 7;
        for at in [0, 1, BLOCK + 3, CHUNK + 1, n - 1] {
            for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut pts: Vec<f64> = (0..3 * n).map(|i| (i % 17) as f64 * 0.1 - 0.8).collect();
                pts[3 * at + (at % 3)] = v;
                let want = check_points(&pts).unwrap_err().message;
                for boxes in [vec![good.clone()], vec![], vec![good.clone(); GRID_BOXES + 1], vec![good.clone(), bad_box.clone()]] {
                    assert_eq!(classify(&pts, &boxes).unwrap_err().message, want, "point {at}, {v}, {} boxes", boxes.len());
                }
            }
        }
        // finite points and a bad box: the box's error
        let e = classify(&[0.0; 6], &[good, bad_box]).unwrap_err();
        assert!(e.message.contains("#1") && e.message.contains("y axis"), "{}", e.message);
        assert!(classify(&[0.0; 4], &[]).is_err());
    }

    /// Every build of a block's first step (plain, AVX2, AVX-512: those this processor
    /// runs) gives each point the cell of [`BoxGrid::cell_of`] when the point is inside the
    /// union's bounding box (and, in the builds that look the bit up, its cell holds a
    /// box), [`NO_CELL`] otherwise, and the same finiteness: for points on and beside cell
    /// edges and the union's faces, outside it, and not finite.
    #[test]
    fn every_build_of_the_cell_step_agrees() {
        let boxes = [
            OrientedBox { center: [0.0; 3], size: [3.0, 2.0, 1.0], rotation: [0.1, 0.2, 0.3] },
            OrientedBox { center: [2.0, -1.0, 0.5], size: [1.0, 4.0, 2.0], rotation: [0.0; 3] },
        ];
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            seed >> 11
        };
        for per_axis in [1, 5, GRID] {
            let grid = BoxGrid::new(&boxes, per_axis);
            let w: [f64; 3] = std::array::from_fn(|i| (grid.hi[i] - grid.lo[i]) / grid.n[i] as f64);
            let mut pts = Vec::new();
            for _ in 0..4000 {
                for i in 0..3 {
                    // a cell edge (from a little outside the union to a little past it), just
                    // beside one, a face of the union, or anywhere
                    let edge = grid.lo[i] + (rnd() % (grid.n[i] as u64 + 3)) as f64 * w[i] - w[i];
                    pts.push(match rnd() % 8 {
                        0 => edge,
                        1 => edge * (1.0 + 1e-15),
                        2 => edge - 1e-13,
                        3 => grid.lo[i],
                        4 => grid.hi[i],
                        5 => f64::from_bits(grid.hi[i].to_bits() + 1),
                        _ => grid.lo[i] - w[i] + (rnd() % 1000) as f64 * 1e-3 * (grid.hi[i] - grid.lo[i] + 2.0 * w[i]),
                    });
                }
            }
            for (at, v) in [(5, f64::NAN), (3 * 300 + 1, f64::INFINITY), (3 * 700 + 2, f64::NEG_INFINITY), (3 * 900, -0.0)] {
                pts[at] = v;
            }
            for block in pts.chunks(3 * BLOCK) {
                let k = block.len() / 3;
                let want: Vec<u32> = block.chunks_exact(3).map(|p| if grid.in_union(p) { grid.cell_of(p) } else { NO_CELL }).collect();
                let finite = block.iter().all(|v| v.is_finite());
                let occupied: Vec<u32> = want.iter().map(|&c| if c != NO_CELL && grid.is_occupied(c) { c } else { NO_CELL }).collect();
                let mut codes = vec![0u32; k];
                assert_eq!(grid.codes_impl::<false>(block, &mut codes), finite);
                assert_eq!(codes, want, "{per_axis} cells an axis, plain");
                assert_eq!(grid.codes_impl::<true>(block, &mut codes), finite);
                assert_eq!(codes, occupied, "{per_axis} cells an axis, plain with the bits");
                #[cfg(target_arch = "x86_64")]
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: the features were detected on this processor
                    assert_eq!(unsafe { grid.codes_avx2(block, &mut codes) }, finite);
                    assert_eq!(codes, occupied, "{per_axis} cells an axis, AVX2");
                    if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl") {
                        // SAFETY: as above
                        assert_eq!(unsafe { grid.codes_avx512(block, &mut codes) }, finite);
                        assert_eq!(codes, occupied, "{per_axis} cells an axis, AVX-512");
                    }
                }
            }
            let inside = pts.chunks_exact(3).filter(|p| grid.in_union(p)).count();
            assert!(inside > 250 && inside < 3800, "{per_axis} cells an axis: {inside} points inside the union");
        }
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

        /// The blocked walk of the grid over many blocks and parallel tasks (offsets past
        /// [`BLOCK`] and [`CHUNK`]), with the grid shared between calls: calls on
        /// clouds of different sizes and with other boxes in between each give every box
        /// exactly [`select`]'s points.
        #[test]
        fn blocked_classification_with_a_shared_grid_equals_select(
            sets in prop::collection::vec(prop::collection::vec(a_box(), 1..20), 2..4),
            seed in any::<u64>(),
            sizes in prop::collection::vec(1usize..40_000, 3..6),
        ) {
            let mut state = seed | 1;
            let mut lattice = move || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                // on the boxes' lattice, just beside it, or off it
                let v = ((state >> 8) % 65) as f64 * 0.25 - 8.0;
                match state % 4 { 0 => v, 1 => v + 1e-13, 2 => v - 1e-13, _ => v + 0.37 }
            };
            for (call, &n) in sizes.iter().enumerate() {
                let boxes = &sets[call % sets.len()];
                let pts: Vec<f64> = (0..3 * n).map(|_| lattice()).collect();
                let got = classify(&pts, boxes).unwrap();
                for (k, b) in boxes.iter().enumerate() {
                    prop_assert_eq!(&got[k], &select(&pts, b).unwrap(), "call {}, {} points, box {}", call, n, k);
                }
            }
        }
    }
}

#[cfg(test)]
mod timing {
    use super::*;

    fn f64s(path: &str) -> Vec<f64> {
        std::fs::read(path).unwrap().chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect()
    }

    /// The point-by-point walk of the grid (before the blocked steps), for comparison.
    fn pointwise(points: &[f64], boxes: &[OrientedBox]) -> Vec<Vec<usize>> {
        let testers: Vec<_> = boxes.iter().map(|b| b.tester()).collect();
        let grid = BoxGrid::new(boxes, cells_per_axis(points.len() / 3));
        classify_near(points, boxes.len(), |p| grid.in_union(p), |p, i, out| {
            push_members(p, grid.cells[grid.cell_of(p) as usize], &testers, i, out)
        })
    }

    /// User and system CPU seconds of this process so far (the machine may be shared).
    fn cpu() -> f64 {
        let s = std::fs::read_to_string("/proc/self/stat").unwrap();
        s.rsplit(')').next().unwrap().split_whitespace().skip(11).take(2).map(|x| x.parse::<f64>().unwrap()).sum::<f64>() / 100.0
    }

    /// Mean CPU seconds of `runs` calls of `f`, each result equal to `want`.
    fn cpu_of(runs: usize, want: &[Vec<usize>], f: impl Fn() -> Vec<Vec<usize>>) -> f64 {
        let c = cpu();
        for _ in 0..runs {
            assert_eq!(f(), want);
        }
        (cpu() - c) / runs as f64
    }

    /// CPU a point of [`classify`] on a chunk dumped by a streamed check (raw float64
    /// points and box rows: centre, size, rotation), one thread, against the
    /// point-by-point walk; runs alternated.
    #[test]
    #[ignore]
    fn classify_speed() {
        let dir = std::env::var("GK_CHUNK_DIR").unwrap_or_else(|_| "/tmp".into());
        let pts = f64s(&format!("{dir}/chunk1.f64"));
        let n = pts.len() / 3;
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        for rows in ["rows0", "rows1"] {
            let boxes: Vec<OrientedBox> = f64s(&format!("{dir}/{rows}.f64"))
                .chunks_exact(9)
                .map(|r| OrientedBox { center: [r[0], r[1], r[2]], size: [r[3], r[4], r[5]], rotation: [r[6], r[7], r[8]] })
                .collect();
            let want = pool.install(|| pointwise(&pts, &boxes));
            let (mut new, mut old) = (0.0, 0.0);
            for _ in 0..3 {
                new += pool.install(|| cpu_of(3, &want, || classify(&pts, &boxes).unwrap()));
                old += pool.install(|| cpu_of(3, &want, || pointwise(&pts, &boxes)));
            }
            let c = cpu();
            for _ in 0..5 {
                std::hint::black_box(BoxGrid::new(&boxes, cells_per_axis(n)));
            }
            let build = (cpu() - c) / 5.0;
            println!("{rows}: {} boxes, {n} points: classify {:.1} ns a point, point by point {:.1} (grid build {:.1} ms, in the point-by-point walk)",
                boxes.len(), new / 3.0 / n as f64 * 1e9, old / 3.0 / n as f64 * 1e9, build * 1e3);
            let grid = BoxGrid::new(&boxes, cells_per_axis(n));
            let (mut inu, mut hm, mut hs) = (0usize, [0usize; 8], [0usize; 8]);
            for p in pts.chunks_exact(3) {
                if grid.in_union(p) {
                    inu += 1;
                    let (s, m) = grid.cells[grid.cell_of(p) as usize];
                    hm[(m.count_ones() as usize).min(7)] += 1;
                    hs[(s.count_ones() as usize).min(7)] += 1;
                }
            }
            println!("grid {:?}, in union {inu}, maybe counts {hm:?}, sure counts {hs:?}", grid.n);
            println!("{} memberships", want.iter().map(Vec::len).sum::<usize>());
        }
    }
}
