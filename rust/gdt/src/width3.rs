//! Widths of a 3-D point set between two parallel planes whose orientation is
//! constrained as ISO 1101 constrains an orientation zone:
//!
//! - [`along`]: normal fixed (parallelism of a plane to a datum plane, perpendicularity
//!   of a plane to a datum axis, any zone fully oriented by its datums);
//! - [`perpendicular_to`]: normal perpendicular to a datum direction, free to turn about
//!   it (perpendicularity of a plane to a datum plane, parallelism of a plane to a
//!   datum axis): the minimum width of the set projected along the datum direction
//!   ([`crate::width2`]), exact;
//! - [`on_cone`]: normal at a fixed angle to a datum direction, free to turn about it
//!   (angularity of a plane to one datum plane).

use crate::vec3::{self, check_points, dot, V3};
use crate::width2;
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// A slab of two parallel planes with unit `normal` at `normal . p = lo` and `= hi`.
#[derive(Debug, Clone, PartialEq)]
pub struct Slab {
    pub normal: V3,
    pub lo: f64,
    pub hi: f64,
    pub width: f64,
}

/// The smallest and largest `normal . p` over the points (normal need not be unit).
pub fn extent(pts: &[f64], normal: V3) -> (f64, f64) {
    pts.par_chunks_exact(3)
        .map(|p| {
            let d = normal[0] * p[0] + normal[1] * p[1] + normal[2] * p[2];
            (d, d)
        })
        .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The slab of fixed unit normal (the normalised `normal`) that encloses the points.
pub fn along(pts: &[f64], normal: V3) -> Result<Slab> {
    check_points(pts, 1, "width along a direction")?;
    let n = vec3::unit(normal, "width along a direction")?;
    let (lo, hi) = extent(pts, n);
    Ok(Slab { normal: n, lo, hi, width: hi - lo })
}

/// The thinnest slab whose normal is perpendicular to `axis` (exact).
pub fn perpendicular_to(pts: &[f64], axis: V3) -> Result<Slab> {
    check_points(pts, 2, "width perpendicular to an axis")?;
    let a = vec3::unit(axis, "width perpendicular to an axis")?;
    let (q, u, v) = vec3::project(pts, a, [0.0; 3]);
    let w = width2::min_width(&q)?;
    let normal = vec3::add(vec3::scale(u, w.normal[0]), vec3::scale(v, w.normal[1]));
    // recompute in 3-D from the reported normal
    let (lo, hi) = extent(pts, normal);
    Ok(Slab { normal, lo, hi, width: hi - lo })
}

/// Grid of the first search over the turn about the axis in [`on_cone`].
const CONE_GRID: usize = 720;

/// The thinnest slab whose normal makes the angle `angle` (rad, in [0, pi/2]) with
/// `axis`, turned freely about it: n(f) = cos(angle) a + sin(angle) (cos f u + sin f v).
///
/// The width w(f) = max_i n(f).p_i - min_i n(f).p_i is a difference of upper envelopes
/// of sinusoids in f. It is evaluated on the convex-hull vertices (the extremes of a
/// linear function are attained there) over a 720-point grid; the best grid cells are
/// refined by golden-section search, and each refined turn is polished exactly: with
/// the extreme pair (i, j) fixed, w(f) = A + B cos f + C sin f has its minimum at
/// f = atan2(-C, -B), accepted when it does not widen the zone.
pub fn on_cone(pts: &[f64], axis: V3, angle: f64) -> Result<Slab> {
    const WHAT: &str = "width at an angle to an axis";
    let n = check_points(pts, 2, WHAT)?;
    let a = vec3::unit(axis, WHAT)?;
    if !(angle.is_finite() && (0.0..=std::f64::consts::FRAC_PI_2 + 1e-12).contains(&angle)) {
        return Err(GkError::invalid(format!("{WHAT}: the angle must be in [0, 90] degrees, got {} rad", angle)));
    }
    let (ca, sa) = (angle.cos(), angle.sin());
    if sa < 1e-15 {
        return along(pts, a);
    }
    let (u, v) = vec3::basis(a);
    // hull vertices (all points when few or when the hull is degenerate)
    let ids: Vec<usize> = if n > 64 {
        gagekit_geometry::convex_hull_indices(pts).unwrap_or_else(|_| (0..n).collect())
    } else {
        (0..n).collect()
    };
    let c = vec3::centroid(pts);
    // g_i(f) = ca * ha_i + sa * (cos f * hu_i + sin f * hv_i), relative to the centroid
    let coef: Vec<[f64; 3]> = ids
        .iter()
        .map(|&i| {
            let d = vec3::sub(vec3::at(pts, i), c);
            [ca * dot(d, a), sa * dot(d, u), sa * dot(d, v)]
        })
        .collect();
    let eval = |f: f64| -> (f64, usize, usize) {
        let (hi, lo) = crate::turn::extremes(&coef, f);
        (hi.0 - lo.0, hi.1, lo.1)
    };
    let step = std::f64::consts::TAU / CONE_GRID as f64;
    let grid: Vec<f64> = (0..CONE_GRID).into_par_iter().map(|k| eval(k as f64 * step).0).collect();
    // local minima of the grid (cyclic), best first, at most 4
    let mut cells: Vec<usize> = (0..CONE_GRID)
        .filter(|&k| grid[k] <= grid[(k + CONE_GRID - 1) % CONE_GRID] && grid[k] <= grid[(k + 1) % CONE_GRID])
        .collect();
    cells.sort_by(|&i, &j| grid[i].total_cmp(&grid[j]).then(i.cmp(&j)));
    cells.truncate(4);
    let mut best = (f64::INFINITY, 0.0);
    for &k in &cells {
        let (mut lo, mut hi) = ((k as f64 - 1.0) * step, (k as f64 + 1.0) * step);
        let r = 0.5 * (5f64.sqrt() - 1.0);
        let (mut x1, mut x2) = (hi - r * (hi - lo), lo + r * (hi - lo));
        let (mut f1, mut f2) = (eval(x1).0, eval(x2).0);
        for _ in 0..90 {
            if f1 <= f2 {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - r * (hi - lo);
                f1 = eval(x1).0;
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + r * (hi - lo);
                f2 = eval(x2).0;
            }
        }
        let mut f = 0.5 * (lo + hi);
        let (mut w, i, j) = eval(f);
        // exact polish with the extreme pair fixed
        let d = [coef[i][0] - coef[j][0], coef[i][1] - coef[j][1], coef[i][2] - coef[j][2]];
        if d[1] != 0.0 || d[2] != 0.0 {
            let fs = (-d[2]).atan2(-d[1]);
            let ws = eval(fs).0;
            if ws <= w {
                f = fs;
                w = ws;
            }
        }
        if w < best.0 {
            best = (w, f);
        }
    }
    let f = best.1;
    let normal = vec3::add(vec3::scale(a, ca), vec3::add(vec3::scale(u, sa * f.cos()), vec3::scale(v, sa * f.sin())));
    let (lo, hi) = extent(pts, normal);
    Ok(Slab { normal, lo, hi, width: hi - lo })
}
