//! Circular tests with a telescoping ballbar, ISO 230-4:2022.
//!
//! A run is a list of readings: the commanded angle theta of the ball on its circle (rad, from
//! the plane's first axis towards its second), the radial deviation d = measured minus nominal
//! ballbar length (mm) and the direction of travel (+1 counter-clockwise, -1 clockwise). The
//! reading is placed at its commanded angle: q = (R + d) (cos theta, sin theta) about the pivot.
//!
//! - Circular deviation G (ISO 230-4 3.2.2): the radial width of the actual path about its
//!   least-squares circle centre, per direction and for both directions together. The
//!   least-squares circle is fitted in deviation form (Gauss-Newton on the radii minus R, never
//!   on coordinates of size R), so G is exact to the last bits of the deviations.
//! - Radial deviation F (3.2.3): max and min of d, about the nominal centre (the pivot).
//! - Circular hysteresis H (3.2.4): the largest radial difference between the clockwise and
//!   counter-clockwise paths at the same angle, about the common least-squares centre.
//! - Diagnostics: one linear least-squares fit of the deviations of both runs to the effect of
//!   each error source on the ballbar length (first order, dr = u . e):
//!   radius 1; centre per run cos, sin; scale mismatch cos 2theta (coefficient R (s1 - s2) / 2);
//!   squareness sin 2theta (coefficient R phi / 2 for a second axis that leans by phi towards
//!   the first: the included angle is 90 deg - phi); servo mismatch s sin 2theta (coefficient
//!   -v dt / 2 for an axis 2 that lags axis 1 by dt at the path speed v); backlash (lost motion
//!   b: the axis is b/2 behind its command in the direction of travel) per axis and run,
//!   s sgn(sin) cos / 2 and -s sgn(cos) sin / 2; cyclic error of pitch p per axis,
//!   (sin, cos)(2 pi x / p) cos and (sin, cos)(2 pi y / p) sin.
//! - Each diagnostic's share of G: (G - G of the deviations without that term's fitted
//!   contribution) / G, both directions together.
//! - Reversal spikes: the largest residual of the fit within a few degrees of each axis
//!   reversal, above the median residual away from the reversals.

use crate::ident::lstsq;
use gagekit_core::{interrupt, GkError, Result};
use std::f64::consts::PI;

/// A least-squares circle of ballbar readings (mm).
#[derive(Clone, Debug)]
pub struct CircleFit {
    /// Centre of the least-squares circle relative to the pivot, plane coordinates.
    pub centre: [f64; 2],
    /// Least-squares radius minus the nominal radius.
    pub radius_deviation: f64,
    /// Radial width of the path about that centre (circular deviation G).
    pub g: f64,
    pub n: usize,
}

/// Everything a ballbar test gives (mm, rad, s).
#[derive(Clone, Debug)]
pub struct BallbarAnalysis {
    pub both: CircleFit,
    pub ccw: Option<CircleFit>,
    pub cw: Option<CircleFit>,
    pub f_max: f64,
    pub f_min: f64,
    pub hysteresis: Option<f64>,
    /// Radius term of the diagnostic fit (ballbar length and mean scale), mm.
    pub radius_term: f64,
    /// Squareness phi, rad (positive: the included angle of +axis1 and +axis2 is below 90 deg).
    pub squareness: f64,
    pub squareness_fraction: f64,
    /// Scale mismatch s1 - s2 (mm/mm; positive: axis 1 travels further than axis 2).
    pub scale_mismatch: f64,
    pub scale_fraction: f64,
    /// v dt: how far axis 2 trails axis 1 along the path, mm (both directions needed).
    pub servo_lag: Option<f64>,
    /// dt = servo_lag / v, s, when the feed is given.
    pub servo_mismatch: Option<f64>,
    pub servo_fraction: Option<f64>,
    /// Lost motion per axis (0, 1) and run (0 ccw, 1 cw), mm; None for a missing run.
    pub backlash: [[Option<f64>; 2]; 2],
    pub backlash_fraction: [f64; 2],
    /// Centre offset term's share of G (about the least-squares centre: ~0 by definition).
    pub centre_fraction: f64,
    /// Cyclic error amplitude per axis, mm, and its pitch (None: no pitch could be resolved).
    pub cyclic: Option<[f64; 2]>,
    pub cyclic_fraction: Option<[f64; 2]>,
    pub pitch: Option<f64>,
    /// Reversal spikes per axis (0, 1) at its positive and negative end, mm (signed).
    pub spikes: [[f64; 2]; 2],
    /// RMS residual of the diagnostic fit, mm.
    pub residual_rms: f64,
}

/// Radius minus R of reading (a = R + d, u) about centre c, computed without cancellation:
/// |a u - c| - R = d + (|c|^2 - 2 a u.c) / (a (1 + sqrt(1 + eps))), eps = (|c|^2 - 2 a u.c) / a^2.
fn radial(r: f64, d: f64, u: [f64; 2], c: [f64; 2]) -> f64 {
    let a = r + d;
    let num = c[0] * c[0] + c[1] * c[1] - 2.0 * a * (u[0] * c[0] + u[1] * c[1]);
    let eps = num / (a * a);
    d + num / (a * (1.0 + (1.0 + eps).sqrt()))
}

/// Least-squares circle of readings (Gauss-Newton in deviation form, from the pivot).
pub fn circle_fit(radius: f64, angles: &[f64], dev: &[f64]) -> Result<CircleFit> {
    let n = angles.len();
    if n < 3 {
        return Err(GkError::degenerate(format!("ballbar: {n} readings; a circle needs at least 3")));
    }
    let u: Vec<[f64; 2]> = angles.iter().map(|t| [t.cos(), t.sin()]).collect();
    let mut c = [0.0f64; 2];
    let mut rho = dev.iter().sum::<f64>() / n as f64;
    for _ in 0..100 {
        // residual e_i = g_i(c) - rho; d e / d c = -(a u - c)/|a u - c| ~ -u; d e / d rho = -1
        let mut ata = [[0.0f64; 3]; 3];
        let mut atb = [0.0f64; 3];
        for i in 0..n {
            let a = radius + dev[i];
            let v = [a * u[i][0] - c[0], a * u[i][1] - c[1]];
            let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
            let j = [-v[0] / len, -v[1] / len, -1.0];
            let e = radial(radius, dev[i], u[i], c) - rho;
            for p in 0..3 {
                atb[p] -= j[p] * e;
                for q in 0..3 {
                    ata[p][q] += j[p] * j[q];
                }
            }
        }
        let step = solve3(ata, atb).ok_or_else(|| {
            GkError::degenerate("ballbar: the readings do not determine a circle (all at one angle?)")
        })?;
        c[0] += step[0];
        c[1] += step[1];
        rho += step[2];
        if step.iter().all(|s| s.abs() <= 1e-17 * radius.max(1.0)) {
            break;
        }
    }
    let g_vals: Vec<f64> = (0..n).map(|i| radial(radius, dev[i], u[i], c)).collect();
    let (lo, hi) = g_vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
    Ok(CircleFit { centre: c, radius_deviation: rho, g: hi - lo, n })
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let m = nalgebra::Matrix3::from_fn(|i, j| a[i][j]);
    let x = m.lu().solve(&nalgebra::Vector3::from(b))?;
    if x.iter().all(|v| v.is_finite()) {
        Some([x[0], x[1], x[2]])
    } else {
        None
    }
}

/// The inputs of one analysis.
pub struct BallbarInput<'a> {
    /// Nominal radius (ballbar length), mm.
    pub radius: f64,
    /// Commanded angles, rad.
    pub angles: &'a [f64],
    /// Radial deviations, mm.
    pub deviations: &'a [f64],
    /// +1 counter-clockwise, -1 clockwise.
    pub directions: &'a [i8],
    /// Pitch of the cyclic error, mm (None: the pitch that explains most is searched).
    pub pitch: Option<f64>,
    /// Path feed, mm/min (for the servo mismatch in seconds).
    pub feed: Option<f64>,
}

/// Sign of a sine or cosine of an angle, 0 at the axis reversals themselves (|v| below 1e-12:
/// sin(pi) is 1.2e-16 in floating point, and a reading at the reversal angle is mid-step).
fn sgn(v: f64) -> f64 {
    if v > 1e-12 {
        1.0
    } else if v < -1e-12 {
        -1.0
    } else {
        0.0
    }
}

/// Columns of the diagnostic fit. `runs`: which of (ccw, cw) are present.
struct Columns {
    names: Vec<&'static str>,
}

fn basis(th: f64, s: f64, runs: [bool; 2], pitch: Option<f64>, radius: f64) -> (Vec<f64>, Vec<&'static str>) {
    let (sn, cs) = th.sin_cos();
    let ccw = if s > 0.0 { 1.0 } else { 0.0 };
    let cw = 1.0 - ccw;
    let mut v = vec![1.0];
    let mut n = vec!["radius"];
    let both = runs[0] && runs[1];
    for (k, (ind, on)) in [(ccw, runs[0]), (cw, runs[1])].into_iter().enumerate() {
        if on {
            v.extend([ind * cs, ind * sn]);
            n.extend(if k == 0 { ["centre_x_ccw", "centre_y_ccw"] } else { ["centre_x_cw", "centre_y_cw"] });
        }
    }
    v.extend([(2.0 * th).cos(), (2.0 * th).sin()]);
    n.extend(["scale", "squareness"]);
    if both {
        v.push(s * (2.0 * th).sin());
        n.push("servo");
    }
    for (k, (ind, on)) in [(ccw, runs[0]), (cw, runs[1])].into_iter().enumerate() {
        if on {
            v.push(ind * 0.5 * s * sgn(sn) * cs);
            v.push(-ind * 0.5 * s * sgn(cs) * sn);
            n.extend(if k == 0 { ["backlash_1_ccw", "backlash_2_ccw"] } else { ["backlash_1_cw", "backlash_2_cw"] });
        }
    }
    if let Some(p) = pitch {
        let w = 2.0 * PI * radius / p;
        v.extend([(w * cs).sin() * cs, (w * cs).cos() * cs, (w * sn).sin() * sn, (w * sn).cos() * sn]);
        n.extend(["cyclic_1s", "cyclic_1c", "cyclic_2s", "cyclic_2c"]);
    }
    (v, n)
}

fn design(inp: &BallbarInput, runs: [bool; 2], pitch: Option<f64>) -> (Vec<f64>, Columns) {
    let mut a = Vec::new();
    let mut names = Vec::new();
    for (i, &th) in inp.angles.iter().enumerate() {
        let (row, n) = basis(th, inp.directions[i] as f64, runs, pitch, inp.radius);
        a.extend(row);
        names = n;
    }
    (a, Columns { names })
}

/// The ballbar's G of both runs together for deviations `dev`.
fn g_both(inp: &BallbarInput, dev: &[f64]) -> Result<f64> {
    Ok(circle_fit(inp.radius, inp.angles, dev)?.g)
}

/// The pitch (mm) whose cyclic terms explain most of what the other terms leave.
fn search_pitch(inp: &BallbarInput, residual: &[f64]) -> Result<Option<f64>> {
    let mut sorted: Vec<f64> = inp.angles.iter().map(|t| t.rem_euclid(2.0 * PI)).collect();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let mut steps: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 1e-12).collect();
    if steps.is_empty() {
        return Ok(None);
    }
    steps.sort_by(|a, b| a.total_cmp(b));
    // the largest step of an axis between two readings is R dtheta (distinct angles of both
    // runs together): at least 2.5 readings per period of the cyclic error
    let dtheta = steps[steps.len() / 2];
    let p_min = (2.5 * inp.radius * dtheta).max(0.5);
    let p_max = inp.radius / 2.0;
    if p_min >= p_max {
        return Ok(None);
    }
    let mut best = (0.0, p_min);
    let mut p = p_min;
    while p <= p_max {
        interrupt::check()?;
        let e = explained(inp, residual, p);
        if e > best.0 {
            best = (e, p);
        }
        p *= 1.002;
    }
    if best.0 <= 0.0 {
        return Ok(None);
    }
    // refine about the best grid pitch (golden section on the explained sum of squares)
    let (mut lo, mut hi) = (best.1 / 1.002, best.1 * 1.002);
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (a, b) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
        if explained(inp, residual, a) > explained(inp, residual, b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    Ok(Some(0.5 * (lo + hi)))
}

/// Sum of squares of `residual` explained by the four cyclic columns of pitch `p`.
fn explained(inp: &BallbarInput, residual: &[f64], p: f64) -> f64 {
    let w = 2.0 * PI * inp.radius / p;
    let mut ata = [[0.0f64; 4]; 4];
    let mut atb = [0.0f64; 4];
    for (i, &th) in inp.angles.iter().enumerate() {
        let (sn, cs) = th.sin_cos();
        let row = [(w * cs).sin() * cs, (w * cs).cos() * cs, (w * sn).sin() * sn, (w * sn).cos() * sn];
        for a in 0..4 {
            atb[a] += row[a] * residual[i];
            for b in 0..4 {
                ata[a][b] += row[a] * row[b];
            }
        }
    }
    let m = nalgebra::Matrix4::from_fn(|i, j| ata[i][j]);
    let rhs = nalgebra::Vector4::from(atb);
    match m.lu().solve(&rhs) {
        Some(x) if x.dot(&rhs).is_finite() => x.dot(&rhs),
        _ => 0.0,
    }
}

/// Analyse one ballbar test (one or both directions).
pub fn analyse(inp: &BallbarInput) -> Result<BallbarAnalysis> {
    let n = inp.angles.len();
    if inp.deviations.len() != n || inp.directions.len() != n {
        return Err(GkError::invalid("ballbar: angles, deviations and directions differ in length"));
    }
    if !(inp.radius.is_finite() && inp.radius > 0.0) {
        return Err(GkError::invalid(format!("ballbar: the radius must be positive, got {}", inp.radius)));
    }
    for i in 0..n {
        if !(inp.angles[i].is_finite() && inp.deviations[i].is_finite()) {
            return Err(GkError::invalid(format!("ballbar: reading {i} is not finite")));
        }
        if inp.deviations[i].abs() >= 0.5 * inp.radius {
            return Err(GkError::invalid(format!(
                "ballbar: reading {i} deviates by {:.4e} mm, half the radius or more: check the units (deviation in um)",
                inp.deviations[i]
            )));
        }
        if inp.directions[i] != 1 && inp.directions[i] != -1 {
            return Err(GkError::invalid(format!("ballbar: reading {i} has no direction (+1 ccw, -1 cw)")));
        }
    }
    if let Some(p) = inp.pitch {
        if !(p.is_finite() && p > 0.0) {
            return Err(GkError::invalid(format!("ballbar: the pitch must be positive, got {p}")));
        }
    }
    if let Some(f) = inp.feed {
        if !(f.is_finite() && f > 0.0) {
            return Err(GkError::invalid(format!("ballbar: the feed must be positive, got {f}")));
        }
    }
    let pick = |dir: i8| -> (Vec<f64>, Vec<f64>) {
        (0..n).filter(|&i| inp.directions[i] == dir).map(|i| (inp.angles[i], inp.deviations[i])).unzip()
    };
    let (a_ccw, d_ccw) = pick(1);
    let (a_cw, d_cw) = pick(-1);
    let runs = [a_ccw.len() >= 3, a_cw.len() >= 3];
    if !a_ccw.is_empty() && !runs[0] || !a_cw.is_empty() && !runs[1] {
        return Err(GkError::degenerate("ballbar: a run has fewer than 3 readings"));
    }
    let both = circle_fit(inp.radius, inp.angles, inp.deviations)?;
    let ccw = if runs[0] { Some(circle_fit(inp.radius, &a_ccw, &d_ccw)?) } else { None };
    let cw = if runs[1] { Some(circle_fit(inp.radius, &a_cw, &d_cw)?) } else { None };
    let (f_min, f_max) = inp.deviations.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
    let hysteresis = if runs[0] && runs[1] { Some(hysteresis(inp.radius, both.centre, &a_ccw, &d_ccw, &a_cw, &d_cw)) } else { None };

    // diagnostic fit: first without cyclic terms (to find the pitch), then with them
    let fit = |pitch: Option<f64>| -> Result<(Vec<f64>, Columns, Vec<f64>, f64)> {
        let (a, cols) = design(inp, runs, pitch);
        let k = cols.names.len();
        let sol = lstsq(&a, n, k, inp.deviations).map_err(|e| {
            GkError::degenerate(format!(
                "ballbar: the readings cannot separate the error sources ({}): measure full circles in both directions",
                e.message
            ))
        })?;
        Ok((sol.x, cols, a, sol.rss))
    };
    let (x0, _, a0, _) = fit(None)?;
    let k0 = x0.len();
    let residual0: Vec<f64> = (0..n).map(|i| inp.deviations[i] - (0..k0).map(|j| a0[i * k0 + j] * x0[j]).sum::<f64>()).collect();
    let pitch = match inp.pitch {
        Some(p) => Some(p),
        None => search_pitch(inp, &residual0)?,
    };
    let (x, cols, a, rss) = match pitch {
        Some(_) => fit(pitch)?,
        None => fit(None)?,
    };
    let k = x.len();
    let col = |name: &str| cols.names.iter().position(|c| *c == name);
    let g0 = both.g;
    let share = |names: &[&str]| -> Result<f64> {
        let idx: Vec<usize> = names.iter().filter_map(|nm| col(nm)).collect();
        if idx.is_empty() || g0 <= 0.0 {
            return Ok(0.0);
        }
        let rest: Vec<f64> =
            (0..n).map(|i| inp.deviations[i] - idx.iter().map(|&j| a[i * k + j] * x[j]).sum::<f64>()).collect();
        Ok((g0 - g_both(inp, &rest)?) / g0)
    };
    let v = |name: &str| col(name).map(|j| x[j]);
    let r = inp.radius;
    let servo_lag = v("servo").map(|c| -2.0 * c);
    let servo_mismatch = match (servo_lag, inp.feed) {
        (Some(l), Some(f)) => Some(l / (f / 60.0)),
        _ => None,
    };
    let backlash = [
        [v("backlash_1_ccw"), v("backlash_1_cw")],
        [v("backlash_2_ccw"), v("backlash_2_cw")],
    ];
    let cyclic = pitch.map(|_| {
        let amp = |s: &str, c: &str| v(s).unwrap_or(0.0).hypot(v(c).unwrap_or(0.0));
        [amp("cyclic_1s", "cyclic_1c"), amp("cyclic_2s", "cyclic_2c")]
    });
    let cyclic_fraction = match pitch {
        Some(_) => Some([share(&["cyclic_1s", "cyclic_1c"])?, share(&["cyclic_2s", "cyclic_2c"])?]),
        None => None,
    };
    let residual: Vec<f64> = (0..n).map(|i| inp.deviations[i] - (0..k).map(|j| a[i * k + j] * x[j]).sum::<f64>()).collect();
    Ok(BallbarAnalysis {
        hysteresis,
        radius_term: v("radius").unwrap_or(0.0),
        squareness: 2.0 * v("squareness").unwrap_or(0.0) / r,
        squareness_fraction: share(&["squareness"])?,
        scale_mismatch: 2.0 * v("scale").unwrap_or(0.0) / r,
        scale_fraction: share(&["scale"])?,
        servo_lag,
        servo_mismatch,
        servo_fraction: if servo_lag.is_some() { Some(share(&["servo"])?) } else { None },
        backlash,
        backlash_fraction: [share(&["backlash_1_ccw", "backlash_1_cw"])?, share(&["backlash_2_ccw", "backlash_2_cw"])?],
        centre_fraction: share(&["centre_x_ccw", "centre_y_ccw", "centre_x_cw", "centre_y_cw"])?,
        cyclic,
        cyclic_fraction,
        pitch,
        spikes: spikes(inp, &residual),
        residual_rms: (rss / n as f64).sqrt(),
        both,
        ccw,
        cw,
        f_max,
        f_min,
    })
}

/// H: the largest radial difference of the two paths at the same angle (cw interpolated
/// linearly, periodically, at each ccw angle), about the common centre.
fn hysteresis(radius: f64, c: [f64; 2], a_ccw: &[f64], d_ccw: &[f64], a_cw: &[f64], d_cw: &[f64]) -> f64 {
    let mut cw: Vec<(f64, f64)> = a_cw
        .iter()
        .zip(d_cw)
        .map(|(&t, &d)| (t.rem_euclid(2.0 * PI), radial(radius, d, [t.cos(), t.sin()], c)))
        .collect();
    cw.sort_by(|a, b| a.0.total_cmp(&b.0));
    let m = cw.len();
    let at = |t: f64| -> f64 {
        let k = cw.partition_point(|p| p.0 < t);
        let (t0, v0, t1, v1) = if k == 0 {
            (cw[m - 1].0 - 2.0 * PI, cw[m - 1].1, cw[0].0, cw[0].1)
        } else if k == m {
            (cw[m - 1].0, cw[m - 1].1, cw[0].0 + 2.0 * PI, cw[0].1)
        } else {
            (cw[k - 1].0, cw[k - 1].1, cw[k].0, cw[k].1)
        };
        if t1 - t0 <= 0.0 {
            return v1;
        }
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    };
    a_ccw
        .iter()
        .zip(d_ccw)
        .map(|(&t, &d)| {
            let tw = t.rem_euclid(2.0 * PI);
            (radial(radius, d, [t.cos(), t.sin()], c) - at(tw)).abs()
        })
        .fold(0.0, f64::max)
}

/// Reversal spikes: per axis and end, the residual of largest magnitude within the window
/// around the reversal angle (axis 1: 0 and 180 deg, axis 2: 90 and 270 deg) minus the
/// median residual outside every window.
fn spikes(inp: &BallbarInput, residual: &[f64]) -> [[f64; 2]; 2] {
    let window = 3.0f64.to_radians();
    let centres = [[0.0, PI], [0.5 * PI, 1.5 * PI]];
    let dist = |t: f64, c: f64| {
        let d = (t - c).rem_euclid(2.0 * PI);
        d.min(2.0 * PI - d)
    };
    let mut outside: Vec<f64> = (0..residual.len())
        .filter(|&i| centres.iter().flatten().all(|&c| dist(inp.angles[i], c) > window))
        .map(|i| residual[i])
        .collect();
    outside.sort_by(|a, b| a.total_cmp(b));
    let median = if outside.is_empty() { 0.0 } else { outside[outside.len() / 2] };
    let mut out = [[0.0; 2]; 2];
    for ax in 0..2 {
        for end in 0..2 {
            let mut best = 0.0f64;
            for i in 0..residual.len() {
                if dist(inp.angles[i], centres[ax][end]) <= window {
                    let v = residual[i] - median;
                    if v.abs() > best.abs() {
                        best = v;
                    }
                }
            }
            out[ax][end] = best;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(radius: f64, n: usize, f: impl Fn(f64, f64) -> f64) -> (Vec<f64>, Vec<f64>, Vec<i8>) {
        let mut a = Vec::new();
        let mut d = Vec::new();
        let mut s = Vec::new();
        for dir in [1i8, -1] {
            for i in 0..n {
                let t = 2.0 * PI * i as f64 / n as f64;
                a.push(t);
                d.push(f(t, dir as f64));
                s.push(dir);
            }
        }
        let _ = radius;
        (a, d, s)
    }

    #[test]
    fn offset_circle_has_no_circular_deviation() {
        // a perfect circle whose centre is off the pivot by (3, -2) um: exact radial readings
        let r = 150.0;
        let c = [0.003, -0.002];
        let (a, d, s) = run(r, 360, |t, _| {
            // the distance from the pivot of the point of the circle at direction t
            let (sn, cs) = t.sin_cos();
            let b = cs * c[0] + sn * c[1];
            b + (b * b - (c[0] * c[0] + c[1] * c[1]) + r * r).sqrt() - r
        });
        let fit = circle_fit(r, &a, &d).unwrap();
        assert!(fit.g < 1e-13, "G {}", fit.g);
        assert!((fit.centre[0] - c[0]).abs() < 1e-15 && (fit.centre[1] - c[1]).abs() < 1e-15);
        let res = analyse(&BallbarInput { radius: r, angles: &a, deviations: &d, directions: &s, pitch: None, feed: None }).unwrap();
        assert!(res.hysteresis.unwrap() < 1e-13);
    }

    #[test]
    fn terms_come_back() {
        let r = 100.0;
        let (sq, sc, bl, lag) = (20e-6, -15e-6, 0.004, 0.0008);
        let (a, d, s) = run(r, 720, |t, s| {
            let (sn, cs) = t.sin_cos();
            0.5 * r * sq * (2.0 * t).sin() + 0.5 * r * sc * (2.0 * t).cos() + 0.5 * bl * s * sgn(sn) * cs
                - 0.5 * lag * s * (2.0 * t).sin()
        });
        let res = analyse(&BallbarInput { radius: r, angles: &a, deviations: &d, directions: &s, pitch: None, feed: Some(1000.0) })
            .unwrap();
        assert!((res.squareness - sq).abs() < 1e-9 * sq.abs().max(1.0));
        assert!((res.scale_mismatch - sc).abs() < 1e-12);
        assert!((res.backlash[0][0].unwrap() - bl).abs() < 1e-12 && (res.backlash[0][1].unwrap() - bl).abs() < 1e-12);
        assert!(res.backlash[1][0].unwrap().abs() < 1e-12);
        assert!((res.servo_lag.unwrap() - lag).abs() < 1e-12);
        assert!((res.servo_mismatch.unwrap() - lag / (1000.0 / 60.0)).abs() < 1e-12);
        assert!(res.squareness_fraction > 0.0 && res.squareness_fraction <= 1.0);
    }

    #[test]
    fn bad_input_is_refused() {
        let a = [0.0, 1.0, 2.0];
        let d = [0.0, f64::NAN, 0.0];
        let s = [1i8, 1, 1];
        let inp = BallbarInput { radius: 100.0, angles: &a, deviations: &d, directions: &s, pitch: None, feed: None };
        assert!(analyse(&inp).is_err());
        let d = [0.0, 0.0, 0.0];
        let inp = BallbarInput { radius: -1.0, angles: &a, deviations: &d, directions: &s, pitch: None, feed: None };
        assert!(analyse(&inp).is_err());
    }
}
