//! Minimum-zone fits on an active set, exact by verification (the kernel side of
//! `gagekit.form.active`): the fit runs on the points near the two boundaries of a nearby
//! zone (within [`BAND`] of its width, and at least [`MIN_EXTREMES`] of each extreme) and
//! is verified on every point; points outside the subset's zone (beyond
//! [`LENGTH_RESOLUTION`]) join the subset and the fit runs again. A zone of a subset that
//! contains every point is the zone of every point (the full set's cannot be narrower).

use crate::datum::{self, Orientation};
use crate::vec3::{dot, V3};
use gagekit_core::Result;
use gagekit_form::circle;
use gagekit_form::criterion::FitCriterion;
use gagekit_form::sphere;

/// Points within this fraction of the zone width of either boundary start the subset
/// (0.1: on the bracket's sphere and roundness sections a trial costs 13.5 ms of CPU
/// against 19 ms with 0.2, and 0.05 gains nothing more; any value gives the same zone).
pub const BAND: f64 = 0.1;
/// ... and at least this many points of each extreme.
pub const MIN_EXTREMES: usize = 16;
/// The containment test's tolerance, mm (`gagekit._util.LENGTH_RESOLUTION_MM`).
pub const LENGTH_RESOLUTION: f64 = 1e-9;

/// The start mask of the points of distances `r` to a nearby zone's centre or plane.
pub fn band(r: &[f64]) -> Vec<bool> {
    let n = r.len();
    if n <= 2 * MIN_EXTREMES {
        return vec![true; n];
    }
    let lo = r.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = r.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let w = BAND * (hi - lo);
    let (mut n_lo, mut n_hi) = (0usize, 0usize);
    let mut sel: Vec<bool> = r
        .iter()
        .map(|&x| {
            let (a, b) = (x <= lo + w, x >= hi - w);
            n_lo += a as usize;
            n_hi += b as usize;
            a || b
        })
        .collect();
    // the MIN_EXTREMES smallest and largest (ties by index; one pass, gagekit_core::select),
    // needed only when the band holds fewer on a side (else the MIN_EXTREMES-th smallest is
    // itself within lo + w, so all of them are in already; the same mask)
    if n_lo >= MIN_EXTREMES && n_hi >= MIN_EXTREMES {
        return sel;
    }
    let (small, large) = gagekit_core::select::extremes(r, MIN_EXTREMES, MIN_EXTREMES);
    for i in small.into_iter().chain(large) {
        sel[i] = true;
    }
    sel
}

/// The fit of every point of `pts` (`dim` coordinates a point) by fitting the subset
/// `sel` and growing it (module docstring). `bounds(fit, pts)`: every point's distance and
/// the zone's (inner, outer) bound. Returns the fit and, when it was made on a proper
/// subset, the subset's point numbers in `pts` (its `k`-th point is `pts`' `map[k]`-th):
/// the indices a fit names count within the subset until [`remap`] translates them.
pub fn active_fit<F, B, T>(pts: &[f64], dim: usize, mut sel: Vec<bool>, fit: F, bounds: B) -> Result<(T, Option<Vec<usize>>)>
where
    F: Fn(&[f64]) -> Result<T>,
    B: Fn(&T, &[f64]) -> (Vec<f64>, f64, f64),
{
    loop {
        if sel.iter().all(|&s| s) {
            return Ok((fit(pts)?, None));
        }
        let sub: Vec<f64> = pts.chunks_exact(dim).zip(&sel).filter(|(_, &s)| s).flat_map(|(p, _)| p.iter().copied()).collect();
        let f = match fit(&sub) {
            Ok(f) => f,
            Err(_) => return Ok((fit(pts)?, None)), // a subset too small or degenerate for the kernel
        };
        let (r, lo, hi) = bounds(&f, pts);
        let mut grew = false;
        for (s, &x) in sel.iter_mut().zip(&r) {
            if x < lo - LENGTH_RESOLUTION || x > hi + LENGTH_RESOLUTION {
                *s = true;
                grew = true;
            }
        }
        if !grew {
            let map = sel.iter().enumerate().filter(|(_, &s)| s).map(|(i, _)| i).collect();
            return Ok((f, Some(map)));
        }
    }
}

/// Point numbers of a subset (`active_fit`'s map) translated to those of every point.
pub fn remap(indices: &mut [usize], map: &Option<Vec<usize>>) {
    if let Some(m) = map {
        for i in indices.iter_mut() {
            *i = m[*i];
        }
    }
}

/// The distances of the points to `c`: the squares of the coordinates' differences summed in
/// order (written out for 2 and 3 coordinates: the same sums as the iterator's, whose sum
/// starts from a zero that adding a square leaves exact, at about half the instructions).
fn radii(pts: &[f64], dim: usize, c: &[f64]) -> Vec<f64> {
    match (dim, c) {
        (2, &[c0, c1]) => pts
            .chunks_exact(2)
            .map(|p| {
                let (a, b) = (p[0] - c0, p[1] - c1);
                (a * a + b * b).sqrt()
            })
            .collect(),
        (3, &[c0, c1, c2]) => pts
            .chunks_exact(3)
            .map(|p| {
                let (a, b, e) = (p[0] - c0, p[1] - c1, p[2] - c2);
                (a * a + b * b + e * e).sqrt()
            })
            .collect(),
        _ => pts.chunks_exact(dim).map(|p| p.iter().zip(c).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()).collect(),
    }
}

/// The minimum-zone circle of flat (n, 2) points started near `center`: the complete fit
/// (its control points numbered in `xy`, its arc that of every point).
pub fn circle_near(xy: &[f64], center: [f64; 2]) -> Result<circle::CircleFit> {
    circle::from_zone(xy, FitCriterion::MinZone, circle_zone_near(xy, center)?)
}

/// The minimum-zone circle's zone alone (centre and radii: what a Monte Carlo trial's
/// roundness reads) of flat (n, 2) points started near `center`: [`circle_near`] without
/// the complete fit's arc of every round.
pub fn circle_zone_near(xy: &[f64], center: [f64; 2]) -> Result<circle::Zone> {
    let start = band(&radii(xy, 2, &center));
    let (mut z, map) = active_fit(xy, 2, start, circle::min_zone, |z, p| (radii(p, 2, &z.center), z.r_in, z.r_out))?;
    remap(&mut z.control_in, &map);
    remap(&mut z.control_out, &map);
    Ok(z)
}

/// The minimum-zone sphere of flat (n, 3) points started near `center`.
pub fn sphere_near(pts: &[f64], center: V3) -> Result<sphere::SphereZone> {
    let start = band(&radii(pts, 3, &center));
    let (mut z, map) = active_fit(pts, 3, start, sphere::min_zone, |f, p| (radii(p, 3, &f.center), f.r_in, f.r_out))?;
    remap(&mut z.control_in, &map);
    remap(&mut z.control_out, &map);
    Ok(z)
}

/// The thinnest slab (free orientation) of flat (n, 3) points started near `normal`.
pub fn slab_near(pts: &[f64], normal: V3) -> Result<crate::width3::Slab> {
    let h: Vec<f64> = pts.chunks_exact(3).map(|p| dot([p[0], p[1], p[2]], normal)).collect();
    let (slab, _) = active_fit(pts, 3, band(&h), |p| datum::slab(p, Orientation::Free), |f, p| {
        (p.chunks_exact(3).map(|q| dot([q[0], q[1], q[2]], f.normal)).collect(), f.lo, f.hi)
    })?;
    Ok(slab) // a slab names no points
}

#[cfg(test)]
mod radii_tests {
    #[test]
    fn the_written_out_distances_are_the_iterators_bit_for_bit() {
        let pts: Vec<f64> = (0..3000).map(|i| ((i * 7919) % 1013) as f64 * 0.0137 - 6.9 + 1e-9 * i as f64).collect();
        for (dim, c) in [(2, vec![0.31, -2.7]), (3, vec![1e3, -0.2, 5.5]), (2, vec![0.0, 0.0])] {
            let want: Vec<f64> = pts.chunks_exact(dim).map(|p| p.iter().zip(&c).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()).collect();
            let got = super::radii(&pts, dim, &c);
            assert_eq!(got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), want.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
        }
    }
}
