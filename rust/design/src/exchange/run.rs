//! The state of one start: the design, F, F^-1 (and F^-1 W F^-1), the per-candidate
//! r x r blocks kept current by low-rank updates, and their exact recomputation.

use super::*;

/// One start's mutable state.
pub(super) struct Run<'p, 'a> {
    pub(super) p: &'p Problem<'a>,
    pub(super) c: Criterion,
    pub(super) ridge: f64,
    pub(super) design: Vec<usize>,
    pub(super) f: Vec<f64>,
    pub(super) finv: Vec<f64>,
    /// F^-1 W F^-1 (A: W = I), for A and I.
    pub(super) fwf: Vec<f64>,
    /// Per candidate r x r: B F^-1 B^T.
    pub(super) d: Vec<f64>,
    /// Per candidate r x r: B F^-1 W F^-1 B^T (A and I).
    pub(super) e: Vec<f64>,
    pub(super) value: f64,
    /// Per candidate (A, I): sqrt(tr((I + d_j)^-1 e_j)), t_j / (1 + t_j) with t_j = tr d_j,
    /// and tr((I + d_j)^-1 d_j),
    /// the two ingredients of the improvement bound, kept with d and e.
    pub(super) bound_terms: Vec<[f64; 3]>,
    /// The candidate blocks regrouped for the lane kernels; empty: unused.
    pub(super) soa: &'p Soa,
}

/// The visited point's removal, shared by all candidates of a visit.
pub(super) struct Removal {
    pub(super) qi: [f64; MAX_R * MAX_R],
    pub(super) qeq: [f64; MAX_R * MAX_R],
    pub(super) value_minus: f64,
    /// Constant of the improvement bound (see [`Run::improvement_bound`]); infinite: no pruning.
    pub(super) bound_c: f64,
    /// A, I: tr d_O and l_max(d_O) (the two bounds on |L c|_F^2).
    pub(super) tr_do: f64,
    pub(super) mu_o: f64,
}

/// Scratch of one candidate evaluation (A, D, I).
pub(super) struct Scratch {
    pub(super) c: [f64; MAX_R * MAX_R],
    pub(super) fx: [f64; MAX_R * MAX_R],
    pub(super) s: [f64; MAX_P * MAX_P],
    pub(super) sinv: [f64; MAX_P * MAX_P],
    pub(super) piv: [usize; MAX_P],
    pub(super) g: Vec<f64>,
}

impl Scratch {
    pub(super) fn new() -> Self {
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
    pub(super) fn new(
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

    pub(super) fn needs_e(&self) -> bool {
        matches!(self.c, Criterion::A | Criterion::I)
    }

    /// F, F^-1, F^-1 W F^-1 and the criterion value from the design, exactly.
    pub(super) fn recompute(&mut self) -> Result<()> {
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
    pub(super) fn refresh(&mut self) {
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
    pub(super) fn for_candidate_products<F>(&mut self, w: &[f64], q: usize, f: F)
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
    pub(super) fn for_candidate_chunks<F>(&mut self, f: F)
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

    pub(super) fn tol(&self) -> f64 {
        match self.c {
            Criterion::D => 1e-10 * (self.value.abs() + 1.0),
            _ => 1e-10 * self.value.abs(),
        }
    }
}
