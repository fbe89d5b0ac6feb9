//! Active subsets for large inputs: the fit runs on the points of most extreme
//! least-squares residual, to which every point that lies outside the fitted
//! cylinder(s) is added until none does. The fit on the subset is then a fit on all
//! points: the objective of a subset never exceeds that of all points, and the two
//! agree at the reported axis.

use super::search::{fit_direct, Region};
use super::{Criterion, CylinderFit, Options};
use crate::lsq::{self, Cylinder};
use gagekit_core::{GkError, Result};
use nalgebra::Vector3;

/// Above this many points the fit runs on an active subset.
const SUBSET_ABOVE: usize = 2000;
/// Points of largest / smallest least-squares residual in the first subset.
const SUBSET_EXTREMES: usize = 128;
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
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| dist[i].total_cmp(&dist[j]).then(i.cmp(&j)));
    let k = SUBSET_EXTREMES;
    let mut subset: Vec<usize> = match crit {
        Criterion::MinCircumscribed => order[n - 2 * k..].to_vec(),
        Criterion::MaxInscribed => order[..2 * k].iter().chain(&order[n - k..]).copied().collect(),
        Criterion::MinZone => order[..k].iter().chain(&order[n - k..]).copied().collect(),
    };
    let (mut iterations, mut evaluations) = (0, 0);
    for _round in 0..30 {
        subset.sort_unstable();
        subset.dedup();
        let sub: Vec<f64> = subset.iter().flat_map(|&i| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]]).collect();
        let mut r = fit_direct(&sub, crit, opts, lsq_axis, region)?;
        iterations += r.iterations;
        evaluations += r.evaluations;
        let tol = 1e-12 * spread.max(r.r_out);
        let d: Vec<f64> = lsq::axis_distances(pts, &r.point, &r.direction).collect();
        let violation = |i: usize| -> f64 {
            let hi = if crit == Criterion::MaxInscribed { 0.0 } else { d[i] - r.r_out };
            let lo = if crit == Criterion::MinCircumscribed { 0.0 } else { r.r_in - d[i] };
            hi.max(lo)
        };
        let mut bad: Vec<usize> = (0..n).filter(|&i| violation(i) > tol).collect();
        if bad.is_empty() {
            r.control_in = r.control_in.iter().map(|&j| subset[j]).collect();
            r.control_out = r.control_out.iter().map(|&j| subset[j]).collect();
            r.extent = lsq::axis_extent(pts, &r.point, &r.direction);
            r.iterations = iterations;
            r.evaluations = evaluations;
            return Ok(r);
        }
        bad.sort_by(|&i, &j| violation(j).total_cmp(&violation(i)).then(i.cmp(&j)));
        subset.extend(bad.into_iter().take(SUBSET_ADD));
    }
    Err(GkError::numerical("cylinder: the active-subset iteration did not settle; please report this data set"))
}

