//! The measurement model's simulated measurement of a point set (JCGM 101:2008 Sec. 5 and
//! 6.4: the input quantities' distributions), drawn by one generator per trial.
//!
//! Every draw of trial `i` comes from one generator whose state depends on (seed, i) alone,
//! so a trial's perturbation is the same on any number of threads and in any order: a
//! xoshiro256++ generator (Blackman and Vigna, "Scrambled linear pseudorandom number
//! generators", ACM TOMS 47(4), 2021; `rand_xoshiro`; 256 bits of state, period 2^256 - 1,
//! passes BigCrush and PractRand; about 1.4 ns an output here against 2.7 ns for ChaCha8),
//! its state the first 256 bits of the ChaCha8 stream keyed by (seed, i) (the generator of
//! the trials before: a keyed hash, so distinct trials start from unrelated states: any two of the
//! 10,000 trials of a run, 10^8 outputs each, overlap with a probability below 10^-60). Normal
//! deviates by the ziggurat method of `rand_distr::StandardNormal` (256 layers: a deviate
//! from one 64-bit output of the generator, a table look-up and a multiplication in about
//! 99 % of the draws; the Marsaglia polar method before needed 2.5 outputs, a logarithm
//! and a square root a pair), uniform ones by the generator's `f64`. The ziggurat's common
//! case is inlined into the perturbation's loop ([`normal`], the same deviates as
//! `rand_distr` bit for bit): about 3.4 ns a deviate against 4.6 ns for the call a deviate.

use crate::vec3::V3;
use gagekit_core::{GkError, Result};
use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// The generator of a trial.
pub type TrialRng = Xoshiro256PlusPlus;

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

/// The generator of trial `trial` of the simulation seeded `seed`: xoshiro256++ started
/// from the first 32 bytes of the ChaCha8 stream keyed by (seed, trial) (module docs; an
/// all-zero state, probability 2^-256, is replaced by `rand_xoshiro`'s fixed non-zero one).
pub fn trial_rng(seed: u64, trial: u64) -> TrialRng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&trial.to_le_bytes());
    key[16..32].copy_from_slice(b"gagekit trial   ");
    let mut state = [0u8; 32];
    ChaCha8Rng::from_seed(key).fill_bytes(&mut state);
    Xoshiro256PlusPlus::from_seed(state)
}

/// A standard normal deviate: the ziggurat of `rand_distr::StandardNormal` (its tables,
/// [`super::ziggurat`]; its steps in its order, so the same deviates from the same outputs
/// of the generator), with the common case (one output, a look-up, a multiplication and a
/// comparison, about 99 % of the draws) inlined into the caller's loop and the rest out of
/// line: `rand_distr`'s `sample` is a call a deviate.
#[inline(always)]
pub fn normal(rng: &mut TrialRng) -> f64 {
    use super::ziggurat::ZIG_NORM_X as X;
    let bits = rng.next_u64();
    let i = bits as usize & 0xff;
    // (bits >> 12) as the fraction of a float in [2, 4), minus 3: [-1, 1)
    let u = f64::from_bits((1024u64 << 52) | (bits >> 12)) - 3.0;
    let x = u * X[i];
    if x.abs() < X[i + 1] {
        return x;
    }
    normal_slow(rng, i, u, x)
}

/// The rest of the ziggurat's first draw (layer `i`, `u`, `x` = u X[i] outside the layer's
/// rectangle), then whole draws until one is accepted, as `rand_distr` 0.5.1 `ziggurat`.
#[cold]
#[inline(never)]
fn normal_slow(rng: &mut TrialRng, mut i: usize, mut u: f64, mut x: f64) -> f64 {
    use super::ziggurat::{ZIG_NORM_F as F, ZIG_NORM_R as R, ZIG_NORM_X as X};
    loop {
        if i == 0 {
            // the tail beyond R (Marsaglia 1964)
            let (mut tx, mut ty) = (1.0f64, 0.0f64);
            while -2.0 * ty < tx * tx {
                let a: f64 = rng.sample(rand::distr::Open01);
                let b: f64 = rng.sample(rand::distr::Open01);
                tx = a.ln() / R;
                ty = b.ln();
            }
            return if u < 0.0 { tx - R } else { R - tx };
        }
        if F[i + 1] + (F[i] - F[i + 1]) * rng.random::<f64>() < (-x * x / 2.0).exp() {
            return x;
        }
        let bits = rng.next_u64();
        i = bits as usize & 0xff;
        u = f64::from_bits((1024u64 << 52) | (bits >> 12)) - 3.0;
        x = u * X[i];
        if x.abs() < X[i + 1] {
            return x;
        }
    }
}

fn uniform(rng: &mut TrialRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// Where a perturbation writes the points: [`each`](Sink::each) visits every point in
/// order with its current coordinates (`dim` of them), or with the input's when `init`, and
/// stores what the visit leaves.
pub trait Sink {
    fn each(&mut self, init: bool, f: impl FnMut(usize, &mut [f64]));
}

/// A flat (n, `dim`) copy of the points.
struct Flat {
    dim: usize,
    out: Vec<f64>,
}

impl Sink for Flat {
    fn each(&mut self, init: bool, mut f: impl FnMut(usize, &mut [f64])) {
        let dim = self.dim;
        let _ = init; // `out` starts as a copy of the points
        for (i, p) in self.out.chunks_exact_mut(dim).enumerate() {
            f(i, p);
        }
    }
}

/// The rows of each feature of a plan in the active points, as runs: the active points
/// `a..b` of a segment go to `dests` (feature, position of point `a` in its buffer). Built
/// once per block of trials; a trial's perturbation then writes each feature's points
/// directly ([`perturb_features`]), with no perturbed copy of the active set.
#[derive(Debug, Clone)]
pub struct Scatter {
    n: usize,
    sizes: Vec<usize>,
    segs: Vec<(usize, usize, usize, usize)>,
    dests: Vec<(usize, usize)>,
}

impl Scatter {
    /// The runs of `rows` (each feature's rows, every row < `n`).
    pub fn new(n: usize, rows: &[&[usize]]) -> Scatter {
        // maximal runs (active a, length, feature, position): consecutive rows at consecutive positions
        let mut runs: Vec<(usize, usize, usize, usize)> = Vec::new();
        for (f, r) in rows.iter().enumerate() {
            let mut k = 0;
            while k < r.len() {
                let mut len = 1;
                while k + len < r.len() && r[k + len] == r[k] + len {
                    len += 1;
                }
                runs.push((r[k], len, f, k));
                k += len;
            }
        }
        let mut cuts: Vec<usize> = runs.iter().flat_map(|&(a, len, _, _)| [a, a + len]).chain([0, n]).collect();
        cuts.sort_unstable();
        cuts.dedup();
        let mut lists: Vec<Vec<(usize, usize)>> = vec![Vec::new(); cuts.len() - 1];
        for &(a, len, f, pos) in &runs {
            let mut j = cuts.partition_point(|&c| c < a);
            while cuts[j] < a + len {
                lists[j].push((f, pos + cuts[j] - a));
                j += 1;
            }
        }
        let mut segs = Vec::with_capacity(lists.len());
        let mut dests = Vec::new();
        for (j, l) in lists.into_iter().enumerate() {
            segs.push((cuts[j], cuts[j + 1], dests.len(), dests.len() + l.len()));
            dests.extend(l);
        }
        Scatter { n, sizes: rows.iter().map(|r| r.len()).collect(), segs, dests }
    }
}

/// The feature buffers of one trial, written through a [`Scatter`].
struct Features<'a> {
    pts: &'a [f64],
    map: &'a Scatter,
    bufs: Vec<Vec<f64>>,
}

impl Sink for Features<'_> {
    fn each(&mut self, init: bool, mut f: impl FnMut(usize, &mut [f64])) {
        for &(a, b, d0, d1) in &self.map.segs {
            let dests = &self.map.dests[d0..d1];
            for i in a..b {
                let mut p = [0.0; 3];
                match dests.first() {
                    Some(&(k, pos)) if !init => p.copy_from_slice(&self.bufs[k][3 * (pos + i - a)..][..3]),
                    _ => p.copy_from_slice(&self.pts[3 * i..3 * i + 3]),
                }
                f(i, &mut p);
                for &(k, pos) in dests {
                    self.bufs[k][3 * (pos + i - a)..][..3].copy_from_slice(&p);
                }
            }
        }
    }
}

fn check_dim(pts: &[f64], dim: usize, model: &Model) -> Result<()> {
    if !(dim == 2 || dim == 3) || pts.len() % dim != 0 {
        return Err(GkError::invalid(format!("measurement model: points must be (n, 2) or (n, 3), got dimension {dim}")));
    }
    if model.origin.is_some() && dim != 3 {
        return Err(GkError::invalid(format!("measurement model: a scanner origin needs 3-D points, got {dim}-D")));
    }
    Ok(())
}

/// One simulated measurement of the flat (n, `dim`) points (`dim` 2 or 3; the line of
/// sight needs 3): a new buffer. Draw order: the per-point noise, the probing error, the
/// offset, the scale error.
pub fn perturb(pts: &[f64], dim: usize, model: &Model, seed: u64, trial: u64) -> Result<Vec<f64>> {
    check_dim(pts, dim, model)?;
    let mut sink = Flat { dim, out: pts.to_vec() };
    apply(&mut sink, pts, dim, model, seed, trial);
    Ok(sink.out)
}

/// [`perturb`] of the flat (n, 3) active points `pts`, written straight into each
/// feature's buffer by `map` (built from the same `n`): buffer `k` holds the perturbed
/// points of feature `k`'s rows, the values [`perturb`] gives them bit for bit (the same
/// draws in the same order, the same operations on each point).
pub fn perturb_features(pts: &[f64], map: &Scatter, model: &Model, seed: u64, trial: u64) -> Result<Vec<Vec<f64>>> {
    check_dim(pts, 3, model)?;
    if pts.len() != 3 * map.n {
        return Err(GkError::invalid("measurement model: the points are not those of the feature map"));
    }
    let bufs = map.sizes.iter().map(|&m| vec![0.0; 3 * m]).collect();
    let mut sink = Features { pts, map, bufs };
    apply(&mut sink, pts, 3, model, seed, trial);
    Ok(sink.bufs)
}

/// The model's steps on `sink`, whose points start as `pts`; the first step writes them
/// from `pts` (`init`), so each point is read and written once when only noise is drawn.
fn apply(sink: &mut impl Sink, pts: &[f64], dim: usize, model: &Model, seed: u64, trial: u64) {
    let mut rng = trial_rng(seed, trial);
        let centre = model.origin.unwrap_or([0.0; 3]);
    let los = |i: usize| -> (V3, f64) {
        let q = [pts[3 * i] - centre[0], pts[3 * i + 1] - centre[1], pts[3 * i + 2] - centre[2]];
        let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        let s = if r > 0.0 { r } else { 1.0 };
        ([q[0] / s, q[1] / s, q[2] / s], r)
    };
    let mut init = true;
    if model.sigma > 0.0 || model.sigma_per_m > 0.0 {
        if model.origin.is_none() {
            sink.each(init, |_, p| {
                for x in p.iter_mut() {
                    *x += normal(&mut rng) * model.sigma;
                }
            });
        } else {
            sink.each(init, |i, p| {
                let (l, r) = los(i);
                let e = normal(&mut rng) * (model.sigma + model.sigma_per_m * r / 1000.0);
                for k in 0..3 {
                    p[k] += l[k] * e;
                }
            });
        }
        init = false;
    }
    if model.probing > 0.0 {
        sink.each(init, |_, p| {
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
        });
        init = false;
    }
    if model.offset > 0.0 {
        if model.origin.is_none() {
            let mut t = [0.0; 3];
            for tk in t.iter_mut().take(dim) {
                *tk = normal(&mut rng) * model.offset;
            }
            sink.each(init, |_, p| {
                for k in 0..dim {
                    p[k] += t[k];
                }
            });
        } else {
            let e = normal(&mut rng) * model.offset;
            sink.each(init, |i, p| {
                let (l, _) = los(i);
                for k in 0..3 {
                    p[k] += l[k] * e;
                }
            });
        }
        init = false;
    }
    if model.relative_scale > 0.0 {
        let s = 1.0 + uniform(&mut rng, -model.relative_scale, model.relative_scale);
        sink.each(init, |_, p| {
            for k in 0..dim {
                p[k] = centre[k] + (p[k] - centre[k]) * s;
            }
        });
        init = false;
    }
    if init {
        sink.each(true, |_, _| {});
    }
}

