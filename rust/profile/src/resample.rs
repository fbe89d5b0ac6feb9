//! Evenly spaced profiles from scanned points, as the filters need them (ISO 12181-2
//! Sec. 7, ISO 12780-2): linear interpolation between neighbouring points, in angle about a
//! centre (closed profiles) or in position along a line (open profiles). Points at the same
//! angle (position) are averaged. A gap wider than the allowed one is refused, not bridged:
//! a straight segment across it would be read as form.

use gagekit_core::{GkError, Result};
use std::f64::consts::TAU;

/// Sort `(key, value)` pairs by key and average the values of equal keys.
fn sorted_unique(mut kv: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    kv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(kv.len());
    let mut count = 0usize;
    for (k, v) in kv {
        match out.last_mut() {
            Some(last) if last.0 == k => {
                count += 1;
                last.1 += (v - last.1) / count as f64;
            }
            _ => {
                out.push((k, v));
                count = 1;
            }
        }
    }
    out
}

/// The polar angles (in `[0, 2 pi)`) and radii of 2-D points about `center`.
pub fn polar(pts: &[f64], center: [f64; 2]) -> Vec<(f64, f64)> {
    pts.chunks_exact(2)
        .map(|p| {
            let (dx, dy) = (p[0] - center[0], p[1] - center[1]);
            (dy.atan2(dx).rem_euclid(TAU), dx.hypot(dy))
        })
        .map(|(a, r)| (if a >= TAU { 0.0 } else { a }, r))
        .collect()
}

/// A closed profile resampled at `n` equal angles `start + 2 pi j / n` about `center`: the radius
/// at each, interpolated linearly in angle between the two neighbouring points (across
/// 0/360 degrees too). Returns `(radii, largest gap in rad)`. Refused: fewer than 3
/// distinct angles, a point at the centre, a gap wider than `max_gap` rad.
pub fn closed(pts: &[f64], center: [f64; 2], n: usize, start: f64, max_gap: f64) -> Result<(Vec<f64>, f64)> {
    let pr = sorted_unique(polar(pts, center));
    if pr.iter().any(|&(_, r)| r == 0.0) {
        return Err(GkError::degenerate("a point of the profile lies at its least-squares centre"));
    }
    let m = pr.len();
    if m < 3 {
        return Err(GkError::invalid(format!("a closed profile needs at least 3 points at distinct angles, got {m}")));
    }
    let (mut gap, mut at) = (pr[0].0 + TAU - pr[m - 1].0, pr[m - 1].0);
    for w in pr.windows(2) {
        if w[1].0 - w[0].0 > gap {
            gap = w[1].0 - w[0].0;
            at = w[0].0;
        }
    }
    if gap > max_gap {
        return Err(GkError::invalid(format!(
            "the profile has a gap of {:.3} deg after {:.3} deg (about its least-squares centre); at most {:.3} deg \
             can be bridged by interpolation for this filter (scan the whole circumference, or allow more: max gap)",
            gap.to_degrees(),
            at.to_degrees(),
            max_gap.to_degrees()
        )));
    }
    // periodic extension: the last point one turn back, the first one turn on
    let mut ext = Vec::with_capacity(m + 2);
    ext.push((pr[m - 1].0 - TAU, pr[m - 1].1));
    ext.extend_from_slice(&pr);
    ext.push((pr[0].0 + TAU, pr[0].1));
    let radii = (0..n)
        .map(|j| {
            let t = (start + TAU * j as f64 / n as f64).rem_euclid(TAU);
            let i = ext.partition_point(|p| p.0 <= t).clamp(1, ext.len() - 1);
            let (a, b) = (ext[i - 1], ext[i]);
            let w = if b.0 > a.0 { (t - a.0) / (b.0 - a.0) } else { 0.0 };
            a.1 + w * (b.1 - a.1)
        })
        .collect();
    Ok((radii, gap))
}

/// An open profile `z(t)` resampled at `t0 + i step`, `i = 0..`, up to the last position,
/// by linear interpolation. Returns `(t0, values, largest gap)`. Refused: fewer than 2
/// distinct positions, a gap wider than `max_gap`.
pub fn open(t: &[f64], z: &[f64], step: f64, max_gap: f64) -> Result<(f64, Vec<f64>, f64)> {
    if !(step.is_finite() && step > 0.0) {
        return Err(GkError::invalid(format!("the sampling step must be a positive length, got {step}")));
    }
    let tz = sorted_unique(t.iter().copied().zip(z.iter().copied()).collect());
    let m = tz.len();
    if m < 2 {
        return Err(GkError::invalid(format!("an open profile needs at least 2 points at distinct positions, got {m}")));
    }
    let (gap, at) = tz.windows(2).map(|w| (w[1].0 - w[0].0, w[0].0)).fold((0.0, tz[0].0), |a, b| if b.0 > a.0 { b } else { a });
    if gap > max_gap {
        return Err(GkError::invalid(format!(
            "the profile has a gap of {gap:.6} mm at {:.6} mm along it; at most {max_gap:.6} mm can be bridged \
             by interpolation for this filter",
            at - tz[0].0
        )));
    }
    let t0 = tz[0].0;
    let len = tz[m - 1].0 - t0;
    let count = (len / step + 1e-9).floor() as usize + 1;
    if count > 50_000_000 {
        return Err(GkError::invalid(format!("a step of {step} mm over {len} mm gives more than 5e7 samples")));
    }
    let values = (0..count)
        .map(|i| {
            let x = t0 + i as f64 * step;
            let k = tz.partition_point(|p| p.0 <= x).clamp(1, m - 1);
            let (a, b) = (tz[k - 1], tz[k]);
            a.1 + (x - a.0) / (b.0 - a.0) * (b.1 - a.1)
        })
        .collect();
    Ok((t0, values, gap))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_spaced_points_come_back_unchanged() {
        let n = 360;
        let pts: Vec<f64> = (0..n)
            .flat_map(|j| {
                let t = TAU * j as f64 / n as f64;
                let r = 5.0 + 0.01 * (3.0 * t).cos();
                [1.0 + r * t.cos(), 2.0 + r * t.sin()]
            })
            .collect();
        let (r, gap) = closed(&pts, [1.0, 2.0], n, 0.0, 0.1).unwrap();
        for (j, v) in r.iter().enumerate() {
            let t = TAU * j as f64 / n as f64;
            assert!((v - (5.0 + 0.01 * (3.0 * t).cos())).abs() < 1e-12);
        }
        assert!((gap - TAU / n as f64).abs() < 1e-12);
        // halfway between samples: the linear interpolation of the two
        let (r2, _) = closed(&pts, [1.0, 2.0], 2 * n, 0.0, 0.1).unwrap();
        assert!((r2[1] - 0.5 * (r[0] + r[1])).abs() < 1e-12);
        assert!((r2[2 * n - 1] - 0.5 * (r[n - 1] + r[0])).abs() < 1e-12);
    }

    #[test]
    fn a_gap_is_refused() {
        let pts: Vec<f64> = (0..300).flat_map(|j| {
            let t = j as f64 * (TAU * 0.75) / 300.0;
            [t.cos(), t.sin()]
        }).collect();
        let e = closed(&pts, [0.0, 0.0], 360, 0.0, 0.1).unwrap_err();
        assert!(e.message.contains("gap of 90.9"), "{}", e.message);
    }

    #[test]
    fn open_profile() {
        let t = [0.0, 1.0, 3.0, 2.0];
        let z = [0.0, 1.0, 3.0, 2.0];
        let (t0, v, gap) = open(&t, &z, 0.5, 1.5).unwrap();
        assert_eq!(t0, 0.0);
        assert_eq!(v, vec![0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]);
        assert_eq!(gap, 1.0);
        assert!(open(&t, &z, 0.5, 0.5).is_err());
    }
}
