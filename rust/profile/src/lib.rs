//! Filtered form parameters, as a roundness instrument (Talyrond, MarForm) prints them.
//!
//! - [`gaussian`]: the ISO 16610-21 Gaussian profile filter, closed profiles (roundness:
//!   exact, in the frequency domain, cut-off in undulations per revolution) and open
//!   profiles (straightness: convolution with the Gaussian weighting function, ends
//!   dropped), and the harmonic spectrum.
//! - [`resample`]: evenly spaced profiles from scanned points (by angle about a centre, by
//!   position along a line), linear interpolation, gaps refused.
//! - [`params`]: the peak, valley, peak-to-valley and RMS deviations (`t`, `p`, `v`, `q`).
//! - [`roundness`]: RONt, RONp, RONv, RONq (ISO 12181-1/-2) against LSCI, MZCI, MCCI, MICI,
//!   eccentricity and the spectrum.
//! - [`straightness`]: STRt, STRp, STRv, STRq of a 2-D profile (ISO 12780), filtered or not.
//! - [`flatness`]: FLTt, FLTp, FLTv, FLTq (ISO 12781) against LSPL or MZPL, unfiltered.

pub mod flatness;
pub mod gaussian;
pub mod params;
pub mod resample;
pub mod roundness;
pub mod spline;
pub mod straightness;

pub use params::Params;

use gagekit_core::{GkError, Result};
use gagekit_form::criterion::FitCriterion;

/// A reference feature by its ISO name: `LS`, `MZ`, `MC`, `MI` followed by the feature's
/// letters (`CI` circle, ISO 12181-1; `LI` line, ISO 12780-1; `PL` plane, ISO 12781-1;
/// `CY` cylinder, ISO 12180-1), or any name of the fit criterion table.
pub fn reference(name: &str) -> Result<FitCriterion> {
    let key = name.trim().to_uppercase();
    let stem = ["CI", "LI", "PL", "CY", "C", "L", "P"]
        .iter()
        .find_map(|s| key.strip_suffix(s).filter(|k| k.len() == 2))
        .unwrap_or(&key);
    match stem {
        "LS" => Ok(FitCriterion::LeastSquares),
        "MZ" => Ok(FitCriterion::MinZone),
        "MC" => Ok(FitCriterion::MinCircumscribed),
        "MI" => Ok(FitCriterion::MaxInscribed),
        _ => name.parse::<FitCriterion>().map_err(|_| {
            GkError::config(format!(
                "unknown reference {name:?}; choose one of LSCI, MZCI, MCCI, MICI (circles), LSLI, MZLI (lines), LSPL, MZPL (planes)"
            ))
        }),
    }
}
