//! Maximum inscribed circle of a large point set in bounded memory: the exact candidates
//! of Sec. 6.2.2 ([`super::mi::exact_in`]) computed tile by tile over the MC disk, each
//! tile from the Delaunay triangulation of only the points near it.
//!
//! Why a tile's points suffice. Let `g(c) = min(r_MC - |c - c_MC|, nn(c))` (Eq. 6.2, `nn`
//! the distance to the nearest input point) and `v >= g` an upper bound of `g` over a tile
//! (below). Take every point within `v` of the tile. For a centre `c` in the tile either
//! `nn(c) <= v`: its nearest points are all taken, so the local nearest-point Voronoi
//! diagram equals the global one around `c` and every candidate there is found with its
//! true value; or `nn(c) > v >= g_MC(c)`: then `g(c) = g_MC(c)` whatever the local diagram
//! says, and such a `c` is no optimum (moving towards `c_MC` increases `g`) unless it is
//! `c_MC` itself, whose value starts the search. So the best candidate over all tiles is
//! the global optimum, as [`super::mi::exact`] on all points would find it.
//!
//! The bound `v` per grid cell: a cell whose Chebyshev distance to the nearest non-empty
//! cell is `k` has `nn(c) <= (k + 1) s sqrt 2` (cell side `s`); and `g_MC(c) <= r_MC -
//! dist(c_MC, cell)`. Tiles are visited by decreasing bound and skipped once their bound
//! falls below the best value found, in batches of a fixed size (the same tiles are
//! skipped for any thread count: the result does not depend on it).
//!
//! Memory: the grid (two `u32` per cell, about one cell per two points), one `u32` per
//! point, and a few triangulations of some thousand points at a time, instead of the
//! triangulation of every point (40 times the input at 10^6 points).

use super::dist;
use super::mi::exact_in;
use gagekit_core::{interrupt, Result};
use rayon::prelude::*;

/// Grid cells per tile side.
const T: usize = 32;
/// Tiles solved in parallel between two updates of the lower bound (fixed, so that the
/// tiles skipped do not depend on the thread count).
const BATCH: usize = 8;

/// A tile's candidate: (value g, centre, control points as input indices).
type Best = (f64, [f64; 2], Vec<usize>);

/// Exact MI of the centred points `p` inside MC (`cmc`, `rmc`), as [`super::mi::exact`]:
/// centre, radius and control points.
pub(crate) fn exact_tiled(
    p: &[[f64; 2]],
    cmc: [f64; 2],
    rmc: f64,
    scale: f64,
) -> Result<([f64; 2], f64, Vec<usize>)> {
    let grid = Grid::new(p, cmc, rmc);
    interrupt::check()?;
    // c_MC itself: g = min(r_MC, nn(c_MC))
    let r0 = p.par_iter().with_min_len(8192).map(|q| dist(*q, cmc)).reduce(|| f64::INFINITY, f64::min);
    let mut best: Best = (r0.min(rmc), cmc, Vec::new());
    let slack = 1e-9 * scale;
    let bound = grid.cell_bounds(cmc, rmc, slack);
    let mut tiles: Vec<(f64, usize)> = (0..grid.nt * grid.nt)
        .map(|t| (grid.tile_bound(t, &bound), t))
        .filter(|&(u, _)| u > best.0)
        .collect();
    tiles.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for batch in tiles.chunks(BATCH) {
        interrupt::check()?;
        let floor = best.0;
        let found: Vec<Result<Option<Best>>> = batch
            .par_iter()
            .map(|&(u, t)| if u > floor { grid.solve_tile(p, t, u, cmc, rmc, scale, floor - slack) } else { Ok(None) })
            .collect();
        for f in found {
            if let Some(b) = f? {
                if b.0 > best.0 {
                    best = b;
                }
            }
        }
    }
    Ok((best.1, best.0, best.2))
}

/// A square grid over the MC disk's bounding square with the input points bucketed by cell.
struct Grid {
    lo: [f64; 2],
    /// Cell side.
    s: f64,
    /// Cells per side (a multiple of `T`) and tiles per side.
    g: usize,
    nt: usize,
    /// Points of cell `i`: `idx[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    idx: Vec<u32>,
}

impl Grid {
    fn new(p: &[[f64; 2]], cmc: [f64; 2], rmc: f64) -> Self {
        let n = p.len();
        let nt = ((n as f64 / 2.0).sqrt() / T as f64).ceil().clamp(1.0, 128.0) as usize;
        let g = nt * T;
        let side = 2.0 * rmc * (1.0 + 1e-12) + f64::MIN_POSITIVE;
        let lo = [cmc[0] - 0.5 * side, cmc[1] - 0.5 * side];
        let s = side / g as f64;
        let mut grid = Self { lo, s, g, nt, start: vec![0; g * g + 1], idx: vec![0; n] };
        for q in p {
            let c = grid.cell_of(*q);
            grid.start[c + 1] += 1;
        }
        for i in 0..g * g {
            grid.start[i + 1] += grid.start[i];
        }
        let mut next = grid.start.clone();
        for (i, q) in p.iter().enumerate() {
            let c = grid.cell_of(*q);
            grid.idx[next[c] as usize] = i as u32;
            next[c] += 1;
        }
        grid
    }

    fn coord(&self, x: f64, axis: usize) -> usize {
        (((x - self.lo[axis]) / self.s).floor().max(0.0) as usize).min(self.g - 1)
    }

    fn cell_of(&self, q: [f64; 2]) -> usize {
        self.coord(q[1], 1) * self.g + self.coord(q[0], 0)
    }

    /// Per cell, an upper bound of `g` (Eq. 6.2) over the cell (plus `slack`); negative for
    /// cells outside MC.
    fn cell_bounds(&self, cmc: [f64; 2], rmc: f64, slack: f64) -> Vec<f64> {
        let g = self.g;
        // Chebyshev distance (in cells) to the nearest non-empty cell, two passes
        let inf = u32::MAX / 2;
        let mut k: Vec<u32> = (0..g * g).map(|i| if self.start[i + 1] > self.start[i] { 0 } else { inf }).collect();
        for y in 0..g {
            for x in 0..g {
                let mut v = k[y * g + x];
                if x > 0 {
                    v = v.min(k[y * g + x - 1] + 1);
                }
                if y > 0 {
                    v = v.min(k[(y - 1) * g + x] + 1);
                    if x > 0 {
                        v = v.min(k[(y - 1) * g + x - 1] + 1);
                    }
                    if x + 1 < g {
                        v = v.min(k[(y - 1) * g + x + 1] + 1);
                    }
                }
                k[y * g + x] = v;
            }
        }
        for y in (0..g).rev() {
            for x in (0..g).rev() {
                let mut v = k[y * g + x];
                if x + 1 < g {
                    v = v.min(k[y * g + x + 1] + 1);
                }
                if y + 1 < g {
                    v = v.min(k[(y + 1) * g + x] + 1);
                    if x + 1 < g {
                        v = v.min(k[(y + 1) * g + x + 1] + 1);
                    }
                    if x > 0 {
                        v = v.min(k[(y + 1) * g + x - 1] + 1);
                    }
                }
                k[y * g + x] = v;
            }
        }
        let s = self.s;
        (0..g * g)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let (x, y) = (i % g, i / g);
                let (x0, y0) = (self.lo[0] + x as f64 * s, self.lo[1] + y as f64 * s);
                let dx = (x0 - cmc[0]).max(cmc[0] - (x0 + s)).max(0.0);
                let dy = (y0 - cmc[1]).max(cmc[1] - (y0 + s)).max(0.0);
                let g_mc = rmc - dx.hypot(dy);
                let nn = (k[i] as f64 + 1.0) * s * std::f64::consts::SQRT_2;
                g_mc.min(nn) + slack
            })
            .collect()
    }

    /// The cell range (x0, x1, y0, y1), end exclusive, of tile `t`.
    fn tile_cells(&self, t: usize) -> (usize, usize, usize, usize) {
        let (tx, ty) = (t % self.nt, t / self.nt);
        (tx * T, (tx + 1) * T, ty * T, (ty + 1) * T)
    }

    fn tile_bound(&self, t: usize, bound: &[f64]) -> f64 {
        let (x0, x1, y0, y1) = self.tile_cells(t);
        (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).map(|(x, y)| bound[y * self.g + x]).fold(f64::NEG_INFINITY, f64::max)
    }

    /// The best candidate with its centre in tile `t` (bound `u`), from the points within
    /// `u` of the tile (more if they are too few to triangulate); None if none beats `floor`.
    #[allow(clippy::too_many_arguments)]
    fn solve_tile(
        &self,
        p: &[[f64; 2]],
        t: usize,
        u: f64,
        cmc: [f64; 2],
        rmc: f64,
        scale: f64,
        floor: f64,
    ) -> Result<Option<Best>> {
        let (cx0, cx1, cy0, cy1) = self.tile_cells(t);
        let s = self.s;
        let rect = [
            self.lo[0] + cx0 as f64 * s,
            self.lo[0] + cx1 as f64 * s,
            self.lo[1] + cy0 as f64 * s,
            self.lo[1] + cy1 as f64 * s,
        ];
        let inside = |c: [f64; 2]| c[0] >= rect[0] && c[0] < rect[1] && c[1] >= rect[2] && c[1] < rect[3];
        let mut margin = u;
        loop {
            let m = (margin / s).ceil() as usize + 1;
            let (x0, x1) = (cx0.saturating_sub(m), (cx1 + m).min(self.g));
            let (y0, y1) = (cy0.saturating_sub(m), (cy1 + m).min(self.g));
            let mut ids: Vec<u32> = Vec::new();
            for y in y0..y1 {
                let (a, b) = (self.start[y * self.g + x0] as usize, self.start[y * self.g + x1] as usize);
                ids.extend(self.idx[a..b].iter().copied().filter(|&i| {
                    let q = p[i as usize];
                    let dx = (rect[0] - q[0]).max(q[0] - rect[1]).max(0.0);
                    let dy = (rect[2] - q[1]).max(q[1] - rect[3]).max(0.0);
                    dx.hypot(dy) <= margin
                }));
            }
            let whole = x0 == 0 && y0 == 0 && x1 == self.g && y1 == self.g;
            if ids.len() >= 3 || whole {
                let q: Vec<[f64; 2]> = ids.iter().map(|&i| p[i as usize]).collect();
                match exact_in(&q, cmc, rmc, scale, floor, &inside) {
                    Ok((c, r, ctrl)) => {
                        if ctrl.is_empty() || !(r > floor) {
                            return Ok(None);
                        }
                        return Ok(Some((r, c, ctrl.into_iter().map(|k| ids[k] as usize).collect())));
                    }
                    // collinear or coincident near the tile: widen (the whole set is not)
                    Err(e) if whole => return Err(e),
                    Err(_) => {}
                }
            }
            margin = 2.0 * margin.max(s);
        }
    }
}
