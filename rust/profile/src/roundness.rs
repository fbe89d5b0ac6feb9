//! Roundness parameters of a closed profile (ISO 12181-1:2011, ISO 12181-2:2011), filtered
//! as a roundness instrument filters them.
//!
//! 1. The least-squares circle of the measured points (the exact geometric fit of
//!    `gagekit_form`) gives the centre the profile is resampled about.
//! 2. Filtered: the radii about that centre are resampled at `N` equal angles (linear
//!    interpolation in angle, [`crate::resample::closed`]; the first angle is the first
//!    measured point's, so the resampled profile moves with the part; gaps wider than the
//!    allowed one refused) and filtered with the ISO 16610-21 Gaussian filter of the chosen UPR
//!    ([`crate::gaussian::filter_closed`], exact in the frequency domain); the filtered
//!    profile is the `N` points `centre + r_f(theta_j) (cos theta_j, sin theta_j)`.
//!    Unfiltered: the measured points themselves.
//! 3. The reference circle is fitted to that profile with the exact kernels of
//!    `gagekit_form::circle`: LSCI (least squares, the default), MZCI (minimum zone; its
//!    reference circle is the mean of the two zone circles), MCCI (minimum circumscribed),
//!    MICI (maximum inscribed).
//! 4. Local roundness deviations are the distances from the reference centre minus its
//!    radius (positive outward); RONp, RONv, RONt, RONq are [`Params`] of them. ISO 12181-1
//!    defines RONp, RONv and RONq on the LSCI; against another reference they are the same
//!    formulas on that reference's deviations (MCCI: RONp = 0; MICI: RONv = 0; MZCI:
//!    RONp = RONv = RONt / 2).
//! 5. Eccentricity: the reference centre relative to the origin of the coordinates (on a
//!    roundness instrument the spindle axis). Spectrum: amplitudes of harmonics 1..K of the
//!    resampled profile's radii about the least-squares centre, filtered when the
//!    parameters are (harmonic k then carries `exp(-pi (alpha k / UPR)^2)` of its amplitude).

use crate::gaussian::{check_upr, filter_closed, spectrum};
use crate::resample::closed;
use crate::Params;
pub use crate::reference;
use gagekit_core::{check_finite, GkError, Result};
use gagekit_form::circle::{fit, least_squares};
use gagekit_form::criterion::FitCriterion;
use std::f64::consts::TAU;

/// Fewest points of a profile.
pub const MIN_POINTS: usize = 8;
/// ISO 12181-2 Sec. 7: at least 7 points per cut-off wavelength.
pub const POINTS_PER_CUTOFF: f64 = 7.0;
/// Resampling: at least this many equal angles (0.1 degree).
pub const DEFAULT_SAMPLES: usize = 3600;
/// Largest resampling count accepted.
pub const MAX_SAMPLES: usize = 10_000_000;
/// Harmonics in the spectrum unless asked otherwise.
pub const DEFAULT_HARMONICS: usize = 500;
/// Cut-off (UPR) whose gap rule applies to an unfiltered profile's spectrum: the coarsest
/// standard one.
pub const UNFILTERED_GAP_UPR: f64 = 15.0;

/// The ISO 12181-1 name of a reference circle.
pub fn reference_name(c: FitCriterion) -> &'static str {
    match c {
        FitCriterion::LeastSquares => "LSCI",
        FitCriterion::MinZone => "MZCI",
        FitCriterion::MinCircumscribed => "MCCI",
        FitCriterion::MaxInscribed => "MICI",
    }
}

/// What to compute.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Gaussian filter cut-off in undulations per revolution; `None`: unfiltered.
    pub upr: Option<f64>,
    pub reference: FitCriterion,
    /// Equal angles to resample at (default: 3600, or `7 UPR` rounded up to a multiple of
    /// 360 when more).
    pub samples: Option<usize>,
    /// Widest gap (degrees) bridged by interpolation (default: two sampling intervals of
    /// ISO 12181-2's minimum sampling, `720 / (7 UPR)` degrees; unfiltered: of 15 UPR).
    pub max_gap_deg: Option<f64>,
    /// Harmonics in the spectrum (default 500, at most `(N - 1) / 2`).
    pub harmonics: Option<usize>,
}

impl Default for Options {
    fn default() -> Self {
        Options { upr: None, reference: FitCriterion::LeastSquares, samples: None, max_gap_deg: None, harmonics: None }
    }
}

/// The roundness of a profile.
#[derive(Debug, Clone, PartialEq)]
pub struct Roundness {
    pub params: Params,
    pub reference: FitCriterion,
    /// The reference circle (MZCI: the mean of the zone circles).
    pub center: [f64; 2],
    pub radius: f64,
    /// Smallest and largest distance of the profile from `center` (MZCI: the zone circles).
    pub r_in: f64,
    pub r_out: f64,
    /// Indices into `profile` of the points that fix the reference.
    pub control: Vec<usize>,
    /// The least-squares centre of the measured points: the resampling centre.
    pub ls_center: [f64; 2],
    /// The evaluated profile, flat `[x0, y0, ...]`: the filtered resampled profile, or the
    /// measured points when unfiltered.
    pub profile: Vec<f64>,
    /// The unfiltered radii resampled at `samples` equal angles about `ls_center`, from the
    /// angle of the first measured point.
    pub resampled: Vec<f64>,
    pub samples: usize,
    pub n_points: usize,
    pub upr: Option<f64>,
    /// Largest angular gap of the measured points about `ls_center` (rad).
    pub max_gap: f64,
    /// Spectrum: amplitude and phase (rad, from the first measured point's angle) of
    /// harmonics 1..=K.
    pub amplitude: Vec<f64>,
    pub phase: Vec<f64>,
}

fn default_samples(upr: Option<f64>) -> usize {
    let need = upr.map_or(0.0, |u| (POINTS_PER_CUTOFF * u).ceil());
    if need <= DEFAULT_SAMPLES as f64 {
        DEFAULT_SAMPLES
    } else {
        ((need / 360.0).ceil() * 360.0).min(MAX_SAMPLES as f64) as usize
    }
}

/// RONt, RONp, RONv, RONq of 2-D points (flat `[x0, y0, ...]`), filtered or not, against
/// the chosen reference circle (see the module documentation for every step).
pub fn roundness(pts: &[f64], opt: &Options) -> Result<Roundness> {
    check_finite(pts, 2, "roundness profile")?;
    let n = pts.len() / 2;
    if let Some(u) = opt.upr {
        check_upr(u)?;
    }
    let need = opt.upr.map_or(MIN_POINTS as f64, |u| (POINTS_PER_CUTOFF * u).ceil().max(MIN_POINTS as f64));
    if (n as f64) < need {
        let why = match opt.upr {
            Some(u) => format!("a {u} UPR filter needs at least {need} (ISO 12181-2: 7 points per cut-off)"),
            None => format!("roundness needs at least {MIN_POINTS}"),
        };
        return Err(GkError::invalid(format!("the profile has {n} points; {why}")));
    }
    let samples = match opt.samples {
        Some(s) if s < MIN_POINTS || s as f64 > MAX_SAMPLES as f64 || (s as f64) < need => {
            return Err(GkError::invalid(format!(
                "samples: {s} equal angles; between {} and {MAX_SAMPLES} are allowed here",
                need.max(MIN_POINTS as f64)
            )))
        }
        Some(s) => s,
        None => default_samples(opt.upr),
    };
    let gap_upr = opt.upr.unwrap_or(UNFILTERED_GAP_UPR);
    let max_gap_deg = opt.max_gap_deg.unwrap_or(720.0 / (POINTS_PER_CUTOFF * gap_upr));
    if !(max_gap_deg.is_finite() && max_gap_deg > 0.0) {
        return Err(GkError::invalid(format!("max gap: a positive number of degrees, got {max_gap_deg}")));
    }
    let ls = least_squares(pts)?;
    // the angles start at the first measured point: the resampled profile moves with the part
    let start = (pts[1] - ls.center[1]).atan2(pts[0] - ls.center[0]);
    let (resampled, max_gap) = closed(pts, ls.center, samples, start, max_gap_deg.to_radians())?;
    let (profile, radii) = match opt.upr {
        Some(u) => {
            let rf = filter_closed(&resampled, u)?;
            let xy = rf
                .iter()
                .enumerate()
                .flat_map(|(j, r)| {
                    let t = start + TAU * j as f64 / samples as f64;
                    [ls.center[0] + r * t.cos(), ls.center[1] + r * t.sin()]
                })
                .collect();
            (xy, rf)
        }
        None => (pts.to_vec(), resampled.clone()),
    };
    if profile.chunks_exact(2).any(|p| p[0] == ls.center[0] && p[1] == ls.center[1]) {
        return Err(GkError::degenerate("the filtered profile passes through its centre"));
    }
    let f = fit(&profile, opt.reference)?;
    let dev: Vec<f64> =
        profile.chunks_exact(2).map(|p| (p[0] - f.center[0]).hypot(p[1] - f.center[1]) - f.radius).collect();
    let params = Params::from_deviations(&dev);
    let (amplitude, phase) = spectrum(&radii, opt.harmonics.unwrap_or(DEFAULT_HARMONICS));
    Ok(Roundness {
        params,
        reference: opt.reference,
        center: f.center,
        radius: f.radius,
        r_in: f.r_in,
        r_out: f.r_out,
        control: f.control,
        ls_center: ls.center,
        profile,
        resampled,
        samples,
        n_points: n,
        upr: opt.upr,
        max_gap,
        amplitude,
        phase,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaussian::closed_transmission;

    fn lobed(n: usize, r0: f64, terms: &[(usize, f64, f64)], shift: [f64; 2]) -> Vec<f64> {
        (0..n)
            .flat_map(|j| {
                let t = TAU * j as f64 / n as f64;
                let r = r0 + terms.iter().map(|&(k, a, ph)| a * (k as f64 * t + ph).cos()).sum::<f64>();
                [shift[0] + r * t.cos(), shift[1] + r * t.sin()]
            })
            .collect()
    }

    #[test]
    fn three_lobes_have_ront_2a_against_every_reference() {
        let a = 0.004;
        let pts = lobed(3600, 20.0, &[(3, a, 0.0)], [3.0, -7.0]);
        for c in [FitCriterion::LeastSquares, FitCriterion::MinZone, FitCriterion::MinCircumscribed, FitCriterion::MaxInscribed] {
            let r = roundness(&pts, &Options { reference: c, ..Default::default() }).unwrap();
            assert!((r.params.t - 2.0 * a).abs() < 1e-12, "{c:?}: {}", r.params.t);
            assert!((r.center[0] - 3.0).abs() < 1e-9 && (r.center[1] + 7.0).abs() < 1e-9);
        }
        let ls = roundness(&pts, &Options::default()).unwrap();
        assert!((ls.params.p - a).abs() < 1e-12 && (ls.params.v - a).abs() < 1e-12);
        assert!((ls.params.q - a / 2f64.sqrt()).abs() < 1e-12);
        assert!((ls.amplitude[2] - a).abs() < 1e-12);
    }

    #[test]
    fn filtered_harmonics_keep_the_gaussian_weight() {
        // 3-fold symmetric, so the least-squares centre is the true centre
        let terms = [(3usize, 0.002, 0.4), (15, 0.001, 1.0), (45, 0.001, -0.5), (150, 0.0005, 2.0)];
        let pts = lobed(3600, 12.0, &terms, [0.0, 0.0]);
        for upr in [15.0, 50.0, 150.0, 500.0] {
            let r = roundness(&pts, &Options { upr: Some(upr), ..Default::default() }).unwrap();
            for &(k, a, _) in &terms {
                let want = a * closed_transmission(k as f64, upr);
                assert!((r.amplitude[k - 1] - want).abs() < 1e-9, "upr {upr} k {k}: {} vs {want}", r.amplitude[k - 1]);
            }
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let pts = lobed(100, 5.0, &[], [0.0, 0.0]);
        assert!(roundness(&pts[..10], &Options::default()).is_err());
        assert!(roundness(&pts, &Options { upr: Some(50.0), ..Default::default() }).unwrap_err().message.contains("7 points per cut-off"));
        assert!(roundness(&pts, &Options { upr: Some(0.0), ..Default::default() }).is_err());
        assert!(roundness(&pts, &Options { upr: Some(f64::NAN), ..Default::default() }).is_err());
        let mut nan = pts.clone();
        nan[5] = f64::NAN;
        assert!(roundness(&nan, &Options::default()).is_err());
        let half: Vec<f64> = pts[..100].to_vec();
        assert!(roundness(&half, &Options::default()).unwrap_err().message.contains("gap"));
        assert_eq!(reference("mzci").unwrap(), FitCriterion::MinZone);
        assert_eq!(reference("MCC").unwrap(), FitCriterion::MinCircumscribed);
        assert_eq!(reference("least-squares").unwrap(), FitCriterion::LeastSquares);
        assert!(reference("bogus").is_err());
    }
}
