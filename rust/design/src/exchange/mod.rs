//! Point-exchange search over a candidate set (Fedorov exchange, Sec. 4.1-4.2):
//! minimise a criterion of M^T M (D: Eq. 4.3, A: Eq. 4.4, K: Eq. 4.5, plus E and I)
//! over the design points (Eq. 4.7).
//!
//! A design is n candidate indices (repeats allowed); design point i may only
//! take candidates of its group (its zone, Eq. 4.8). Each start builds a
//! randomised greedy D-optimal design, then sweeps over the points in random
//! order and moves each to the allowed candidate that improves the criterion most.
//! From that local optimum a few rounds of iterated local search follow (D, I, K, E; see
//! `polish_rounds`): a tenth of the points jump to random candidates of their zones, the
//! sweeps run again, and the result is kept only when it is better (so a start never ends
//! worse than its first local optimum).
//!
//! Exchanging block O for block B is the rank-2r update F' = F + U C U^T with
//! U = [B^T O^T] and C = diag(I, -I). With S = C + U^T F^-1 U (2r x 2r):
//! det F' / det F = (-1)^r det S and tr(W F'^-1) = tr(W F^-1) - tr(S^-1 U^T F^-1 W F^-1 U),
//! so A, D and I are exact from the per-candidate r x r blocks B F^-1 B^T and
//! B F^-1 W F^-1 B^T, which are kept current by the same update (recomputed exactly
//! after every REFRESH_AFTER exchanges). Candidates whose improvement bound cannot beat
//! the tolerance are skipped before the exact value. K and E have no such formula:
//! candidates are screened by first-order perturbation of the extreme eigenvalues and
//! the best few evaluated exactly.
//!
//! Speed: the candidates' products run eight candidates per group of SIMD lanes
//! (`lanes.rs`, AVX-512) from a copy of the blocks regrouped by eight that leaves out the
//! columns zero for every candidate (the block updates and the K/E screening stream it; the
//! A/I visits gather the few kept candidates into it), with the same fused operations in
//! the same order as the one-candidate code, so the search takes the same path either way;
//! without AVX-512, a row kernel (AVX2) and the one-candidate code do the same work.


mod local_search;
mod problem;
mod products;
mod run;
mod values;
mod visit;

use crate::criteria::{information, metrics, Criterion, Metrics};
use crate::dense::{
    dot, gram_add, lu_in_place, lu_inverse, mul_ab, mul_abt, skinny_mul, small_spd_inverse,
    small_spd_trace_solves, spd_inverse, sym_eig, sym_eigenvalues, MAX_P, MAX_R,
};
use crate::lanes::{
    best_exchange, bound_terms, exchange_values, rank_update, soa_kernel, soa_screen, soa_update,
    ExchangeIn, RankUpdate, Screen, Soa, LANES,
};
use gagekit_core::{interrupt, GkError, Result};
use rand::seq::{index::sample, SliceRandom};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use local_search::{greedy_start, polish_rounds};
use products::*;
use run::{Removal, Run, Scratch};
use values::*;


/// The design problem: stacked candidate blocks and the zone structure.
#[derive(Debug, Clone)]
pub struct Problem<'a> {
    /// Candidate blocks, (n_cand, r, k) row-major: the design-matrix rows each candidate adds.
    pub blocks: &'a [f64],
    pub n_cand: usize,
    /// Rows per design point (3 for a tracker point).
    pub r: usize,
    /// Model parameters (columns of M).
    pub k: usize,
    /// Allowed candidates of each group (zone).
    pub groups: Vec<Vec<usize>>,
    /// Group of each design point; its length is the number of points n.
    pub point_group: Vec<usize>,
    /// W (k x k, row-major) for the I criterion.
    pub weights: Option<&'a [f64]>,
}

/// Search settings.
#[derive(Debug, Clone)]
pub struct Options {
    pub criterion: Criterion,
    /// Independent random starts (run in parallel).
    pub starts: usize,
    /// Upper bound on exchange sweeps per start.
    pub max_sweeps: usize,
    pub seed: u64,
    /// Start from this design instead of random starts (a single start).
    pub initial: Option<Vec<usize>>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            criterion: Criterion::D,
            starts: 8,
            max_sweeps: 50,
            seed: 0,
            initial: None,
        }
    }
}

/// The best design found.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Candidate index of each design point.
    pub design: Vec<usize>,
    pub metrics: Metrics,
    /// The criterion value of `design` (exact, Metrics::objective).
    pub objective: f64,
    /// The objective reached by each start.
    pub start_objectives: Vec<f64>,
    /// Exchanges made by the best start.
    pub exchanges: usize,
}

/// Candidates screened exactly per visit for K and E.
const EXACT_TOP: usize = 32;
/// Candidates whose improvement bounds one task checks.
const BOUND_CHUNK: usize = 4096;
/// Candidates evaluated together between checks of the improvement bound.
const PRUNE_CHUNK: usize = 512;
/// Low-rank updates of the per-candidate blocks before they are recomputed exactly.
const REFRESH_AFTER: usize = 40;
/// Points moved per perturbation of the iterated local search: n / this.
const PERTURB_FRACTION: usize = 10;


/// An initial design has one candidate per point, each inside its point's zone.
fn check_initial(p: &Problem, o: &Options) -> Result<()> {
    if let Some(init) = &o.initial {
        if init.len() != p.n() {
            return Err(GkError::invalid(format!(
                "the initial design has {} points, expected {}",
                init.len(),
                p.n()
            )));
        }
        for (i, &j) in init.iter().enumerate() {
            if !p.groups[p.point_group[i]].contains(&j) {
                return Err(GkError::invalid(format!(
                    "initial point {i} (candidate {j}) is outside its zone"
                )));
            }
        }
    }
    Ok(())
}

/// Multistart exchange search (Eqs. 4.7, 4.8). Deterministic for a seed: each
/// start has its own ChaCha stream, and ties break on the lowest index.
pub fn search(p: &Problem, o: &Options) -> Result<Outcome> {
    let c = o.criterion;
    p.validate(c)?;
    let scale = p.pooled()?;
    let ridge = 1e-11 * scale;
    check_initial(p, o)?;
    let starts = if o.initial.is_some() {
        1
    } else {
        o.starts.max(1)
    };
    // the lane kernels' layout of the blocks, shared by the starts (A, D, I update the
    // per-candidate blocks with it)
    let soa = if soa_kernel(p.r, 2 * p.r) {
        Soa::new(p.blocks, p.n_cand, p.r, p.k)
    } else {
        Soa::default()
    };
    let run_start = |s: usize| -> Result<(Vec<usize>, usize)> {
        let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
        rng.set_stream(s as u64);
        let mut moves = 0;
        let design = match &o.initial {
            Some(d) => d.clone(),
            None => {
                let d = greedy_start(p, 1e-6 * scale, &mut rng);
                if matches!(c, Criterion::A | Criterion::I) {
                    // A- and I-optimal designs are usually close to the D-optimal one,
                    // whose exchanges are much cheaper: polish that instead.
                    let mut pre = Run::new(p, &soa, Criterion::D, ridge, d)?;
                    moves += pre.optimise(o.max_sweeps.max(1), &mut rng);
                    pre.design
                } else {
                    d
                }
            }
        };
        let mut run = Run::new(p, &soa, c, ridge, design)?;
        moves += run.optimise(o.max_sweeps.max(1), &mut rng);
        if o.initial.is_none() {
            moves += run.perturb_and_polish(polish_rounds(c), o.max_sweeps.max(1), &mut rng);
        }
        Ok((run.design, moves))
    };
    // With at least as many starts as threads, the starts are the parallelism: each runs
    // its inner loops on a pool of its own single thread (nested fine-grained tasks cost
    // more than they give). The result does not depend on this (fixed-order reductions).
    let solo = starts >= 2 && rayon::current_num_threads() >= 2;
    let one_start = |s: usize| -> Result<(Vec<usize>, usize)> {
        if solo {
            if let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                return pool.install(|| run_start(s));
            }
        }
        run_start(s)
    };
    let runs: Vec<Result<(Vec<usize>, usize)>> =
        (0..starts).into_par_iter().map(one_start).collect();
    interrupt::check()?;
    let mut best: Option<(f64, usize, Vec<usize>, Metrics, usize)> = None;
    let mut start_objectives = Vec::with_capacity(starts);
    for (s, res) in runs.into_iter().enumerate() {
        let (design, moves) = res?;
        let m = metrics(&information(p.blocks, &design, p.r, p.k), p.k, p.weights);
        let v = sane(m.objective(c));
        start_objectives.push(v);
        if best.as_ref().is_none_or(|b| v < b.0) {
            best = Some((v, s, design, m, moves));
        }
    }
    let (objective, _, design, metrics, exchanges) = best.expect("at least one start");
    if metrics.rank < p.k {
        return Err(GkError::degenerate(format!(
            "no plan of {} points found that identifies all {} parameters (rank {}); \
             use more points or widen the zones",
            p.n(),
            p.k,
            metrics.rank
        )));
    }
    Ok(Outcome {
        design,
        metrics,
        objective,
        start_objectives,
        exchanges,
    })
}
