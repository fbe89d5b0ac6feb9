//! Active subsets for large inputs: the fit runs on the points of most extreme
//! least-squares residual, to which every point that lies outside the fitted
//! cylinder(s) is added until none does. The fit on the subset is then a fit on all
//! points: the objective of a subset never exceeds that of all points, and the two
//! agree at the reported axis.

use super::search::{fit_direct, fit_warm, Region};
use super::slp;
use super::{Criterion, CylinderFit, Options};
use crate::lsq::{self, Cylinder, Extent};
use gagekit_core::{GkError, Result};
use nalgebra::Vector3;
use std::cell::Cell;

/// Above this many points the fit runs on an active subset.
pub(crate) const SUBSET_ABOVE: usize = 2000;
/// Points of largest / smallest least-squares residual in the first subset.
pub(crate) const SUBSET_EXTREMES: usize = 128;
/// Violating points added to the subset per round.
const SUBSET_ADD: usize = 64;

/// The fit within `region` of all points (through active subsets above 2000 points);
/// `spread` is the largest principal spread of the points.
pub(super) fn fit_in(
    pts: &[f64],
    crit: Criterion,
    opts: &Options,
    lsq_fit: Option<&Cylinder>,
    region: &Region,
    spread: f64,
) -> Result<CylinderFit> {
    let n = pts.len() / 3;
    let lsq_axis = lsq_fit.map(|cy| Vector3::from(cy.direction));
    let Some(lc) = lsq_fit.filter(|_| n > SUBSET_ABOVE) else {
        return fit_direct(pts, crit, opts, lsq_axis, region);
    };
    // first subset: extreme residuals of the least-squares cylinder
    let dist: Vec<f64> = lsq::axis_distances(pts, &lc.point, &lc.direction).collect();
    let subset = first_subset(&dist, crit);
    let (mut iterations, mut evaluations) = (0, 0);
    let fit_sub = |sub: &[f64]| -> Result<CylinderFit> {
        let r = fit_direct(sub, crit, opts, lsq_axis, region)?;
        iterations += r.iterations;
        evaluations += r.evaluations;
        Ok(r)
    };
    let c = lsq::centroid(pts, 3);
    let c = [c[0], c[1], c[2]];
    let last = Cell::new(None);
    let violations = |r: &CylinderFit| violations(pts, crit, r, spread, &c, &last);
    let (mut r, subset) = settle(pts, subset, "cylinder", fit_sub, violations)?;
    r.control_in = r.control_in.iter().map(|&j| subset[j]).collect();
    r.control_out = r.control_out.iter().map(|&j| subset[j]).collect();
    (r.point, r.extent) = last.get().expect("the last round's foot and extent");
    r.iterations = iterations;
    r.evaluations = evaluations;
    Ok(r)
}

/// The warm-started fit within `region` of all points (see [`super::fit_near`]): above
/// 2000 points on an active subset that starts from the points of most extreme distance
/// to the warm axis; `None` when the local method cannot decide (see `fit_warm`).
pub(super) fn fit_near_in(
    pts: &[f64],
    crit: Criterion,
    warm: &slp::Axis,
    region: &Region,
    spread: f64,
    sum: Option<[f64; 3]>,
) -> Result<Option<CylinderFit>> {
    let n = pts.len() / 3;
    if n <= SUBSET_ABOVE {
        return fit_warm(pts, crit, warm, region);
    }
    let (p, d) = ([warm.point[0], warm.point[1], warm.point[2]], [warm.dir[0], warm.dir[1], warm.dir[2]]);
    let (dist, c): (Vec<f64>, [f64; 3]) = match sum {
        // lsq::centroid's two passes: its sum came from the checks' pass, its correction
        // joins the distances' pass (the same sums in the same order: the same bits)
        Some(sum) => {
            let nf = n as f64;
            let mean = [sum[0] / nf, sum[1] / nf, sum[2] / nf];
            let mut corr = [0.0f64; 3];
            let dist = lsq::axis_distances(pts, &p, &d)
                .zip(pts.chunks_exact(3))
                .map(|(x, q)| {
                    for k in 0..3 {
                        corr[k] += q[k] - mean[k];
                    }
                    x
                })
                .collect();
            (dist, [mean[0] + corr[0] / nf, mean[1] + corr[1] / nf, mean[2] + corr[2] / nf])
        }
        None => {
            let c = lsq::centroid(pts, 3);
            (lsq::axis_distances(pts, &p, &d).collect(), [c[0], c[1], c[2]])
        }
    };
    let subset = first_subset(&dist, crit);
    let (mut iterations, mut evaluations, mut undecided) = (0, 0, false);
    let fit_sub = |sub: &[f64]| -> Result<Option<CylinderFit>> {
        let r = fit_warm(sub, crit, warm, region)?;
        if let Some(r) = &r {
            iterations += r.iterations;
            evaluations += r.evaluations;
        } else {
            undecided = true;
        }
        Ok(r)
    };
    let last = Cell::new(None);
    let violations = |r: &Option<CylinderFit>| -> Vec<f64> { r.as_ref().map_or_else(Vec::new, |r| violations(pts, crit, r, spread, &c, &last)) };
    let (r, subset) = settle(pts, subset, "cylinder", fit_sub, violations)?;
    let Some(mut r) = r.filter(|_| !undecided) else { return Ok(None) };
    r.control_in = r.control_in.iter().map(|&j| subset[j]).collect();
    r.control_out = r.control_out.iter().map(|&j| subset[j]).collect();
    (r.point, r.extent) = last.get().expect("the last round's foot and extent");
    r.iterations = iterations;
    r.evaluations = evaluations;
    Ok(Some(r))
}

/// The foot on the axis (`point`, unit `dir`) of the centroid `c` of all the points
/// ([`lsq::centroid`]): the point a [`CylinderFit`] reports. The subset's fit gives the foot
/// of the subset's centroid, which moves along the axis with the subset (the bracket's boss
/// datum: 0.58 mm, when a start of the least-squares fit changed at the rounding level).
fn centroid_foot(c: &[f64; 3], point: &[f64; 3], dir: &[f64; 3]) -> [f64; 3] {
    let (p, d) = (Vector3::from(*point), Vector3::from(*dir));
    let foot = p + d * ((Vector3::new(c[0], c[1], c[2]) - p).dot(&d));
    if foot.iter().all(|x| x.is_finite()) {
        [foot[0], foot[1], foot[2]]
    } else {
        *point
    }
}

/// The first active subset: the [`SUBSET_EXTREMES`] points of smallest and largest
/// distance `dist` each criterion needs (MCC: the 2k largest; MIC: the 2k smallest and
/// k largest; MZC: k of each).
///
/// The order is total (ties by index), so these sets are unique: on many points one
/// linear pass finds them (`gagekit_core::select::extremes`; the same sets as a full sort,
/// whose order the active-subset iteration does not read: it sorts the subset by index).
fn first_subset(dist: &[f64], crit: Criterion) -> Vec<usize> {
    let n = dist.len();
    let k = SUBSET_EXTREMES;
    if n > 8 * k {
        let (low, high) = match crit {
            Criterion::MinCircumscribed => (0, 2 * k),
            Criterion::MaxInscribed => (2 * k, k),
            Criterion::MinZone => (k, k),
        };
        // one pass (the same sets: the order is total)
        let (mut out, large) = gagekit_core::select::extremes(dist, low, high);
        out.extend(large);
        return out;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| dist[i].total_cmp(&dist[j]).then(i.cmp(&j)));
    match crit {
        Criterion::MinCircumscribed => order[n - 2 * k..].to_vec(),
        Criterion::MaxInscribed => order[..2 * k].iter().chain(&order[n - k..]).copied().collect(),
        Criterion::MinZone => order[..k].iter().chain(&order[n - k..]).copied().collect(),
    }
}

/// How far each point lies outside the fitted cylinder(s) `r` (positive: outside, beyond
/// a tolerance of 1e-12 of the part's size), by the distances to its axis through the foot
/// of the centroid `c` of all the points ([`centroid_foot`]: the point the fit reports).
/// `last` gets that foot and the extent of the distances (the certificate, as
/// [`lsq::axis_extent`] computes it) of the fit in hand: when no point violates, the fit's
/// point and extent, without two more passes over the points.
fn violations(pts: &[f64], crit: Criterion, r: &CylinderFit, spread: f64, c: &[f64; 3], last: &Cell<Option<([f64; 3], Extent)>>) -> Vec<f64> {
    let tol = 1e-12 * spread.max(r.r_out);
    let foot = centroid_foot(c, &r.point, &r.direction);
    let mut e = Extent { min: f64::INFINITY, max: f64::NEG_INFINITY };
    let v = lsq::axis_distances(pts, &foot, &r.direction)
        .map(|d| {
            e = Extent { min: e.min.min(d), max: e.max.max(d) };
            let hi = if crit == Criterion::MaxInscribed { 0.0 } else { d - r.r_out };
            let lo = if crit == Criterion::MinCircumscribed { 0.0 } else { r.r_in - d };
            hi.max(lo) - tol
        })
        .collect();
    last.set(Some((foot, e)));
    v
}

/// The active-subset iteration: fit the points `subset` of `pts` (flat, row-major), add
/// the (at most [`SUBSET_ADD`]) points of largest positive `violations` of that fit, until
/// no point violates it. Returns the last fit and its subset (sorted: the fit's point `j`
/// is `subset[j]`).
pub(crate) fn settle<R>(
    pts: &[f64],
    mut subset: Vec<usize>,
    what: &str,
    mut fit: impl FnMut(&[f64]) -> Result<R>,
    violations: impl Fn(&R) -> Vec<f64>,
) -> Result<(R, Vec<usize>)> {
    for _round in 0..30 {
        subset.sort_unstable();
        subset.dedup();
        let sub: Vec<f64> = subset.iter().flat_map(|&i| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]]).collect();
        let r = fit(&sub)?;
        let v = violations(&r);
        let mut bad: Vec<usize> = (0..v.len()).filter(|&i| v[i] > 0.0).collect();
        if bad.is_empty() {
            return Ok((r, subset));
        }
        bad.sort_by(|&i, &j| v[j].total_cmp(&v[i]).then(i.cmp(&j)));
        subset.extend(bad.into_iter().take(SUBSET_ADD));
    }
    Err(GkError::numerical(format!("{what}: the active-subset iteration did not settle; please report this data set")))
}

#[cfg(test)]
mod first_subset_tests {
    use super::*;

    #[test]
    fn the_selected_extremes_are_those_of_a_full_sort() {
        // many ties (distances rounded to a few values) and distinct ones
        for n in [300, 1025, 5000] {
            let dist: Vec<f64> = (0..n).map(|i| ((i * 7919 % 97) as f64 * 0.25).floor() + if i % 3 == 0 { 1e-9 * i as f64 } else { 0.0 }).collect();
            for crit in [Criterion::MinCircumscribed, Criterion::MaxInscribed, Criterion::MinZone] {
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&i, &j| dist[i].total_cmp(&dist[j]).then(i.cmp(&j)));
                let k = SUBSET_EXTREMES;
                let mut want: Vec<usize> = match crit {
                    Criterion::MinCircumscribed => order[n - 2 * k..].to_vec(),
                    Criterion::MaxInscribed => order[..2 * k].iter().chain(&order[n - k..]).copied().collect(),
                    Criterion::MinZone => order[..k].iter().chain(&order[n - k..]).copied().collect(),
                };
                let mut got = first_subset(&dist, crit);
                want.sort_unstable();
                got.sort_unstable();
                assert_eq!(got, want, "n {n}");
            }
        }
    }
}
