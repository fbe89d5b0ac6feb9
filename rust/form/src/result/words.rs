//! The reader's words about a fit: arc, search-cone and outside-optimum warnings, with
//! numbers formatted as the package has always printed them (C's `%g`).

use crate::criterion::FitCriterion;

/// `x` as C's / Python's `%.{prec}g`: `prec` significant digits, fixed notation for
/// decimal exponents in [-4, prec), else scientific with a signed two-digit exponent;
/// trailing zeros (and a trailing point) dropped.
pub fn fmt_g(x: f64, prec: usize) -> String {
    if !x.is_finite() {
        return if x.is_nan() { "nan".into() } else if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    let prec = prec.max(1);
    if x == 0.0 {
        return if x.is_sign_negative() { "-0".into() } else { "0".into() };
    }
    let sci = format!("{:.*e}", prec - 1, x);
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let trim = |s: &str| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if (-4..prec as i32).contains(&exp) {
        trim(&format!("{:.*}", (prec as i32 - 1 - exp) as usize, x))
    } else {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{}{:02}", trim(mantissa), sign, exp.abs())
    }
}

/// The explanation of a short arc of a circle (the ill-posed flag is the kernel's).
pub(super) fn circle_arc(crit: FitCriterion, arc_deg: f64) -> Vec<String> {
    let min = crate::circle::MIN_ARC_DEG;
    if arc_deg >= min {
        return Vec::new();
    }
    if crit == FitCriterion::MaxInscribed {
        return vec![format!(
            "the points cover only {arc_deg:.1} degrees of arc (< {min:.0}): the maximum inscribed circle is \
             ill-posed and its radius is not a meaningful size"
        )];
    }
    vec![format!("the points cover only {arc_deg:.1} degrees of arc: centre and radius are poorly determined")]
}

/// The explanation of a short arc around a cylinder's axis.
pub(super) fn cylinder_arc(crit: FitCriterion, arc_deg: f64) -> Vec<String> {
    let min = crate::cylinder::MIN_ARC.to_degrees();
    if arc_deg >= min {
        return Vec::new();
    }
    if crit == FitCriterion::MaxInscribed {
        return vec![format!(
            "the points cover only {arc_deg:.1} degrees around the axis (< {min:.0}): the maximum inscribed \
             cylinder is ill-posed and its radius is not a meaningful size"
        )];
    }
    vec![format!("the points cover only {arc_deg:.1} degrees around the axis: axis and radius are poorly determined")]
}

/// The warning for an axis on the boundary of the search cone.
pub(super) fn at_limit(max_tilt_deg: f64) -> String {
    format!(
        "the axis lies on the boundary of the search cone (max_tilt = {} degrees from the reference axis): the \
         points alone would tilt it further; give the nominal axis (axis=...) or check the data",
        fmt_g(max_tilt_deg, 6)
    )
}

/// The warning for a better optimum of the free search outside the search cone: its
/// `value` (radius, or zone width for the minimum zone; mm) and the `tilt` (rad) of its
/// axis from the reference axis.
pub fn outside_warning(crit: FitCriterion, value: f64, tilt: f64, max_tilt_deg: f64) -> String {
    let what = if crit == FitCriterion::MinZone { "zone width" } else { "radius" };
    format!(
        "a search over all orientations finds a better {} {what}, {} mm, with the axis {:.2} degrees from the \
         reference axis, outside max_tilt = {} degrees (it is not reported; pass max_tilt=90 to accept it)",
        crit.name(),
        fmt_g(value, 9),
        tilt.to_degrees(),
        fmt_g(max_tilt_deg, 6)
    )
}
