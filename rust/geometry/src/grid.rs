//! A uniform cell grid over a point cloud, for interactive region queries.
//!
//! The sampling volumes of Sec. 5.4.1 are oriented boxes; classifying every
//! point of a 14-million-point scan against a box costs a full pass. The grid
//! sorts the point numbers once by cell (a counting sort; the points themselves
//! are not moved); a query then visits only the cells that meet the box's
//! bounding box: cells wholly inside the box are taken whole, cells wholly
//! outside are skipped (separating axes of the box), and the points of the
//! remaining cells go through the very same membership test as
//! [`crate::region::select`], so the answer is identical to a full pass.

use crate::region::OrientedBox;
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// The most cells a grid may hold (memory of the offsets array).
const MAX_CELLS: usize = 1 << 22;

/// A uniform grid of cubic cells over the bounding box of a point set. Points
/// are kept by the caller in cell order (see [`CellGrid::build`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CellGrid {
    origin: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    /// `order[starts[c]..starts[c + 1]]` are the point numbers of cell `c`, ascending.
    starts: Vec<usize>,
    order: Vec<u32>,
    /// Rounding margin for the whole-cell decisions (mm).
    margin: f64,
    /// Largest coordinate along x, y, z (the smallest is `origin`).
    upper: [f64; 3],
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum CellState {
    Outside,
    Inside,
    Partial,
}

impl CellGrid {
    /// Sort the points of `points` (row-major (n, 3)) into cells of about
    /// `per_cell` points on average. Queries must be given the same `points`.
    pub fn build(points: &[f64], per_cell: usize) -> Result<CellGrid> {
        gagekit_core::check_finite(points, 3, "point cloud")?;
        let n = points.len() / 3;
        if n == 0 {
            return Err(GkError::invalid("point cloud: no points to index"));
        }
        if n > u32::MAX as usize {
            return Err(GkError::invalid(format!("point cloud: {n} points is more than a grid indexes ({})", u32::MAX)));
        }
        let per_cell = per_cell.max(1);
        let (lo, hi) = points.par_chunks(3 * 65536).map(bounds).reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |a, b| {
                (
                    [a.0[0].min(b.0[0]), a.0[1].min(b.0[1]), a.0[2].min(b.0[2])],
                    [a.1[0].max(b.1[0]), a.1[1].max(b.1[1]), a.1[2].max(b.1[2])],
                )
            },
        );
        let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        let target = (n / per_cell).clamp(1, MAX_CELLS);
        let (cell, dims) = cell_size(ext, target);
        let ncells = dims[0] * dims[1] * dims[2];
        let grid0 = CellGrid { origin: lo, cell, dims, starts: Vec::new(), order: Vec::new(), margin: 0.0, upper: hi };
        let ids: Vec<u32> = points.par_chunks_exact(3).map(|p| grid0.cell_of(p) as u32).collect();
        let mut starts = vec![0usize; ncells + 1];
        for &c in &ids {
            starts[c as usize + 1] += 1;
        }
        for c in 0..ncells {
            starts[c + 1] += starts[c];
        }
        let mut next = starts.clone();
        let mut order = vec![0u32; n];
        for (i, &c) in ids.iter().enumerate() {
            let slot = &mut next[c as usize];
            order[*slot] = i as u32;
            *slot += 1;
        }
        let scale = lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max(v.abs())) + cell;
        let margin = 1e-9 * scale;
        Ok(CellGrid { origin: lo, cell, dims, starts, order, margin, upper: hi })
    }

    /// Number of points indexed.
    pub fn len(&self) -> usize {
        *self.starts.last().unwrap_or(&0)
    }

    /// True when no point is indexed (never, for a grid from [`CellGrid::build`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of cells along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Edge length of a cell (mm).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// The bounding box of the points: smallest and largest x, y, z.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.origin, self.upper)
    }

    fn cell_of(&self, p: &[f64]) -> usize {
        let mut idx = [0usize; 3];
        for k in 0..3 {
            let f = ((p[k] - self.origin[k]) / self.cell).floor();
            idx[k] = if f <= 0.0 { 0 } else { (f as usize).min(self.dims[k] - 1) };
        }
        (idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0]
    }

    fn check(&self, points: &[f64], b: &OrientedBox) -> Result<()> {
        if points.len() != 3 * self.len() {
            return Err(GkError::invalid(format!(
                "point grid: built for {} points, given {}",
                self.len(),
                points.len() / 3
            )));
        }
        b.validate("region")
    }

    /// Index ranges (inclusive) of the cells that meet the box's bounding box,
    /// or None when it misses the grid.
    fn cell_range(&self, b: &OrientedBox) -> Option<[(usize, usize); 3]> {
        let ext = b.half_extents();
        let mut out = [(0, 0); 3];
        for i in 0..3 {
            let e = ext[i];
            let lo = ((b.center[i] - e - self.margin - self.origin[i]) / self.cell).floor();
            let hi = ((b.center[i] + e + self.margin - self.origin[i]) / self.cell).floor();
            if hi < 0.0 || lo > (self.dims[i] - 1) as f64 {
                return None;
            }
            out[i] = (lo.max(0.0) as usize, (hi as usize).min(self.dims[i] - 1));
        }
        Some(out)
    }

    /// Whole-cell decision by the separating axes of the box (conservative:
    /// anything within the rounding margin is `Partial`).
    fn state(&self, b: &OrientedBox, r: &[[f64; 3]; 3], ijk: [usize; 3]) -> CellState {
        let h = self.cell / 2.0;
        let d: Vec<f64> = (0..3).map(|i| self.origin[i] + (ijk[i] as f64 + 0.5) * self.cell - b.center[i]).collect();
        let mut inside = true;
        #[allow(clippy::needless_range_loop)]
        for k in 0..3 {
            let local = r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2];
            let reach = h * (r[0][k].abs() + r[1][k].abs() + r[2][k].abs());
            let half = b.size[k] / 2.0;
            if local.abs() - reach > half + self.margin {
                return CellState::Outside;
            }
            if local.abs() + reach > half - self.margin {
                inside = false;
            }
        }
        if inside {
            CellState::Inside
        } else {
            CellState::Partial
        }
    }

    #[allow(clippy::too_many_arguments)]
    /// Walk the cells of one z slab, handing the point numbers of whole inside
    /// cells to `whole` and those of partial cells that pass the point test to `one`.
    fn slab<T>(
        &self,
        points: &[f64],
        b: &OrientedBox,
        range: &[(usize, usize); 3],
        iz: usize,
        acc: &mut T,
        whole: impl Fn(&mut T, &[u32]),
        one: impl Fn(&mut T, u32),
    ) {
        let r = crate::region::rotation_matrix(b.rotation);
        let inside = b.tester();
        for iy in range[1].0..=range[1].1 {
            for ix in range[0].0..=range[0].1 {
                let c = (iz * self.dims[1] + iy) * self.dims[0] + ix;
                let ids = &self.order[self.starts[c]..self.starts[c + 1]];
                if ids.is_empty() {
                    continue;
                }
                match self.state(b, &r, [ix, iy, iz]) {
                    CellState::Outside => {}
                    CellState::Inside => whole(acc, ids),
                    CellState::Partial => {
                        for &i in ids {
                            let i3 = 3 * i as usize;
                            if inside(&points[i3..i3 + 3]) {
                                one(acc, i);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Ascending indices of the points inside `b`: what [`crate::region::select`]
    /// finds on the same `points` (the ones the grid was built on).
    pub fn select(&self, points: &[f64], b: &OrientedBox) -> Result<Vec<usize>> {
        self.check(points, b)?;
        let Some(range) = self.cell_range(b) else { return Ok(Vec::new()) };
        let parts: Vec<Vec<usize>> = (range[2].0..=range[2].1)
            .into_par_iter()
            .map(|iz| {
                let mut v = Vec::new();
                self.slab(
                    points,
                    b,
                    &range,
                    iz,
                    &mut v,
                    |v, ids| v.extend(ids.iter().map(|&i| i as usize)),
                    |v, i| v.push(i as usize),
                );
                v
            })
            .collect();
        let mut out = parts.concat();
        out.par_sort_unstable();
        Ok(out)
    }

    /// Number of points inside `b` (the length of [`CellGrid::select`]).
    pub fn count(&self, points: &[f64], b: &OrientedBox) -> Result<usize> {
        self.check(points, b)?;
        let Some(range) = self.cell_range(b) else { return Ok(0) };
        Ok((range[2].0..=range[2].1)
            .into_par_iter()
            .map(|iz| {
                let mut n = 0usize;
                self.slab(points, b, &range, iz, &mut n, |n, ids| *n += ids.len(), |n, _| *n += 1);
                n
            })
            .sum())
    }
}

fn bounds(chunk: &[f64]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in chunk.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// A cubic cell size giving about `target` cells over extents `ext`, and the
/// number of cells along each axis (at least one; flat clouds stay one cell thick).
fn cell_size(ext: [f64; 3], target: usize) -> (f64, [usize; 3]) {
    let max_ext = ext.iter().fold(0.0f64, |m, &e| m.max(e));
    if max_ext <= 0.0 {
        return (1.0, [1, 1, 1]);
    }
    let dims_for = |s: f64| -> [usize; 3] {
        let mut d = [1usize; 3];
        for k in 0..3 {
            d[k] = ((ext[k] / s).floor() as usize + 1).clamp(1, 1 << 20);
        }
        d
    };
    let mut s = max_ext / (target as f64).cbrt();
    for _ in 0..200 {
        let d = dims_for(s);
        let cells = d[0] * d[1] * d[2];
        if cells > 2 * target || cells > MAX_CELLS {
            s *= 1.1;
        } else if 2 * cells < target && s > max_ext * 1e-9 {
            s /= 1.1;
        } else {
            break;
        }
    }
    let d = dims_for(s);
    if d[0] * d[1] * d[2] > MAX_CELLS {
        // extremely elongated clouds: fall back to a coarser grid
        let s = max_ext / (MAX_CELLS as f64).cbrt() * 2.0;
        return (s, dims_for(s));
    }
    (s, d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::region::select;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cloud(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..3 * n).map(|i| rng.random_range(-50.0..50.0) * if i % 3 == 2 { 0.2 } else { 1.0 }).collect()
    }

    #[test]
    fn order_is_a_permutation_and_cells_hold_their_points() {
        let pts = cloud(5000, 1);
        let g = CellGrid::build(&pts, 16).unwrap();
        let mut seen = g.order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..5000).collect::<Vec<_>>());
        assert_eq!(g.len(), 5000);
        let (lo, hi) = g.bounds();
        for k in 0..3 {
            let col = pts.iter().skip(k).step_by(3);
            assert_eq!(lo[k], col.clone().fold(f64::INFINITY, |m, &v| m.min(v)));
            assert_eq!(hi[k], col.fold(f64::NEG_INFINITY, |m, &v| m.max(v)));
        }
        for c in 0..g.starts.len() - 1 {
            let ids = &g.order[g.starts[c]..g.starts[c + 1]];
            assert!(ids.windows(2).all(|w| w[0] < w[1]));
            for &i in ids {
                assert_eq!(g.cell_of(&pts[3 * i as usize..3 * i as usize + 3]), c);
            }
        }
    }

    #[test]
    fn queries_match_a_full_pass_for_random_boxes() {
        let pts = cloud(20000, 2);
        let g = CellGrid::build(&pts, 8).unwrap();
        let s = pts;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..300 {
            let b = OrientedBox {
                center: [rng.random_range(-70.0..70.0), rng.random_range(-70.0..70.0), rng.random_range(-15.0..15.0)],
                size: [rng.random_range(0.1..120.0), rng.random_range(0.1..60.0), rng.random_range(0.1..30.0)],
                rotation: [rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)],
            };
            let want = select(&s, &b).unwrap();
            assert_eq!(g.select(&s, &b).unwrap(), want);
            assert_eq!(g.count(&s, &b).unwrap(), want.len());
        }
    }

    #[test]
    fn points_on_the_box_boundary_and_on_cell_borders_are_kept() {
        // an integer lattice: many points lie exactly on box faces and cell borders
        let mut pts = Vec::new();
        for i in -10..=10 {
            for j in -10..=10 {
                for k in -3..=3 {
                    pts.extend([i as f64, j as f64, k as f64]);
                }
            }
        }
        let g = CellGrid::build(&pts, 4).unwrap();
        let s = pts;
        for (c, sz) in [([0.0, 0.0, 0.0], [4.0, 6.0, 2.0]), ([10.0, 10.0, 3.0], [2.0, 2.0, 2.0]), ([0.5, 0.0, 0.0], [21.0, 20.0, 6.0])] {
            let b = OrientedBox { center: c, size: sz, rotation: [0.0; 3] };
            assert_eq!(g.select(&s, &b).unwrap(), select(&s, &b).unwrap());
        }
    }

    #[test]
    fn degenerate_clouds_and_bad_input() {
        let pts = vec![1.0, 2.0, 3.0, 1.0, 2.0, 3.0];
        let g = CellGrid::build(&pts, 1).unwrap();
        assert_eq!(g.dims(), [1, 1, 1]);
        let b = OrientedBox { center: [1.0, 2.0, 3.0], size: [1e-9; 3], rotation: [0.0; 3] };
        assert_eq!(g.count(&pts, &b).unwrap(), 2);
        let flat: Vec<f64> = (0..300).flat_map(|i| [i as f64, (i % 7) as f64, 0.0]).collect();
        let g = CellGrid::build(&flat, 4).unwrap();
        assert_eq!(g.dims()[2], 1);
        assert!(CellGrid::build(&[], 4).is_err());
        assert!(CellGrid::build(&[0.0, f64::NAN, 0.0], 4).is_err());
        let bad = OrientedBox { center: [0.0; 3], size: [0.0, 1.0, 1.0], rotation: [0.0; 3] };
        assert!(g.count(&flat, &bad).is_err());
        assert!(g.count(&flat[..6], &b).is_err());
    }

    #[test]
    fn a_box_far_away_selects_nothing() {
        let pts = cloud(1000, 4);
        let g = CellGrid::build(&pts, 8).unwrap();
        let b = OrientedBox { center: [1e4, 0.0, 0.0], size: [1.0; 3], rotation: [0.0; 3] };
        assert!(g.select(&pts, &b).unwrap().is_empty());
    }
}
