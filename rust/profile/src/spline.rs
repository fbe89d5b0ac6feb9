//! The ISO 16610-22:2015 cubic spline filter of open profiles.
//!
//! The mean line `w` of a profile `z` sampled at spacing `dx` solves
//! `(I + alpha^4 Q) w = z` (ISO 16610-22 Eq. 3 with the tension parameter beta = 0), where
//! `Q = D^T D` and `D` takes second differences: the boundary rows of `Q` are those of an
//! open profile (no periodic wrap), so a straight profile is its own mean line and the ends
//! need no run-in: nothing is dropped. `alpha = 1 / (2 sin(pi dx / lc))`, so that away
//! from the ends a wave of wavelength `lambda` keeps
//! `1 / (1 + (sin(pi dx / lambda) / sin(pi dx / lc))^4)` of its amplitude: 50 % at the
//! cut-off `lc` ([`spline_transmission`]). The system is symmetric positive definite and
//! pentadiagonal: a banded Cholesky factorisation solves it in linear time. Its condition
//! number is about `16 alpha^4 ~ (lc / (pi dx))^4 / 6`, so rounding grows with the fourth
//! power of the samples per cut-off (about 1e-10 relative at 250 samples per cut-off).

use gagekit_core::{GkError, Result};
use std::f64::consts::PI;

/// Amplitude transmission of a wave of wavelength `lambda` (interior of the profile).
pub fn spline_transmission(lambda: f64, cutoff: f64, dx: f64) -> f64 {
    let r = (PI * dx / lambda).sin() / (PI * dx / cutoff).sin();
    1.0 / (1.0 + r.powi(4))
}

/// The cubic spline mean line of `z` (spacing `dx`, cut-off `cutoff`, same unit).
pub fn filter_open(z: &[f64], dx: f64, cutoff: f64) -> Result<Vec<f64>> {
    if !(cutoff.is_finite() && cutoff > 0.0) || !(dx.is_finite() && dx > 0.0) {
        return Err(GkError::invalid(format!("spline filter: cut-off {cutoff} and spacing {dx} must be positive")));
    }
    if cutoff < 2.0 * dx {
        return Err(GkError::invalid(format!("spline filter: the cut-off {cutoff} mm is below two sampling steps ({dx} mm)")));
    }
    let n = z.len();
    if n < 3 {
        return Err(GkError::invalid(format!("spline filter: a profile needs at least 3 samples, got {n}")));
    }
    let a4 = (1.0 / (2.0 * (PI * dx / cutoff).sin())).powi(4);
    // bands of A = I + a4 D^T D: diagonal, first and second sub-diagonals
    let (mut d0, mut d1, mut d2) = (vec![1.0; n], vec![0.0; n], vec![0.0; n]);
    let c = [1.0, -2.0, 1.0];
    for k in 0..n - 2 {
        for i in 0..3 {
            d0[k + i] += a4 * c[i] * c[i];
            if i >= 1 {
                d1[k + i] += a4 * c[i] * c[i - 1];
            }
            if i == 2 {
                d2[k + i] += a4 * c[2] * c[0];
            }
        }
    }
    // banded Cholesky A = L L^T: l0 diagonal, l1 / l2 first / second sub-diagonal of L
    let (mut l0, mut l1, mut l2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        if i >= 2 {
            l2[i] = d2[i] / l0[i - 2];
        }
        if i >= 1 {
            let prev = if i >= 2 { l2[i] * l1[i - 1] } else { 0.0 };
            l1[i] = (d1[i] - prev) / l0[i - 1];
        }
        let s = d0[i] - l1[i] * l1[i] - l2[i] * l2[i];
        if !(s > 0.0) {
            return Err(GkError::numerical("spline filter: the system lost positive definiteness (cut-off far too long for the spacing)"));
        }
        l0[i] = s.sqrt();
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = z[i];
        if i >= 1 {
            s -= l1[i] * y[i - 1];
        }
        if i >= 2 {
            s -= l2[i] * y[i - 2];
        }
        y[i] = s / l0[i];
    }
    let mut w = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        if i + 1 < n {
            s -= l1[i + 1] * w[i + 1];
        }
        if i + 2 < n {
            s -= l2[i + 2] * w[i + 2];
        }
        w[i] = s / l0[i];
    }
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_its_own_mean_line() {
        let z: Vec<f64> = (0..500).map(|i| 3.0 - 0.002 * i as f64).collect();
        let w = filter_open(&z, 0.01, 0.8).unwrap();
        for (a, b) in z.iter().zip(&w) {
            assert!((a - b).abs() < 1e-10, "{a} {b}");
        }
    }

    #[test]
    fn waves_keep_the_standard_s_transmission_away_from_the_ends() {
        let dx = 0.005;
        let lc = 0.8;
        for lambda in [0.25, 0.8, 2.5] {
            let n = 8001;
            let z: Vec<f64> = (0..n).map(|i| (2.0 * PI * i as f64 * dx / lambda).cos()).collect();
            let w = filter_open(&z, dx, lc).unwrap();
            let want = spline_transmission(lambda, lc, dx);
            // the end effect decays like exp(-x / (alpha dx)) ~ exp(-x pi / lc): 5 cut-offs in
            let skip = (5.0 * lc / dx) as usize;
            let amp = w[skip..n - skip].iter().map(|v| v.abs()).fold(0.0, f64::max);
            assert!((amp - want).abs() < 1e-6, "lambda {lambda}: {amp} vs {want}");
        }
        assert!((spline_transmission(0.8, 0.8, 0.001) - 0.5).abs() < 1e-15);
    }
}
