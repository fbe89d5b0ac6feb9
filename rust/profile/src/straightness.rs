//! Straightness parameters of a 2-D profile (ISO 12780-1:2011, ISO 12780-2:2011), filtered
//! or not.
//!
//! The profile's frame is its least-squares line: position `t` along it, oriented from the
//! first point of the file to the last, and deviation `z` along the normal to its left
//! (`(-d_y, d_x)`). Filtered: `z(t)` is resampled at a constant step (linear interpolation,
//! [`crate::resample::open`]; the default step is the mean spacing of the points, which
//! must be at most `cutoff / 7`) and filtered with the ISO 16610-21 Gaussian filter of
//! cut-off length `cutoff` ([`crate::gaussian::filter_open`], one cut-off dropped at each
//! end), or with the ISO 16610-22 cubic spline filter (`spline`: nothing dropped, a line is
//! its own mean line). The reference line is fitted to the evaluated profile: LSLI (least squares) or
//! MZLI (minimum zone, its mid-line); STRt, STRp, STRv, STRq are [`Params`] of the signed
//! deviations from it.

use crate::gaussian::filter_open;
use crate::resample::open;
use crate::spline;
use crate::Params;
use gagekit_core::{check_finite, GkError, Result};
use gagekit_form::criterion::FitCriterion;
use gagekit_form::{lsq, minzone};

/// Options of [`straightness`].
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Filter cut-off length (mm); `None`: unfiltered.
    pub cutoff: Option<f64>,
    /// The ISO 16610-22 cubic spline filter instead of the Gaussian (nothing dropped).
    pub spline: bool,
    /// Least squares (LSLI) or minimum zone (MZLI).
    pub reference: FitCriterion,
    /// Resampling step (mm); default: the mean spacing of the points.
    pub step: Option<f64>,
    /// Widest gap bridged by interpolation (mm); default `2 cutoff / 7`.
    pub max_gap: Option<f64>,
}

/// The straightness of a profile.
#[derive(Debug, Clone, PartialEq)]
pub struct Straightness {
    pub params: Params,
    pub reference: FitCriterion,
    /// The reference line: a point and unit direction, in the input's coordinates.
    pub point: [f64; 2],
    pub direction: [f64; 2],
    /// The evaluated profile (flat `[x0, y0, ...]`, input coordinates).
    pub profile: Vec<f64>,
    pub n_points: usize,
    /// Resampling step (filtered) and length of profile evaluated.
    pub step: Option<f64>,
    pub length: f64,
}

fn unit2(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    [v[0] / n, v[1] / n]
}

/// STRt, STRp, STRv, STRq of 2-D points (see the module documentation).
pub fn straightness(pts: &[f64], opt: &Options) -> Result<Straightness> {
    check_finite(pts, 2, "straightness profile")?;
    let n = pts.len() / 2;
    if n < 3 {
        return Err(GkError::invalid(format!("a straightness profile needs at least 3 points, got {n}")));
    }
    if !matches!(opt.reference, FitCriterion::LeastSquares | FitCriterion::MinZone) {
        return Err(GkError::config("straightness: the reference line is LSLI (least squares) or MZLI (minimum zone)"));
    }
    let ls = lsq::line(pts, 2)?;
    let c = [ls.point[0], ls.point[1]];
    let mut d = unit2([ls.direction[0], ls.direction[1]]);
    let (first, last) = (&pts[..2], &pts[pts.len() - 2..]);
    if (last[0] - first[0]) * d[0] + (last[1] - first[1]) * d[1] < 0.0 {
        d = [-d[0], -d[1]];
    }
    let nrm = [-d[1], d[0]];
    let to_xy = |t: f64, z: f64| [c[0] + t * d[0] + z * nrm[0], c[1] + t * d[1] + z * nrm[1]];
    let (profile, step) = match opt.cutoff {
        None => (pts.to_vec(), None),
        Some(lc) => {
            if !(lc.is_finite() && lc > 0.0) {
                return Err(GkError::invalid(format!("the cut-off length must be a positive number of mm, got {lc}")));
            }
            let t: Vec<f64> = pts.chunks_exact(2).map(|p| (p[0] - c[0]) * d[0] + (p[1] - c[1]) * d[1]).collect();
            let z: Vec<f64> = pts.chunks_exact(2).map(|p| (p[0] - c[0]) * nrm[0] + (p[1] - c[1]) * nrm[1]).collect();
            let (lo, hi) = t.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
            let step = opt.step.unwrap_or((hi - lo) / (n - 1) as f64);
            if !(step.is_finite() && step > 0.0) || step > lc / 7.0 {
                return Err(GkError::invalid(format!(
                    "a sampling step of {step:.6} mm is too coarse for a cut-off of {lc} mm (ISO 12780-2: at least 7 points per cut-off)"
                )));
            }
            let (t0, zs, _) = open(&t, &z, step, opt.max_gap.unwrap_or(2.0 * lc / 7.0))?;
            let (skip, zf) = if opt.spline { (0, spline::filter_open(&zs, step, lc)?) } else { filter_open(&zs, step, lc)? };
            let xy = zf
                .iter()
                .enumerate()
                .flat_map(|(i, &v)| to_xy(t0 + (skip + i) as f64 * step, v))
                .collect();
            (xy, Some(step))
        }
    };
    let (point, normal) = match opt.reference {
        FitCriterion::MinZone => {
            let z = minzone::line2(&profile)?;
            ([z.point[0], z.point[1]], [z.normal[0], z.normal[1]])
        }
        _ => {
            let l = lsq::line(&profile, 2)?;
            ([l.point[0], l.point[1]], [-l.direction[1], l.direction[0]])
        }
    };
    // deviations positive on the side of the profile frame's normal
    let s = if normal[0] * nrm[0] + normal[1] * nrm[1] < 0.0 { -1.0 } else { 1.0 };
    let normal = unit2([s * normal[0], s * normal[1]]);
    let dev: Vec<f64> =
        profile.chunks_exact(2).map(|p| (p[0] - point[0]) * normal[0] + (p[1] - point[1]) * normal[1]).collect();
    let ts: Vec<f64> = profile.chunks_exact(2).map(|p| (p[0] - c[0]) * d[0] + (p[1] - c[1]) * d[1]).collect();
    let length = ts.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - ts.iter().cloned().fold(f64::INFINITY, f64::min);
    Ok(Straightness {
        params: Params::from_deviations(&dev),
        reference: opt.reference,
        point,
        direction: [normal[1], -normal[0]],
        profile,
        n_points: n,
        step,
        length,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaussian::open_transmission;

    fn wavy(n: usize, len: f64, waves: &[(f64, f64)]) -> Vec<f64> {
        (0..n)
            .flat_map(|i| {
                let x = len * i as f64 / (n - 1) as f64;
                let z: f64 = waves.iter().map(|&(lam, a)| a * (std::f64::consts::TAU * x / lam).cos()).sum();
                // a tilted line: rotated by 0.3 rad, shifted
                let (c, s) = (0.3f64.cos(), 0.3f64.sin());
                [5.0 + c * x - s * z, -2.0 + s * x + c * z]
            })
            .collect()
    }

    #[test]
    fn unfiltered_sine_has_strt_2a() {
        let pts = wavy(4001, 40.0, &[(4.0, 0.003)]);
        for c in [FitCriterion::LeastSquares, FitCriterion::MinZone] {
            let s = straightness(&pts, &Options { cutoff: None, spline: false, reference: c, step: None, max_gap: None }).unwrap();
            assert!((s.params.t - 0.006).abs() < 1e-9, "{c:?} {}", s.params.t);
        }
    }

    #[test]
    fn filtered_waves_keep_the_gaussian_weight() {
        // whole periods in the 35 mm kept (one cut-off dropped at each end): the LS line is the axis
        for (lam, a) in [(5.0, 0.003), (2.5, 0.003), (0.25, 0.002)] {
            let pts = wavy(40001, 40.0, &[(lam, a)]);
            let s = straightness(&pts, &Options { cutoff: Some(2.5), spline: false, reference: FitCriterion::LeastSquares, step: None, max_gap: None })
                .unwrap();
            let want = 2.0 * a * open_transmission(lam, 2.5);
            assert!((s.params.t - want).abs() < 1e-9 + 1e-6 * want, "lambda {lam}: {} vs {want}", s.params.t);
            assert!((s.length - 35.0).abs() < 1e-6);
        }
        let pts = wavy(401, 40.0, &[(5.0, 0.003)]);
        let o = Options { cutoff: Some(0.5), spline: false, reference: FitCriterion::LeastSquares, step: None, max_gap: None };
        assert!(straightness(&pts, &o).unwrap_err().message.contains("7 points per cut-off"));
    }
}
