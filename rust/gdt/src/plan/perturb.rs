//! The measurement model's simulated measurement of a point set (JCGM 101:2008 Sec. 5 and
//! 6.4: the input quantities' distributions), drawn by one generator per trial.
//!
//! Every draw of trial `i` comes from a ChaCha8 generator keyed by (seed, i) alone, so a
//! trial's perturbation is the same on any number of threads and in any order. Normal
//! deviates by the ziggurat method of `rand_distr::StandardNormal` (256 layers: a deviate
//! from one 64-bit output of the generator, a table look-up and a multiplication in about
//! 99 % of the draws; the Marsaglia polar method before needed 2.5 outputs, a logarithm
//! and a square root a pair), uniform ones by the generator's `f64`.

use crate::vec3::V3;
use gagekit_core::{GkError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// An instrument's error model (`gagekit.uncertainty.model.MeasurementModel`); lengths mm.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Per-point noise: each coordinate N(0, sigma^2), or along the line of sight from
    /// `origin` with s(r) = sigma + sigma_per_m * r / 1000.
    pub sigma: f64,
    pub origin: Option<V3>,
    pub sigma_per_m: f64,
    /// P_FTU (ISO 10360-5): a uniform amount in [-P/2, P/2] along a random direction.
    pub probing: f64,
    /// Half-width of the uniform relative scale error about the origin (or (0, 0, 0)).
    pub relative_scale: f64,
    /// Standard uncertainty of one systematic offset per measurement.
    pub offset: f64,
}

impl Model {
    /// Check the model: finite non-negative numbers, range noise only with an origin.
    pub fn checked(self) -> Result<Self> {
        let nums = [self.sigma, self.sigma_per_m, self.probing, self.relative_scale, self.offset];
        if !nums.iter().all(|v| v.is_finite() && *v >= 0.0) || self.origin.is_some_and(|o| !o.iter().all(|v| v.is_finite())) {
            return Err(GkError::invalid("measurement model: every term must be a finite number >= 0"));
        }
        if self.sigma_per_m > 0.0 && self.origin.is_none() {
            return Err(GkError::config("measurement model: sigma_per_m (range-dependent noise) needs the scanner's origin"));
        }
        Ok(self)
    }
}

/// The generator of trial `trial` of the simulation seeded `seed`.
pub fn trial_rng(seed: u64, trial: u64) -> ChaCha8Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&trial.to_le_bytes());
    key[16..32].copy_from_slice(b"gagekit trial   ");
    ChaCha8Rng::from_seed(key)
}

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// One simulated measurement of the flat (n, `dim`) points (`dim` 2 or 3; the line of
/// sight needs 3): a new buffer. Draw order: the per-point noise, the probing error, the
/// offset, the scale error.
pub fn perturb(pts: &[f64], dim: usize, model: &Model, seed: u64, trial: u64) -> Result<Vec<f64>> {
    if !(dim == 2 || dim == 3) || pts.len() % dim != 0 {
        return Err(GkError::invalid(format!("measurement model: points must be (n, 2) or (n, 3), got dimension {dim}")));
    }
    if model.origin.is_some() && dim != 3 {
        return Err(GkError::invalid(format!("measurement model: a scanner origin needs 3-D points, got {dim}-D")));
    }
    let mut rng = trial_rng(seed, trial);
    let normal = |rng: &mut ChaCha8Rng| -> f64 { rng.sample(StandardNormal) };
    let mut out = pts.to_vec();
    let n = pts.len() / dim;
    let centre = model.origin.unwrap_or([0.0; 3]);
    let los = |i: usize| -> (V3, f64) {
        let q = [pts[3 * i] - centre[0], pts[3 * i + 1] - centre[1], pts[3 * i + 2] - centre[2]];
        let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        let s = if r > 0.0 { r } else { 1.0 };
        ([q[0] / s, q[1] / s, q[2] / s], r)
    };
    if model.sigma > 0.0 || model.sigma_per_m > 0.0 {
        if model.origin.is_none() {
            for x in out.iter_mut() {
                *x += normal(&mut rng) * model.sigma;
            }
        } else {
            for i in 0..n {
                let (l, r) = los(i);
                let e = normal(&mut rng) * (model.sigma + model.sigma_per_m * r / 1000.0);
                for k in 0..3 {
                    out[3 * i + k] += l[k] * e;
                }
            }
        }
    }
    if model.probing > 0.0 {
        for p in out.chunks_exact_mut(dim) {
            let mut d = [0.0; 3];
            for dk in d.iter_mut().take(dim) {
                *dk = normal(&mut rng);
            }
            let m = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            let a = uniform(&mut rng, -0.5 * model.probing, 0.5 * model.probing);
            if m > 0.0 {
                for k in 0..dim {
                    p[k] += d[k] / m * a;
                }
            }
        }
    }
    if model.offset > 0.0 {
        if model.origin.is_none() {
            let mut t = [0.0; 3];
            for tk in t.iter_mut().take(dim) {
                *tk = normal(&mut rng) * model.offset;
            }
            for p in out.chunks_exact_mut(dim) {
                for k in 0..dim {
                    p[k] += t[k];
                }
            }
        } else {
            let e = normal(&mut rng) * model.offset;
            for i in 0..n {
                let (l, _) = los(i);
                for k in 0..3 {
                    out[3 * i + k] += l[k] * e;
                }
            }
        }
    }
    if model.relative_scale > 0.0 {
        let s = 1.0 + uniform(&mut rng, -model.relative_scale, model.relative_scale);
        for p in out.chunks_exact_mut(dim) {
            for k in 0..dim {
                p[k] = centre[k] + (p[k] - centre[k]) * s;
            }
        }
    }
    Ok(out)
}
