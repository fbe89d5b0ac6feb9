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

/// Perturb-and-polish rounds after a start's local optimum (see [`Run::perturb_and_polish`]).
fn polish_rounds(c: Criterion) -> usize {
    // by the cost of a re-optimisation (D and I are cheap, K and E dear); A keeps its
    // time for the main search, whose result already beats a plain exchange's
    match c {
        Criterion::D | Criterion::I => 6,
        Criterion::K | Criterion::E => 1,
        Criterion::A => 0,
    }
}

/// Candidates sampled per point when building a greedy start.
const GREEDY_SAMPLE: usize = 64;

impl Problem<'_> {
    fn n(&self) -> usize {
        self.point_group.len()
    }

    fn block(&self, j: usize) -> &[f64] {
        let sz = self.r * self.k;
        &self.blocks[j * sz..(j + 1) * sz]
    }

    fn validate(&self, c: Criterion) -> Result<()> {
        let (r, k) = (self.r, self.k);
        if r == 0 || r > MAX_R {
            return Err(GkError::invalid(format!(
                "each design point must give 1 to {MAX_R} rows of the design matrix, got {r}"
            )));
        }
        if k == 0 {
            return Err(GkError::invalid("the model has no parameters (0 columns)"));
        }
        if self.n_cand == 0 {
            return Err(GkError::invalid("no candidate points to design from"));
        }
        if self.blocks.len() != self.n_cand * r * k {
            return Err(GkError::invalid(format!(
                "expected {} x {r} x {k} design-matrix values, got {}",
                self.n_cand,
                self.blocks.len()
            )));
        }
        if let Some(pos) = self.blocks.iter().position(|v| !v.is_finite()) {
            return Err(GkError::invalid(format!(
                "the design-matrix rows of candidate {} contain NaN or inf",
                pos / (r * k)
            )));
        }
        let n = self.n();
        if n == 0 {
            return Err(GkError::invalid("a plan needs at least one point"));
        }
        if n * r < k {
            return Err(GkError::invalid(format!(
                "{n} points give {} equations for {k} parameters: a plan needs at least {} points",
                n * r,
                k.div_ceil(r)
            )));
        }
        for (g, members) in self.groups.iter().enumerate() {
            if members.is_empty() && self.point_group.contains(&g) {
                return Err(GkError::infeasible(format!(
                    "zone {g} contains no candidate point"
                )));
            }
            if let Some(&bad) = members.iter().find(|&&j| j >= self.n_cand) {
                return Err(GkError::invalid(format!(
                    "zone {g} refers to candidate {bad}, but there are only {}",
                    self.n_cand
                )));
            }
        }
        if let Some(&g) = self.point_group.iter().find(|&&g| g >= self.groups.len()) {
            return Err(GkError::invalid(format!(
                "a design point belongs to zone {g}, but there are only {} zones",
                self.groups.len()
            )));
        }
        if c == Criterion::I {
            match self.weights {
                None => return Err(GkError::invalid("the I criterion needs a weight matrix")),
                Some(w) if w.len() != k * k || w.iter().any(|v| !v.is_finite()) => {
                    return Err(GkError::invalid(format!(
                        "the I weight matrix must be {k} x {k} and finite"
                    )))
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Information of all usable candidates: identifiability check and scale.
    fn pooled(&self) -> Result<f64> {
        let mut used = vec![false; self.n_cand];
        for &g in &self.point_group {
            for &j in &self.groups[g] {
                used[j] = true;
            }
        }
        let idx: Vec<usize> = (0..self.n_cand).filter(|&j| used[j]).collect();
        let f = information(self.blocks, &idx, self.r, self.k);
        let m = metrics(&f, self.k, None);
        if m.rank < self.k {
            return Err(GkError::degenerate(format!(
                "the model has {} parameters but only {} independent combinations can be observed \
                 anywhere in the design space; remove dependent columns, rescale badly scaled ones, or widen the bounds",
                self.k, m.rank
            )));
        }
        let tr: f64 = (0..self.k).map(|a| f[a * self.k + a]).sum();
        Ok(tr / idx.len() as f64 * self.n() as f64 / self.k as f64)
    }
}

/// Candidates per blocked matrix product.
const GEMM_CHUNK: usize = 256;

/// Products with at most this many columns use [`skinny_mul`] (a GEMM's packing costs more).
const SKINNY_Q: usize = 24;

/// `out (m x q) = a (m x k) * w (k x q)`, all row-major.
fn gemm(a: &[f64], m: usize, k: usize, w: &[f64], q: usize, out: &mut [f64]) {
    assert!(a.len() >= m * k && w.len() >= k * q && out.len() >= m * q);
    if q <= SKINNY_Q {
        skinny_mul(a, m, k, w, q, out);
        return;
    }
    // SAFETY: the slices hold the m x k, k x q and m x q row-major matrices (checked above).
    unsafe {
        matrixmultiply::dgemm(
            m,
            k,
            q,
            1.0,
            a.as_ptr(),
            k as isize,
            1,
            w.as_ptr(),
            q as isize,
            1,
            0.0,
            out.as_mut_ptr(),
            q as isize,
            1,
        );
    }
}

impl Problem<'_> {
    /// `body(j, B_j W)` for every candidate j of `members` (B_j W is r x q), in
    /// parallel chunks of blocked products; results in the order of `members`.
    fn products<T, F>(&self, members: &[usize], w: &[f64], q: usize, body: F) -> Vec<T>
    where
        T: Send,
        F: Fn(usize, &[f64]) -> T + Sync,
    {
        let (r, k) = (self.r, self.k);
        members
            .par_chunks(GEMM_CHUNK)
            .flat_map_iter(|chunk| {
                let mut out = vec![0.0; chunk.len() * r * q];
                let m = chunk.len() * r;
                let gathered = self.gather(chunk);
                gemm(&gathered, m, k, w, q, &mut out);
                chunk
                    .iter()
                    .enumerate()
                    .map(|(t, &j)| body(j, &out[t * r * q..(t + 1) * r * q]))
                    .collect::<Vec<T>>()
            })
            .collect()
    }
}

impl Problem<'_> {
    /// The stacked blocks of `chunk`: borrowed when the candidates are consecutive,
    /// else copied (prefetching ahead, as scattered candidates live in L3).
    fn gather(&self, chunk: &[usize]) -> std::borrow::Cow<'_, [f64]> {
        let sz = self.r * self.k;
        match (chunk.first(), chunk.last()) {
            (Some(&a), Some(&b))
                if b >= a
                    && b - a + 1 == chunk.len()
                    && chunk.windows(2).all(|x| x[1] == x[0] + 1) =>
            {
                std::borrow::Cow::Borrowed(&self.blocks[a * sz..(b + 1) * sz])
            }
            _ => {
                let mut a = Vec::with_capacity(chunk.len() * sz);
                for (t, &j) in chunk.iter().enumerate() {
                    if let Some(&ahead) = chunk.get(t + PREFETCH_AHEAD) {
                        prefetch(self.block(ahead));
                    }
                    a.extend_from_slice(self.block(j));
                }
                std::borrow::Cow::Owned(a)
            }
        }
    }

    /// `body(chunk, B W)` for chunks of `members` (B W stacks the r x q products of the
    /// chunk's candidates), in parallel; results in chunk order.
    fn products_chunks<T, F>(&self, members: &[usize], w: &[f64], q: usize, body: F) -> Vec<T>
    where
        T: Send,
        F: Fn(&[usize], &[f64]) -> T + Sync,
    {
        let (r, k) = (self.r, self.k);
        members
            .par_chunks(GEMM_CHUNK)
            .map(|chunk| {
                let mut out = vec![0.0; chunk.len() * r * q];
                skinny_mul(&self.gather(chunk), chunk.len() * r, k, w, q, &mut out);
                body(chunk, &out)
            })
            .collect()
    }
}

/// Candidates ahead whose blocks are prefetched when gathering scattered candidates.
const PREFETCH_AHEAD: usize = 6;

/// Hint the processor to bring `x` into cache (scattered candidate blocks live in L3).
#[inline(always)]
fn prefetch(x: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for line in x.chunks(8) {
        // SAFETY: a prefetch hint has no effect on memory; the address is inside `x`.
        unsafe {
            std::arch::x86_64::_mm_prefetch(
                line.as_ptr() as *const i8,
                std::arch::x86_64::_MM_HINT_T0,
            )
        };
    }
}

fn total_min(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    match a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)) {
        std::cmp::Ordering::Greater => b,
        _ => a,
    }
}

fn sane(v: f64) -> f64 {
    if v.is_nan() {
        f64::INFINITY
    } else {
        v
    }
}

/// The R x R product `c m` with `m` row-major (the one-candidate twin of the lanes'
/// `times_matrix`: same operations, same order).
fn times_matrix<const R: usize>(c: &[[f64; R]; R], m: &[f64]) -> [[f64; R]; R] {
    std::array::from_fn(|a| {
        std::array::from_fn(|q| {
            let mut v = 0.0;
            for t in 0..R {
                v += c[a][t] * m[t * R + q];
            }
            v
        })
    })
}

/// Spectral objective from ascending eigenvalues.
fn spectral_value(c: Criterion, lmin: f64, lmax: f64) -> f64 {
    if !(lmin > 0.0) {
        return f64::INFINITY;
    }
    match c {
        Criterion::K => (lmax / lmin).sqrt(),
        _ => 1.0 / lmin,
    }
}

/// [`Run::bound_terms`] of one candidate from its d_j and e_j (r x r).
fn bound_terms_of(dj: &[f64], ej: &[f64], r: usize) -> [f64; 3] {
    let rr = r * r;
    let mut pm = [0.0; MAX_R * MAX_R];
    pm[..rr].copy_from_slice(&dj[..rr]);
    for a in 0..r {
        pm[a * r + a] += 1.0;
    }
    let t: f64 = (0..r).map(|a| dj[a * r + a]).sum::<f64>().max(0.0);
    match small_spd_trace_solves(&pm[..rr], [&ej[..rr], &dj[..rr]], r) {
        Some([a, tau]) => [a.max(0.0).sqrt(), t / (1.0 + t), tau.max(0.0)],
        // not positive definite: no bound, always evaluate exactly
        None => [f64::INFINITY, 1.0, 1.0],
    }
}

/// [`bound_terms_of`] of every candidate of a chunk (d, e: r x r each).
fn bound_terms_chunk(d: &[f64], e: &[f64], bt: &mut [[f64; 3]], r: usize) {
    match r {
        1 => bound_terms::<1>(d, e, bt),
        2 => bound_terms::<2>(d, e, bt),
        3 => bound_terms::<3>(d, e, bt),
        _ => {
            let rr = r * r;
            for (t, b) in bt.iter_mut().enumerate() {
                *b = bound_terms_of(&d[t * rr..(t + 1) * rr], &e[t * rr..(t + 1) * rr], r);
            }
        }
    }
}

/// One start's mutable state.
struct Run<'p, 'a> {
    p: &'p Problem<'a>,
    c: Criterion,
    ridge: f64,
    design: Vec<usize>,
    f: Vec<f64>,
    finv: Vec<f64>,
    /// F^-1 W F^-1 (A: W = I), for A and I.
    fwf: Vec<f64>,
    /// Per candidate r x r: B F^-1 B^T.
    d: Vec<f64>,
    /// Per candidate r x r: B F^-1 W F^-1 B^T (A and I).
    e: Vec<f64>,
    value: f64,
    /// Per candidate (A, I): sqrt(tr((I + d_j)^-1 e_j)), t_j / (1 + t_j) with t_j = tr d_j,
    /// and tr((I + d_j)^-1 d_j),
    /// the two ingredients of the improvement bound, kept with d and e.
    bound_terms: Vec<[f64; 3]>,
    /// The candidate blocks regrouped for the lane kernels; empty: unused.
    soa: &'p Soa,
}

/// The visited point's removal, shared by all candidates of a visit.
struct Removal {
    qi: [f64; MAX_R * MAX_R],
    qeq: [f64; MAX_R * MAX_R],
    value_minus: f64,
    /// Constant of the improvement bound (see [`Run::improvement_bound`]); infinite: no pruning.
    bound_c: f64,
    /// A, I: tr d_O and l_max(d_O) (the two bounds on |L c|_F^2).
    tr_do: f64,
    mu_o: f64,
}

/// Scratch of one candidate evaluation (A, D, I).
struct Scratch {
    c: [f64; MAX_R * MAX_R],
    fx: [f64; MAX_R * MAX_R],
    s: [f64; MAX_P * MAX_P],
    sinv: [f64; MAX_P * MAX_P],
    piv: [usize; MAX_P],
    g: Vec<f64>,
}

impl Scratch {
    fn new() -> Self {
        Self {
            c: [0.0; MAX_R * MAX_R],
            fx: [0.0; MAX_R * MAX_R],
            s: [0.0; MAX_P * MAX_P],
            sinv: [0.0; MAX_P * MAX_P],
            piv: [0; MAX_P],
            g: vec![0.0; MAX_P * MAX_P],
        }
    }
}

impl<'p, 'a> Run<'p, 'a> {
    fn new(
        p: &'p Problem<'a>,
        soa: &'p Soa,
        c: Criterion,
        ridge: f64,
        design: Vec<usize>,
    ) -> Result<Self> {
        let r = p.r;
        let needs_e = matches!(c, Criterion::A | Criterion::I);
        let blocks_d = if c.is_spectral() { 0 } else { p.n_cand * r * r };
        let mut run = Self {
            p,
            c,
            ridge,
            design,
            f: vec![],
            finv: vec![],
            fwf: vec![],
            d: vec![0.0; blocks_d],
            e: vec![0.0; if needs_e { blocks_d } else { 0 }],
            value: f64::INFINITY,
            bound_terms: vec![],
            soa,
        };
        run.recompute()?;
        Ok(run)
    }

    fn needs_e(&self) -> bool {
        matches!(self.c, Criterion::A | Criterion::I)
    }

    /// F, F^-1, F^-1 W F^-1 and the criterion value from the design, exactly.
    fn recompute(&mut self) -> Result<()> {
        let k = self.p.k;
        let mut f = information(self.p.blocks, &self.design, self.p.r, k);
        for a in 0..k {
            f[a * k + a] += self.ridge;
        }
        let (finv, logdet) = spd_inverse(&f, k).ok_or_else(|| {
            GkError::numerical("the information matrix lost positive definiteness")
        })?;
        self.value = match self.c {
            Criterion::A => (0..k).map(|a| finv[a * k + a]).sum(),
            Criterion::D => -logdet,
            Criterion::I => {
                let w = self.p.weights.unwrap_or(&[]);
                (0..k * k).map(|q| w[q] * finv[q]).sum() // tr(W F^-1), both symmetric
            }
            _ => {
                let ev = sym_eigenvalues(&f, k);
                spectral_value(self.c, ev[0], ev[k - 1])
            }
        };
        if self.needs_e() {
            let mut tmp = vec![0.0; k * k];
            match self.p.weights {
                Some(w) if self.c == Criterion::I => mul_ab(w, &finv, k, k, &mut tmp),
                _ => tmp.copy_from_slice(&finv),
            }
            let mut fwf = vec![0.0; k * k];
            mul_ab(&finv, &tmp, k, k, &mut fwf);
            // symmetrise against round-off
            for a in 0..k {
                for b in 0..a {
                    let v = 0.5 * (fwf[a * k + b] + fwf[b * k + a]);
                    fwf[a * k + b] = v;
                    fwf[b * k + a] = v;
                }
            }
            self.fwf = fwf;
        }
        self.f = f;
        self.finv = finv;
        Ok(())
    }

    /// Recompute every candidate's B F^-1 B^T (and B F^-1 W F^-1 B^T) exactly.
    fn refresh(&mut self) {
        let (r, k) = (self.p.r, self.p.k);
        let rr = r * r;
        let needs_e = self.needs_e();
        let q = if needs_e { 2 * k } else { k };
        let mut w = vec![0.0; k * q]; // [F^-1, F^-1 W F^-1]
        for t in 0..k {
            w[t * q..t * q + k].copy_from_slice(&self.finv[t * k..(t + 1) * k]);
            if needs_e {
                w[t * q + k..t * q + 2 * k].copy_from_slice(&self.fwf[t * k..(t + 1) * k]);
            }
        }
        let blocks = self.p.blocks;
        self.for_candidate_products(&w, q, |prod, first, dch, ech, bt| {
            for t in 0..dch.len() / rr {
                let b = &blocks[(first + t) * r * k..(first + t + 1) * r * k];
                let pr = &prod[t * r * q..(t + 1) * r * q];
                for a in 0..r {
                    for c in 0..r {
                        dch[t * rr + a * r + c] =
                            dot(&pr[a * q..a * q + k], &b[c * k..(c + 1) * k]);
                        if needs_e {
                            ech[t * rr + a * r + c] =
                                dot(&pr[a * q + k..a * q + 2 * k], &b[c * k..(c + 1) * k]);
                        }
                    }
                }
            }
            if needs_e {
                bound_terms_chunk(dch, ech, bt, r);
            }
        });
    }

    /// For every chunk of candidates (from `first`), in parallel, with blocked products:
    /// `f(B W (r x q per candidate), first, d, e, bound terms)` (e and the bound terms empty for D).
    fn for_candidate_products<F>(&mut self, w: &[f64], q: usize, f: F)
    where
        F: Fn(&[f64], usize, &mut [f64], &mut [f64], &mut [[f64; 3]]) + Sync,
    {
        let (r, k) = (self.p.r, self.p.k);
        let rr = r * r;
        let sz = r * k;
        let blocks = self.p.blocks;
        self.for_candidate_chunks(|first, dch, ech, bt| {
            let n = dch.len() / rr;
            let mut prod = vec![0.0; n * r * q];
            gemm(
                &blocks[first * sz..(first + n) * sz],
                n * r,
                k,
                w,
                q,
                &mut prod,
            );
            f(&prod, first, dch, ech, bt);
        });
    }

    /// `f(first, d, e, bound terms)` for every chunk of candidates (from `first`), in parallel
    /// (e and the bound terms empty for D).
    fn for_candidate_chunks<F>(&mut self, f: F)
    where
        F: Fn(usize, &mut [f64], &mut [f64], &mut [[f64; 3]]) + Sync,
    {
        let rr = self.p.r * self.p.r;
        let run_chunk = |ci: usize, dch: &mut [f64], ech: &mut [f64], bt: &mut [[f64; 3]]| {
            // Ctrl-C: skip the remaining chunks (the run is abandoned; `search` reports it)
            if !interrupt::requested() {
                f(ci * GEMM_CHUNK, dch, ech, bt)
            }
        };
        if self.needs_e() {
            self.bound_terms.resize(self.p.n_cand, [0.0; 3]);
            self.d
                .par_chunks_mut(rr * GEMM_CHUNK)
                .zip(self.e.par_chunks_mut(rr * GEMM_CHUNK))
                .zip(self.bound_terms.par_chunks_mut(GEMM_CHUNK))
                .enumerate()
                .for_each(|(ci, ((dch, ech), bt))| run_chunk(ci, dch, ech, bt));
        } else {
            self.d
                .par_chunks_mut(rr * GEMM_CHUNK)
                .enumerate()
                .for_each(|(ci, dch)| run_chunk(ci, dch, &mut [], &mut []));
        }
    }

    fn tol(&self) -> f64 {
        match self.c {
            Criterion::D => 1e-10 * (self.value.abs() + 1.0),
            _ => 1e-10 * self.value.abs(),
        }
    }

    /// Build S = C + U^T F^-1 U for exchanging O (point) with B (candidate j),
    /// and (A, I) the matrix E = U^T F^-1 W F^-1 U, into the scratch.
    fn capacitance(
        &self,
        s: &mut Scratch,
        j: usize,
        a_t: &[f64],
        d_o: &[f64],
        b_t: &[f64],
        e_o: &[f64],
    ) {
        let (r, k) = (self.p.r, self.p.k);
        let p = 2 * r;
        let b = self.p.block(j);
        mul_abt(b, a_t, r, k, r, &mut s.c); // B F^-1 O^T
        let dj = &self.d[j * r * r..(j + 1) * r * r];
        for x in 0..r {
            for y in 0..r {
                let id = if x == y { 1.0 } else { 0.0 };
                s.s[x * p + y] = id + dj[x * r + y];
                s.s[x * p + r + y] = s.c[x * r + y];
                s.s[(r + y) * p + x] = s.c[x * r + y];
                s.s[(r + x) * p + r + y] = d_o[x * r + y] - id;
            }
        }
        if self.needs_e() {
            mul_abt(b, b_t, r, k, r, &mut s.fx); // B F^-1 W F^-1 O^T
            let ej = &self.e[j * r * r..(j + 1) * r * r];
            // E is stored in sinv's buffer until the inverse overwrites it: keep it in g.
            let eb = &mut s.g[..p * p];
            for x in 0..r {
                for y in 0..r {
                    eb[x * p + y] = ej[x * r + y];
                    eb[x * p + r + y] = s.fx[x * r + y];
                    eb[(r + y) * p + x] = s.fx[x * r + y];
                    eb[(r + x) * p + r + y] = e_o[x * r + y];
                }
            }
        }
    }

    /// Criterion after exchanging point (a_t, d_o, ...) for candidate j; INFINITY if singular.
    fn exchange_value(
        &self,
        s: &mut Scratch,
        j: usize,
        a_t: &[f64],
        d_o: &[f64],
        b_t: &[f64],
        e_o: &[f64],
    ) -> f64 {
        let r = self.p.r;
        let p = 2 * r;
        self.capacitance(s, j, a_t, d_o, b_t, e_o);
        let Some(det) = lu_in_place(&mut s.s[..p * p], &mut s.piv[..p], p) else {
            return f64::INFINITY;
        };
        let ratio = if r % 2 == 0 { det } else { -det };
        if !(ratio > 1e-300) {
            return f64::INFINITY;
        }
        match self.c {
            Criterion::D => self.value - ratio.ln(),
            _ => {
                lu_inverse(&s.s[..p * p], &s.piv[..p], p, &mut s.sinv[..p * p]);
                let eb = &s.g[..p * p];
                let mut t = 0.0;
                for x in 0..p {
                    for y in 0..p {
                        t += s.sinv[x * p + y] * eb[y * p + x];
                    }
                }
                let v = self.value - t;
                if v > 0.0 {
                    v
                } else {
                    f64::INFINITY
                }
            }
        }
    }

    /// Removing the visited block O first: F_- = F - O^T O, with Q = I - O F^-1 O^T.
    /// `None` when Q is too close to singular for the two-step formulas.
    fn removal(&self, d_o: &[f64], e_o: &[f64]) -> Option<Removal> {
        let r = self.p.r;
        let mut q = [0.0; MAX_R * MAX_R];
        for a in 0..r {
            for b in 0..r {
                q[a * r + b] = if a == b { 1.0 } else { 0.0 } - d_o[a * r + b];
            }
        }
        let mut rm = Removal {
            qi: [0.0; MAX_R * MAX_R],
            qeq: [0.0; MAX_R * MAX_R],
            value_minus: 0.0,
            bound_c: f64::INFINITY,
            tr_do: 0.0,
            mu_o: 0.0,
        };
        let logdet_q = small_spd_inverse(&q, r, &mut rm.qi)?;
        if logdet_q < -18.0 {
            return None; // removing O nearly loses rank: use the joint 2r formula
        }
        rm.value_minus = match self.c {
            Criterion::D => self.value - logdet_q,
            _ => {
                let mut t = [0.0; MAX_R * MAX_R];
                mul_ab(&rm.qi, e_o, r, r, &mut t); // Qi e_O
                mul_ab(&t, &rm.qi, r, r, &mut rm.qeq); // Qi e_O Qi (e_O symmetric)
                self.value + (0..r).map(|a| t[a * r + a]).sum::<f64>()
            }
        };
        let mu = sym_eigenvalues(&d_o[..r * r], r)[r - 1];
        rm.tr_do = (0..r).map(|a| d_o[a * r + a]).sum::<f64>().max(0.0);
        rm.mu_o = mu.max(0.0);
        rm.bound_c = match self.c {
            Criterion::D => {
                if mu < 1.0 {
                    1.0 / (r as f64 * (1.0 - mu))
                } else {
                    f64::INFINITY
                }
            }
            _ => sym_eigenvalues(&rm.qeq[..r * r], r)[r - 1].max(0.0),
        };
        Some(rm)
    }

    /// Upper bound on the improvement (current value minus value after the exchange)
    /// from candidate j, from its stored blocks alone.
    ///
    /// D: F_- >= (1 - mu) F with mu = l_max(O F^-1 O^T), so B F_-^-1 B^T <= d_j / (1 - mu)
    /// and det(I + B F_-^-1 B^T) <= (1 + tr d_j / (r (1 - mu)))^r.
    /// A, I: P = I + B F_-^-1 B^T >= I + d_j, so with L = (I + d_j)^-1/2,
    /// tr(P^-1 e-) <= |L B F_-^-1 W^1/2|_F^2 = |L B F^-1 W^1/2 + L c Qi O F^-1 W^1/2|_F^2
    /// (c = B F^-1 O^T) <= (sqrt(tr((I + d_j)^-1 e_j)) + |L c|_F sqrt(l_max(Qi e_O Qi)))^2, and
    /// |L c|_F^2 <= tr d_O t_j / (1 + t_j) with t_j = tr d_j (the eigenvalues of
    /// F^-1/2 B^T (I + d_j)^-1 B F^-1/2 are s / (1 + s), s those of d_j), and also
    /// |L c|_F^2 = tr(L B F^-1 O^T O F^-1 B^T L) <= l_max(d_O) tr((I + d_j)^-1 d_j).
    fn improvement_bound(&self, rm: &Removal, j: usize) -> f64 {
        let base = self.value - rm.value_minus;
        match self.c {
            Criterion::D => {
                let r = self.p.r;
                let rr = r * r;
                let tr_d: f64 = (0..r)
                    .map(|a| self.d[j * rr + a * r + a])
                    .sum::<f64>()
                    .max(0.0);
                base + r as f64 * (tr_d * rm.bound_c).ln_1p()
            }
            _ => {
                let [sa, lev, tau] = self.bound_terms[j];
                let lc = (rm.tr_do * lev).min(rm.mu_o * tau); // >= |L c|_F^2
                let s = sa + (rm.bound_c * lc).sqrt();
                // relative slack against the round-off of the updated blocks
                (base + s * s) * (1.0 + 1e-9) + 1e-12 * self.value.abs()
            }
        }
    }

    /// Recompute [`Run::bound_terms`] from d and e (A, I).
    /// Criterion after exchanging the visited point for candidate j, as a removal
    /// (prepared in `rm`) followed by a rank-r addition.
    fn exchange_value_fast(
        &self,
        s: &mut Scratch,
        j: usize,
        rm: &Removal,
        a_t: &[f64],
        b_t: &[f64],
    ) -> f64 {
        self.exchange_value_cf(s, j, rm, a_t, b_t, None)
    }

    /// As [`Self::exchange_value_fast`]; `cf` (r x 2r) may hold B [F^-1 O^T, F^-1 W F^-1 O^T]
    /// computed beforehand (by a blocked matrix product over many candidates).
    fn exchange_value_cf(
        &self,
        s: &mut Scratch,
        j: usize,
        rm: &Removal,
        a_t: &[f64],
        b_t: &[f64],
        cf: Option<&[f64]>,
    ) -> f64 {
        match self.p.r {
            1 => self.fast_r::<1>(j, rm, a_t, b_t, cf),
            2 => self.fast_r::<2>(j, rm, a_t, b_t, cf),
            3 => self.fast_r::<3>(j, rm, a_t, b_t, cf),
            _ => self.fast_dyn(s, j, rm, a_t, b_t),
        }
    }

    /// [`Self::exchange_value_fast`] for a fixed block height R (unrolled small algebra).
    fn fast_r<const R: usize>(
        &self,
        j: usize,
        rm: &Removal,
        a_t: &[f64],
        b_t: &[f64],
        cf: Option<&[f64]>,
    ) -> f64 {
        let k = self.p.k;
        let b = self.p.block(j);
        // B X^T for the k x R-transposed `x_t`, or the `at`-th R columns of the cached `cf`
        let product = |x_t: &[f64], at: usize| -> [[f64; R]; R] {
            std::array::from_fn(|a| {
                std::array::from_fn(|q| match cf {
                    Some(cf) => cf[a * 2 * R + at * R + q],
                    None => dot(&b[a * k..(a + 1) * k], &x_t[q * k..(q + 1) * k]),
                })
            })
        };
        let c = product(a_t, 0); // c = B F^-1 O^T
        let cq = times_matrix(&c, &rm.qi); // c Qi
        let dj = &self.d[j * R * R..(j + 1) * R * R];
        let mut pm = [[0.0; R]; R]; // I + B F_-^-1 B^T
        for a in 0..R {
            for q in 0..=a {
                let mut v = dj[a * R + q];
                for t in 0..R {
                    v += cq[a][t] * c[q][t];
                }
                pm[a][q] = v + if a == q { 1.0 } else { 0.0 };
            }
        }
        // Cholesky of pm in place (lower triangle).
        let mut det = 1.0;
        for a in 0..R {
            let mut v = pm[a][a];
            for t in 0..a {
                v -= pm[a][t] * pm[a][t];
            }
            if !(v > 0.0) {
                return f64::INFINITY;
            }
            det *= v;
            let l = v.sqrt();
            pm[a][a] = l;
            for q in a + 1..R {
                let mut w = pm[q][a];
                for t in 0..a {
                    w -= pm[q][t] * pm[a][t];
                }
                pm[q][a] = w / l;
            }
        }
        if self.c == Criterion::D {
            return rm.value_minus - det.ln();
        }
        let f = product(b_t, 1); // f = B F^-1 W F^-1 O^T
        let cqe = times_matrix(&c, &rm.qeq);
        // e- = B F_-^-1 W F_-^-1 B^T = e_j + f cQ^T + cQ f^T + c (Qi e_O Qi) c^T
        let ej = &self.e[j * R * R..(j + 1) * R * R];
        let mut em = [[0.0; R]; R];
        for a in 0..R {
            for q in 0..R {
                let mut v = ej[a * R + q];
                for t in 0..R {
                    v += f[a][t] * cq[q][t] + cq[a][t] * f[q][t] + cqe[a][t] * c[q][t];
                }
                em[a][q] = v;
            }
        }
        // tr(P^-1 e-) with P = L L^T: solve L X = e-, then tr(L^-T X) = sum ||L^-1 e-^(1/2)||..
        // computed column by column: x = L^-T L^-1 e-[:, q], accumulate x[q].
        let mut t = 0.0;
        for q in 0..R {
            let mut y = [0.0; R];
            for a in 0..R {
                let mut v = em[a][q];
                for u in 0..a {
                    v -= pm[a][u] * y[u];
                }
                y[a] = v / pm[a][a];
            }
            for a in (0..R).rev() {
                let mut v = y[a];
                for u in a + 1..R {
                    v -= pm[u][a] * y[u];
                }
                y[a] = v / pm[a][a];
            }
            t += y[q];
        }
        let v = rm.value_minus - t;
        if v > 0.0 {
            v
        } else {
            f64::INFINITY
        }
    }

    /// The best exchange among `chunk` (candidates j != visited point), with `cf` the rows
    /// B_j [F^-1 O^T, F^-1 W F^-1 O^T] (R x 2R each, in chunk order): [`Self::fast_r`]
    /// eight candidates at a time.
    fn best_of_lanes<const R: usize>(
        &self,
        chunk: &[usize],
        cf: &[f64],
        rm: &Removal,
    ) -> (f64, usize) {
        let sz = R * 2 * R;
        let rr = R * R;
        let mut best = (f64::INFINITY, usize::MAX);
        for (g, js) in chunk.chunks(LANES).enumerate() {
            let at = |l: usize| g * LANES + l.min(js.len() - 1);
            let x = ExchangeIn {
                cf: std::array::from_fn(|l| &cf[at(l) * sz..(at(l) + 1) * sz]),
                d: std::array::from_fn(|l| &self.d[chunk[at(l)] * rr..(chunk[at(l)] + 1) * rr]),
                e: std::array::from_fn(|l| &self.e[chunk[at(l)] * rr..(chunk[at(l)] + 1) * rr]),
                qi: &rm.qi[..rr],
                qeq: &rm.qeq[..rr],
                value_minus: rm.value_minus,
            };
            let v = exchange_values::<R>(&x);
            for (l, &j) in js.iter().enumerate() {
                best = total_min(best, (sane(v[l]), j));
            }
        }
        best
    }

    /// [`Self::exchange_value_fast`] for any block height.
    fn fast_dyn(&self, s: &mut Scratch, j: usize, rm: &Removal, a_t: &[f64], b_t: &[f64]) -> f64 {
        let (r, k) = (self.p.r, self.p.k);
        let rr = r * r;
        let b = self.p.block(j);
        mul_abt(b, a_t, r, k, r, &mut s.c); // c = B F^-1 O^T
        let mut cq = [0.0; MAX_R * MAX_R];
        mul_ab(&s.c, &rm.qi, r, r, &mut cq); // c Qi
        let dj = &self.d[j * rr..(j + 1) * rr];
        let mut pm = [0.0; MAX_R * MAX_R];
        for a in 0..r {
            for bb in 0..r {
                let mut v = dj[a * r + bb];
                for q in 0..r {
                    v += cq[a * r + q] * s.c[bb * r + q];
                }
                pm[a * r + bb] = v + if a == bb { 1.0 } else { 0.0 };
            }
        }
        let mut pinv = [0.0; MAX_R * MAX_R];
        let Some(logdet_p) = small_spd_inverse(&pm, r, &mut pinv) else {
            return f64::INFINITY;
        };
        if self.c == Criterion::D {
            return rm.value_minus - logdet_p;
        }
        mul_abt(b, b_t, r, k, r, &mut s.fx); // f = B F^-1 W F^-1 O^T
        let ej = &self.e[j * rr..(j + 1) * rr];
        // e- = B F_-^-1 W F_-^-1 B^T = e_j + f cQ^T + cQ f^T + c (Qi e_O Qi) c^T
        let mut cqe = [0.0; MAX_R * MAX_R];
        mul_ab(&s.c, &rm.qeq, r, r, &mut cqe);
        let mut t = 0.0;
        for a in 0..r {
            for bb in 0..r {
                let mut v = ej[a * r + bb];
                for q in 0..r {
                    v += s.fx[a * r + q] * cq[bb * r + q]
                        + cq[a * r + q] * s.fx[bb * r + q]
                        + cqe[a * r + q] * s.c[bb * r + q];
                }
                t += pinv[bb * r + a] * v;
            }
        }
        let v = rm.value_minus - t;
        if v > 0.0 {
            v
        } else {
            f64::INFINITY
        }
    }

    /// Visit point i (A, D, I); returns whether it moved.
    fn visit_algebraic(&mut self, i: usize) -> bool {
        let (r, k) = (self.p.r, self.p.k);
        let o = self.design[i];
        let ob = self.p.block(o);
        let mut a_t = vec![0.0; r * k];
        mul_ab(ob, &self.finv, r, k, &mut a_t); // O F^-1
        let mut d_o = vec![0.0; r * r];
        mul_abt(&a_t, ob, r, k, r, &mut d_o);
        let mut b_t = vec![0.0; r * k];
        let mut e_o = vec![0.0; r * r];
        if self.needs_e() {
            mul_ab(ob, &self.fwf, r, k, &mut b_t);
            mul_abt(&b_t, ob, r, k, r, &mut e_o);
        }
        let cands = &self.p.groups[self.p.point_group[i]];
        let this = &*self;
        let removal = self.removal(&d_o, &e_o);
        let best = match &removal {
            None => cands
                .par_iter()
                .with_min_len(256)
                .filter(|&&j| j != o)
                .map_init(
                    || Box::new(Scratch::new()),
                    |s, &j| (sane(this.exchange_value(s, j, &a_t, &d_o, &b_t, &e_o)), j),
                )
                .reduce(|| (f64::INFINITY, usize::MAX), total_min),
            Some(rm) if self.c != Criterion::D => {
                // A, I: keep the candidates whose improvement bound can beat the tolerance
                // (exact: the others cannot improve), then one blocked product
                // B [F^-1 O^T, F^-1 W F^-1 O^T] over them and the small r x r algebra each.
                let tol = self.tol();
                let kept: Vec<usize> = cands
                    .par_chunks(BOUND_CHUNK)
                    .flat_map_iter(|ch| {
                        ch.iter()
                            .copied()
                            .filter(|&j| j != o && !(this.improvement_bound(rm, j) <= tol))
                            .collect::<Vec<usize>>()
                    })
                    .collect();
                if kept.is_empty() {
                    return false;
                }
                let mut w = vec![0.0; k * 2 * r];
                for t in 0..k {
                    for q in 0..r {
                        w[t * 2 * r + q] = a_t[q * k + t];
                        w[t * 2 * r + r + q] = b_t[q * k + t];
                    }
                }
                let rr = r * r;
                let soa = self.soa;
                let lanes = |ch: &[usize]| {
                    let (qi, qeq, v) = (&rm.qi[..rr], &rm.qeq[..rr], rm.value_minus);
                    let (d, e) = (&this.d[..], &this.e[..]);
                    match r {
                        1 => best_exchange::<1>(soa, ch, &w, d, e, qi, qeq, v),
                        2 => best_exchange::<2>(soa, ch, &w, d, e, qi, qeq, v),
                        3 => best_exchange::<3>(soa, ch, &w, d, e, qi, qeq, v),
                        _ => None,
                    }
                };
                if !soa.is_empty() && lanes(&[]).is_some() {
                    kept.par_chunks(GEMM_CHUNK)
                        .map(|ch| lanes(ch).unwrap_or((f64::INFINITY, usize::MAX)))
                        .reduce(|| (f64::INFINITY, usize::MAX), total_min)
                } else {
                    self.p
                        .products_chunks(&kept, &w, 2 * r, |chunk, out| match r {
                            1 => this.best_of_lanes::<1>(chunk, out, rm),
                            2 => this.best_of_lanes::<2>(chunk, out, rm),
                            3 => this.best_of_lanes::<3>(chunk, out, rm),
                            _ => chunk
                                .iter()
                                .map(|&j| {
                                    let v = this.fast_dyn(&mut Scratch::new(), j, rm, &a_t, &b_t);
                                    (sane(v), j)
                                })
                                .fold((f64::INFINITY, usize::MAX), total_min),
                        })
                        .into_iter()
                        .fold((f64::INFINITY, usize::MAX), total_min)
                }
            }
            Some(rm) => {
                // Evaluate in order of decreasing improvement bound; stop when no
                // remaining candidate can beat the best found (exact, not a heuristic).
                let tol = self.tol();
                // bound > tol needs tr d_j above a threshold (the bound grows with it):
                // compute the bound (a logarithm) only for candidates that pass it
                let r = self.p.r;
                let rr = r * r;
                let x_min = ((tol - (self.value - rm.value_minus)) / r as f64).exp_m1()
                    / rm.bound_c
                    * (1.0 - 1e-9);
                let d = &self.d;
                let mut order: Vec<(f64, usize)> = cands
                    .par_chunks(BOUND_CHUNK)
                    .flat_map_iter(|ch| {
                        ch.iter()
                            .copied()
                            .filter(|&j| {
                                let tr_d: f64 = (0..r).map(|a| d[j * rr + a * r + a]).sum();
                                j != o && !(tr_d < x_min)
                            })
                            .map(|j| (this.improvement_bound(rm, j), j))
                            .filter(|&(b, _)| !(b <= tol))
                            .collect::<Vec<(f64, usize)>>()
                    })
                    .collect();
                order.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
                let mut best = (f64::INFINITY, usize::MAX);
                for chunk in order.chunks(PRUNE_CHUNK) {
                    // Only candidates that can beat both the best so far and the current
                    // design by the tolerance matter.
                    let gain = (self.value - best.0).max(tol);
                    if !(chunk[0].0 > gain) {
                        break;
                    }
                    let b = chunk
                        .par_iter()
                        .with_min_len(128)
                        .map_init(
                            || Box::new(Scratch::new()),
                            |s, &(_, j)| (sane(this.exchange_value_fast(s, j, rm, &a_t, &b_t)), j),
                        )
                        .reduce(|| (f64::INFINITY, usize::MAX), total_min);
                    best = total_min(best, b);
                }
                best
            }
        };
        if !(best.0 < self.value - self.tol()) {
            return false;
        }
        let j = best.1;
        // Low-rank update of the per-candidate blocks, with the old F^-1.
        let p = 2 * r;
        let mut s = Scratch::new();
        self.capacitance(&mut s, j, &a_t, &d_o, &b_t, &e_o);
        let e_pair: Vec<f64> = s.g[..p * p].to_vec();
        let Some(_) = lu_in_place(&mut s.s[..p * p], &mut s.piv[..p], p) else {
            return false;
        };
        let mut x = vec![0.0; p * p];
        lu_inverse(&s.s[..p * p], &s.piv[..p], p, &mut x);
        let bj = self.p.block(j);
        let mut pt = vec![0.0; p * k]; // U^T F^-1
        mul_ab(bj, &self.finv, r, k, &mut pt[..r * k]);
        pt[r * k..].copy_from_slice(&a_t);
        let mut qt = vec![0.0; p * k]; // U^T F^-1 W F^-1
        if self.needs_e() {
            mul_ab(bj, &self.fwf, r, k, &mut qt[..r * k]);
            qt[r * k..].copy_from_slice(&b_t);
        }
        // With P = F^-1 U, Q = F^-1 W F^-1 U, y = B P, z = B Q, X = S^-1, R = U^T Q:
        // d' = d - y X y^T and e' = e - [y z] G [y z]^T, G = [[-X R X, X], [X, 0]].
        // Folding the eigenvectors of X and G into the product (X = V L V^T, G = E M E^T)
        // leaves sums of weighted rank-one terms per candidate.
        for a in 0..p {
            for b in 0..a {
                let v = 0.5 * (x[a * p + b] + x[b * p + a]);
                x[a * p + b] = v;
                x[b * p + a] = v;
            }
        }
        let (lam, vx) = sym_eig(&x, p);
        let needs_e = self.needs_e();
        let pe = 2 * p;
        let (gam, ve) = if needs_e {
            let mut xr = vec![0.0; p * p];
            mul_ab(&x, &e_pair, p, p, &mut xr);
            let mut xrx = vec![0.0; p * p];
            mul_ab(&xr, &x, p, p, &mut xrx);
            let mut g = vec![0.0; pe * pe];
            for a in 0..p {
                for b in 0..p {
                    g[a * pe + b] = -0.5 * (xrx[a * p + b] + xrx[b * p + a]);
                    g[a * pe + p + b] = x[a * p + b];
                    g[(p + a) * pe + b] = x[a * p + b];
                }
            }
            sym_eig(&g, pe)
        } else {
            (vec![], vec![])
        };
        let q = if needs_e { p + pe } else { p };
        let mut w = vec![0.0; k * q]; // [P V, [P Q] E]
        for t in 0..k {
            for l in 0..p {
                w[t * q + l] = (0..p).map(|c| pt[c * k + t] * vx[c * p + l]).sum();
            }
            if needs_e {
                for l in 0..pe {
                    w[t * q + p + l] = (0..p)
                        .map(|c| {
                            pt[c * k + t] * ve[c * pe + l] + qt[c * k + t] * ve[(p + c) * pe + l]
                        })
                        .sum();
                }
            }
        }
        let (lam, gam) = (&lam[..], &gam[..]);
        if !self.soa.is_empty() && soa_kernel(r, q) {
            let soa = self.soa;
            self.for_candidate_chunks(|first, dch, ech, bt| {
                soa_update(soa, first, r, &w, lam, gam, dch, ech, bt);
            });
        } else {
            self.for_candidate_products(&w, q, |prod, _first, dch, ech, bt| {
                let u = RankUpdate { prod, q, lam, gam };
                match r {
                    1 => rank_update::<1>(&u, dch, ech, bt),
                    2 => rank_update::<2>(&u, dch, ech, bt),
                    3 => rank_update::<3>(&u, dch, ech, bt),
                    _ => {
                        for t in 0..dch.len() / (r * r) {
                            let pr = &prod[t * r * q..(t + 1) * r * q];
                            let dm = &mut dch[t * r * r..(t + 1) * r * r];
                            for a in 0..r {
                                let ya = &pr[a * q..a * q + p];
                                for c in 0..=a {
                                    let yc = &pr[c * q..c * q + p];
                                    let v: f64 = (0..p).map(|l| lam[l] * ya[l] * yc[l]).sum();
                                    dm[a * r + c] -= v;
                                    if c != a {
                                        dm[c * r + a] -= v;
                                    }
                                }
                            }
                            if needs_e {
                                let em = &mut ech[t * r * r..(t + 1) * r * r];
                                for a in 0..r {
                                    let ha = &pr[a * q + p..(a + 1) * q];
                                    for c in 0..=a {
                                        let hc = &pr[c * q + p..(c + 1) * q];
                                        let v: f64 = (0..pe).map(|l| gam[l] * ha[l] * hc[l]).sum();
                                        em[a * r + c] -= v;
                                        if c != a {
                                            em[c * r + a] -= v;
                                        }
                                    }
                                }
                            }
                        }
                        if needs_e {
                            bound_terms_chunk(dch, ech, bt, r);
                        }
                    }
                }
            });
        }
        let old = self.design[i];
        self.design[i] = j;
        if self.recompute().is_err() {
            self.design[i] = old;
            let _ = self.recompute();
            self.refresh();
            return false;
        }
        true
    }

    /// Visit point i (K, E): screen by first-order eigenvalue perturbation, then exact.
    fn visit_spectral(&mut self, i: usize) -> bool {
        let (r, k) = (self.p.r, self.p.k);
        let (vals, vecs) = sym_eig(&self.f, k);
        let s_lo = k.min(4);
        let s_hi = if self.c == Criterion::K { k.min(2) } else { 0 };
        let idx: Vec<usize> = (0..s_lo).chain((k - s_hi)..k).collect();
        let s = idx.len();
        let mut vsub = vec![0.0; s * k];
        for (q, &m) in idx.iter().enumerate() {
            for a in 0..k {
                vsub[q * k + a] = vecs[a * k + m];
            }
        }
        let proj = |b: &[f64], out: &mut [f64]| {
            // out[q] = sum over rows of (row . v_q)^2
            for (q, o) in out.iter_mut().enumerate().take(s) {
                let v = &vsub[q * k..(q + 1) * k];
                *o = b.chunks_exact(k).map(|row| dot(row, v).powi(2)).sum();
            }
        };
        let o = self.design[i];
        let mut h_o = vec![0.0; s];
        proj(self.p.block(o), &mut h_o);
        let c = self.c;
        let cands = &self.p.groups[self.p.point_group[i]];
        // one blocked product B_j [v_q] over the candidates, then h_q = |B_j v_q|^2
        let mut w = vec![0.0; k * s];
        for (q, &m) in idx.iter().enumerate() {
            for a in 0..k {
                w[a * s + q] = vecs[a * k + m];
            }
        }
        // screening value of candidate j from h_q = |B_j v_q|^2
        let base: Vec<f64> = (0..s).map(|q| vals[idx[q]]).collect();
        let screen = |j: usize, h: &dyn Fn(usize) -> f64| {
            let mut lo = f64::INFINITY;
            let mut hi = vals[k - 1];
            for q in 0..s {
                let est = base[q] + h(q) - h_o[q];
                if q < s_lo {
                    lo = lo.min(est);
                } else {
                    hi = hi.max(est);
                }
            }
            (sane(spectral_value(c, lo, hi)), j)
        };
        let n_cand = self.p.n_cand;
        let all = cands.len() == n_cand && cands.iter().enumerate().all(|(t, &j)| t == j);
        let soa = self.soa;
        let mut vs = vec![];
        if all && !soa.is_empty() {
            let sc = Screen {
                base: &base,
                h_o: &h_o,
                s_lo,
                hi0: vals[k - 1],
                ratio: c == Criterion::K,
            };
            vs = vec![0.0; n_cand];
            let done = vs
                .par_chunks_mut(GEMM_CHUNK)
                .enumerate()
                .map(|(ci, vc)| soa_screen(soa, ci * GEMM_CHUNK, r, &w, &sc, vc))
                .reduce(|| true, |a, b| a && b);
            if !done {
                vs.clear();
            }
        }
        let mut screened: Vec<(f64, usize)> = if !vs.is_empty() {
            (0..n_cand)
                .filter(|&j| j != o)
                .map(|j| (vs[j], j))
                .collect()
        } else {
            self.p
                .products(cands, &w, s, |j, prod| {
                    if j == o {
                        return (f64::INFINITY, usize::MAX);
                    }
                    screen(j, &|q| {
                        (0..r).map(|a| prod[a * s + q] * prod[a * s + q]).sum()
                    })
                })
                .into_iter()
                .filter(|x| x.1 != usize::MAX)
                .collect()
        };
        let top = EXACT_TOP.min(screened.len());
        if top == 0 {
            return false;
        }
        let cmp = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
        if screened.len() > top {
            screened.select_nth_unstable_by(top - 1, cmp);
            screened.truncate(top);
        }
        let ob = self.p.block(o);
        let f = &self.f;
        let best = screened
            .par_iter()
            .map(|&(_, j)| {
                let mut g = f.clone();
                gram_add(&mut g, ob, r, k, -1.0);
                gram_add(&mut g, self.p.block(j), r, k, 1.0);
                let ev = sym_eigenvalues(&g, k);
                (sane(spectral_value(c, ev[0], ev[k - 1])), j)
            })
            .reduce(|| (f64::INFINITY, usize::MAX), total_min);
        if !(best.0 < self.value - self.tol()) {
            return false;
        }
        let old = self.design[i];
        self.design[i] = best.1;
        if self.recompute().is_err() {
            self.design[i] = old;
            let _ = self.recompute();
            return false;
        }
        true
    }

    /// Sweep until no point moves; returns the number of exchanges.
    fn optimise(&mut self, max_sweeps: usize, rng: &mut ChaCha8Rng) -> usize {
        let n = self.p.n();
        let mut order: Vec<usize> = (0..n).collect();
        let mut moves = 0;
        let mut stale = usize::MAX; // exchanges since the per-candidate blocks were refreshed
                                    // A and I (k-exchange): cheap sweeps visit only the quarter of the points whose removal
                                    // costs least; when they stop improving, a sweep over every point confirms (so the
                                    // result is a local optimum for single exchanges either way).
        let k_exchange = self.needs_e() && n >= 16;
        let mut full = !k_exchange;
        for _ in 0..max_sweeps {
            if !self.c.is_spectral() && stale >= REFRESH_AFTER {
                self.refresh();
                stale = 0;
            }
            let visit: Vec<usize> = if full {
                order.shuffle(rng);
                order.clone()
            } else {
                self.cheapest_points(n.div_ceil(4))
            };
            let mut moved = false;
            for &i in &visit {
                if interrupt::requested() {
                    return moves; // Ctrl-C: `search` reports it after the starts return
                }
                let m = if self.c.is_spectral() {
                    self.visit_spectral(i)
                } else {
                    self.visit_algebraic(i)
                };
                if m {
                    moves += 1;
                    stale = stale.saturating_add(1);
                    moved = true;
                }
            }
            if !moved {
                if full {
                    break;
                }
                full = true;
            } else if k_exchange {
                full = false;
            }
        }
        moves
    }

    /// Iterated local search from the local optimum reached: `rounds` times, move a few
    /// random points to random candidates of their zones, optimise again, and keep the
    /// result only if it beats the best so far (so the value never gets worse).
    fn perturb_and_polish(
        &mut self,
        rounds: usize,
        max_sweeps: usize,
        rng: &mut ChaCha8Rng,
    ) -> usize {
        let n = self.p.n();
        let mut moves = 0;
        for _ in 0..rounds {
            if interrupt::requested() {
                break;
            }
            let (best, best_value) = (self.design.clone(), self.value);
            let kick = (n / PERTURB_FRACTION).clamp(1, n);
            for i in sample(rng, n, kick).iter() {
                let members = &self.p.groups[self.p.point_group[i]];
                self.design[i] = members[rng.random_range(0..members.len())];
            }
            let mut m = 0;
            let improved = self.recompute().is_ok() && {
                m = self.optimise(max_sweeps, rng);
                self.value < best_value - self.tol()
            };
            if improved {
                moves += m;
            } else {
                self.design = best;
                // the best design was valid a moment ago
                let _ = self.recompute();
            }
        }
        moves
    }

    /// The `m` design points whose removal raises the criterion least: tr(Q^-1 e_O)
    /// with Q = I - O F^-1 O^T (A, I), from the stored per-candidate blocks.
    fn cheapest_points(&self, m: usize) -> Vec<usize> {
        let r = self.p.r;
        let rr = r * r;
        let mut loss: Vec<(f64, usize)> = (0..self.p.n())
            .map(|i| {
                let o = self.design[i];
                let mut q = [0.0; MAX_R * MAX_R];
                for a in 0..r {
                    for b in 0..r {
                        q[a * r + b] = if a == b { 1.0 } else { 0.0 } - self.d[o * rr + a * r + b];
                    }
                }
                let mut qi = [0.0; MAX_R * MAX_R];
                let v = match small_spd_inverse(&q, r, &mut qi) {
                    Some(_) => (0..rr).map(|t| qi[t] * self.e[o * rr + t]).sum(),
                    None => f64::INFINITY,
                };
                (sane(v), i)
            })
            .collect();
        loss.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        loss.into_iter().take(m).map(|x| x.1).collect()
    }
}

/// Randomised greedy D-optimal construction: each point (random order) takes the
/// best of a random sample of its zone's candidates.
fn greedy_start(p: &Problem, ridge0: f64, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let (r, k, n) = (p.r, p.k, p.n());
    let mut f = vec![0.0; k * k];
    for a in 0..k {
        f[a * k + a] = ridge0;
    }
    let mut finv = spd_inverse(&f, k).map(|x| x.0).unwrap_or_else(|| f.clone());
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(rng);
    let mut design = vec![0; n];
    let mut g = vec![0.0; r * k];
    let mut m = [0.0; MAX_R * MAX_R];
    let mut piv = [0; MAX_R];
    for &i in &order {
        let members = &p.groups[p.point_group[i]];
        let take = GREEDY_SAMPLE.min(members.len());
        let picks = sample(rng, members.len(), take);
        let mut best = (f64::NEG_INFINITY, members[picks.index(0)]);
        for q in picks.iter() {
            let j = members[q];
            let b = p.block(j);
            mul_ab(b, &finv, r, k, &mut g);
            mul_abt(&g, b, r, k, r, &mut m);
            for a in 0..r {
                m[a * r + a] += 1.0;
            }
            let det = lu_in_place(&mut m[..r * r], &mut piv[..r], r).unwrap_or(0.0);
            if det > best.0 {
                best = (det, j);
            }
        }
        design[i] = best.1;
        gram_add(&mut f, p.block(best.1), r, k, 1.0);
        if let Some((inv, _)) = spd_inverse(&f, k) {
            finv = inv;
        }
    }
    design
}

/// Multistart exchange search (Eqs. 4.7, 4.8). Deterministic for a seed: each
/// start has its own ChaCha stream, and ties break on the lowest index.
pub fn search(p: &Problem, o: &Options) -> Result<Outcome> {
    let c = o.criterion;
    p.validate(c)?;
    let scale = p.pooled()?;
    let ridge = 1e-11 * scale;
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
