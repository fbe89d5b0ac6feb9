//! The ISO 16610-21:2011 Gaussian profile filter and the harmonic spectrum.
//!
//! The weighting function is `s(x) = 1/(alpha lc) exp(-pi (x / (alpha lc))^2)` with
//! `alpha = sqrt(ln 2 / pi)` (ISO 16610-21 Eq. 1), so a wave of the cut-off wavelength `lc`
//! keeps 50 % of its amplitude. Its transmission (the mean line's) for a wavelength
//! `lambda` is `exp(-pi (alpha lc / lambda)^2)` (Eq. 2).
//!
//! - Closed profiles (ISO 16610-21 Sec. 4.2, ISO 12181-2): the cut-off is given in
//!   undulations per revolution (UPR: 15, 50, 150, 500, 1500), harmonic `k` has wavelength
//!   `1/k` revolutions and keeps `exp(-pi (alpha k / UPR)^2)` of its amplitude. The profile
//!   is periodic, so the convolution is exactly a product of discrete Fourier coefficients:
//!   [`filter_closed`] multiplies harmonic `k` (and its alias `N - k`) by that weight; no
//!   truncation, no end effects.
//! - Open profiles (ISO 16610-21 Sec. 4.1): discrete convolution with the weighting
//!   function sampled at the profile's spacing and truncated at `+-lc` (where it has fallen
//!   to 6.5e-7 of its peak; the truncated weights are normalised to sum 1, so the
//!   transmission at zero frequency is exactly 1). End effects (ISO 16610-28): the first and
//!   last `lc` of the profile, where the weighting function would reach past its ends, are
//!   dropped: the filtered profile is `lc` shorter at each end ([`filter_open`]).

use gagekit_core::{GkError, Result};
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

/// `alpha = sqrt(ln 2 / pi)` of ISO 16610-21 Eq. 1.
pub fn alpha() -> f64 {
    (std::f64::consts::LN_2 / PI).sqrt()
}

/// Amplitude transmission of harmonic `k` of a closed profile through the Gaussian filter
/// of cut-off `upr` undulations per revolution: `exp(-pi (alpha k / upr)^2)`.
pub fn closed_transmission(k: f64, upr: f64) -> f64 {
    let x = alpha() * k / upr;
    (-PI * x * x).exp()
}

/// Amplitude transmission of a wave of wavelength `lambda` through the open-profile
/// Gaussian filter of cut-off `cutoff` (the same length unit): `exp(-pi (alpha lc / lambda)^2)`.
pub fn open_transmission(lambda: f64, cutoff: f64) -> f64 {
    let x = alpha() * cutoff / lambda;
    (-PI * x * x).exp()
}

/// Checks a cut-off in undulations per revolution.
pub fn check_upr(upr: f64) -> Result<()> {
    if !(upr.is_finite() && upr > 0.0) {
        return Err(GkError::invalid(format!(
            "the filter's cut-off must be a positive number of undulations per revolution \
             (ISO 12181-2: 15, 50, 150, 500 or 1500 UPR), got {upr}"
        )));
    }
    Ok(())
}

fn fft(values: &[f64], inverse: bool) -> Vec<Complex<f64>> {
    let mut buf: Vec<Complex<f64>> = values.iter().map(|&v| Complex::new(v, 0.0)).collect();
    transform(&mut buf, inverse);
    buf
}

fn transform(buf: &mut [Complex<f64>], inverse: bool) {
    let mut planner = FftPlanner::<f64>::new();
    let plan = if inverse { planner.plan_fft_inverse(buf.len()) } else { planner.plan_fft_forward(buf.len()) };
    plan.process(buf);
}

/// The Gaussian filter (mean line) of a closed profile sampled at `N` equal angles
/// `2 pi j / N`: harmonic `k` (`0 <= k <= N/2`, and `N - k` with it) is multiplied by
/// [`closed_transmission`]`(k, upr)`; the mean radius (k = 0) is kept.
pub fn filter_closed(r: &[f64], upr: f64) -> Result<Vec<f64>> {
    check_upr(upr)?;
    let n = r.len();
    if n < 3 {
        return Err(GkError::invalid(format!("a closed profile needs at least 3 samples, got {n}")));
    }
    let mut x = fft(r, false);
    for (k, c) in x.iter_mut().enumerate() {
        let h = k.min(n - k) as f64;
        *c *= closed_transmission(h, upr);
    }
    transform(&mut x, true);
    let scale = 1.0 / n as f64;
    Ok(x.iter().map(|c| c.re * scale).collect())
}

/// The harmonic spectrum of a closed profile sampled at `N` equal angles: for harmonics
/// `k = 1..=harmonics` (at most `(N - 1) / 2`, below the Nyquist harmonic) the amplitude
/// `a_k` and phase `phi_k` (rad) of `r(theta) = a_0 + sum a_k cos(k theta + phi_k)`.
pub fn spectrum(r: &[f64], harmonics: usize) -> (Vec<f64>, Vec<f64>) {
    let n = r.len();
    let kmax = harmonics.min(n.saturating_sub(1) / 2);
    let x = fft(r, false);
    let s = 2.0 / n as f64;
    let amp = (1..=kmax).map(|k| x[k].norm() * s).collect();
    let phase = (1..=kmax).map(|k| x[k].im.atan2(x[k].re)).collect();
    (amp, phase)
}

/// The Gaussian filter (mean line) of an open profile `z` sampled at spacing `dx`, cut-off
/// `cutoff` (same unit as `dx`). Returns `(first, filtered)`: the filtered values of samples
/// `first .. z.len() - first`, where `first = ceil(cutoff / dx)` (the ends, one cut-off
/// long, are dropped: ISO 16610-28's end-effect alternative of discarding them).
pub fn filter_open(z: &[f64], dx: f64, cutoff: f64) -> Result<(usize, Vec<f64>)> {
    if !(cutoff.is_finite() && cutoff > 0.0) {
        return Err(GkError::invalid(format!("the filter's cut-off length must be a positive number of mm, got {cutoff}")));
    }
    if !(dx.is_finite() && dx > 0.0) {
        return Err(GkError::invalid(format!("the profile's sampling step must be positive, got {dx}")));
    }
    let m = (cutoff / dx).ceil() as usize;
    let n = z.len();
    if n < 2 * m + 2 {
        return Err(GkError::invalid(format!(
            "the profile is {:.6} mm long: a Gaussian filter of cut-off {cutoff} mm needs more than 2 cut-offs \
             (one cut-off at each end is dropped, ISO 16610-28)",
            dx * (n.max(1) - 1) as f64
        )));
    }
    let al = alpha() * cutoff;
    let mut w: Vec<f64> = (0..=2 * m)
        .map(|i| {
            let x = (i as f64 - m as f64) * dx / al;
            (-PI * x * x).exp()
        })
        .collect();
    let sum: f64 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= sum);
    let out = (m..n - m)
        .map(|i| w.iter().zip(&z[i - m..=i + m]).map(|(a, b)| a * b).sum())
        .collect();
    Ok((m, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifty_percent_at_the_cut_off() {
        assert!((closed_transmission(50.0, 50.0) - 0.5).abs() < 1e-15);
        assert!((open_transmission(0.8, 0.8) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn closed_filter_keeps_exp_of_each_harmonic() {
        let n = 3600;
        let ks = [1usize, 2, 3, 7, 15, 50, 120, 400];
        let r: Vec<f64> = (0..n)
            .map(|j| {
                let t = std::f64::consts::TAU * j as f64 / n as f64;
                10.0 + ks.iter().map(|&k| 0.001 * (k as f64 * t + 0.3 * k as f64).cos()).sum::<f64>()
            })
            .collect();
        let f = filter_closed(&r, 50.0).unwrap();
        let (a, ph) = spectrum(&f, 500);
        for k in 1..=500 {
            let want = if ks.contains(&k) { 0.001 * closed_transmission(k as f64, 50.0) } else { 0.0 };
            assert!((a[k - 1] - want).abs() < 1e-12, "k {k}: {} vs {want}", a[k - 1]);
            if ks.contains(&k) && want > 1e-9 {
                let d = (ph[k - 1] - 0.3 * k as f64).rem_euclid(std::f64::consts::TAU);
                assert!(d.min(std::f64::consts::TAU - d) < 1e-6, "phase of {k}");
            }
        }
        let mean: f64 = f.iter().sum::<f64>() / n as f64;
        assert!((mean - 10.0).abs() < 1e-12);
    }

    #[test]
    fn open_filter_transmits_a_sine_as_the_standard_says() {
        let dx = 0.001;
        let lc = 0.8;
        for lambda in [0.4, 0.8, 2.5, 8.0] {
            let z: Vec<f64> = (0..20000).map(|i| (std::f64::consts::TAU * i as f64 * dx / lambda).sin()).collect();
            let (first, f) = filter_open(&z, dx, lc).unwrap();
            let amp = f.iter().map(|v| v.abs()).fold(0.0, f64::max);
            let want = open_transmission(lambda, lc);
            // sampling the Gaussian at dx = lc / 800: the discrete transmission differs by < 1e-9
            assert!((amp - want).abs() < 1e-6, "lambda {lambda}: {amp} vs {want}");
            assert_eq!(first, 800);
            assert_eq!(f.len(), 20000 - 1600);
        }
        assert!(filter_open(&[0.0; 100], 0.01, 0.8).is_err());
        assert!(filter_open(&[0.0; 100], 0.01, -1.0).is_err());
    }
}
