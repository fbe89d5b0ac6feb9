//! Visiting one design point: the best exchange among its zone's candidates (algebraic
//! criteria A, D, I by exact formulas with pruning; spectral K, E by screening), then the
//! low-rank update of the per-candidate blocks.

use super::*;

/// O F^-1, O F^-1 O^T and (A, I) O F^-1 W F^-1, O F^-1 W F^-1 O^T of a design point's block O.
struct PointProducts {
    a_t: Vec<f64>,
    d_o: Vec<f64>,
    b_t: Vec<f64>,
    e_o: Vec<f64>,
}

/// The rank-2r update of the per-candidate blocks for one exchange (see `update_terms`).
struct BlockUpdate {
    w: Vec<f64>,
    q: usize,
    lam: Vec<f64>,
    gam: Vec<f64>,
}

impl<'p, 'a> Run<'p, 'a> {

    /// Visit point i (A, D, I); returns whether it moved.
    pub(super) fn visit_algebraic(&mut self, i: usize) -> bool {
        let o = self.design[i];
        let pp = self.point_products(o);
        let best = match self.removal(&pp.d_o, &pp.e_o) {
            None => self.best_unpruned(i, o, &pp),
            Some(rm) if self.c != Criterion::D => match self.best_bounded_ai(i, o, &pp, &rm) {
                Some(b) => b,
                None => return false,
            },
            Some(rm) => self.best_bounded_d(i, o, &pp, &rm),
        };
        if !(best.0 < self.value - self.tol()) {
            return false;
        }
        self.exchange(i, best.1, &pp)
    }

    /// O F^-1 and O F^-1 O^T of the point's block O (and O F^-1 W F^-1, its r x r block).
    fn point_products(&self, o: usize) -> PointProducts {
        let (r, k) = (self.p.r, self.p.k);
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
        PointProducts { a_t, d_o, b_t, e_o }
    }

    /// Every candidate of the zone evaluated exactly (no removal bound available).
    fn best_unpruned(&self, i: usize, o: usize, pp: &PointProducts) -> (f64, usize) {
        let cands = &self.p.groups[self.p.point_group[i]];
        let PointProducts { a_t, d_o, b_t, e_o } = pp;
        cands
            .par_iter()
            .with_min_len(256)
            .filter(|&&j| j != o)
            .map_init(|| Box::new(Scratch::new()), |s, &j| (sane(self.exchange_value(s, j, a_t, d_o, b_t, e_o)), j))
            .reduce(|| (f64::INFINITY, usize::MAX), total_min)
    }

    /// A, I: keep the candidates whose improvement bound can beat the tolerance (exact: the
    /// others cannot improve), then one blocked product B [F^-1 O^T, F^-1 W F^-1 O^T] over
    /// them and the small r x r algebra each. None when no candidate is kept.
    fn best_bounded_ai(&self, i: usize, o: usize, pp: &PointProducts, rm: &Removal) -> Option<(f64, usize)> {
        let (r, k) = (self.p.r, self.p.k);
        let cands = &self.p.groups[self.p.point_group[i]];
        let (a_t, b_t) = (&pp.a_t, &pp.b_t);
        let this = self;
        let tol = self.tol();
        let kept: Vec<usize> = cands
            .par_chunks(BOUND_CHUNK)
            .flat_map_iter(|ch| {
                ch.iter().copied().filter(|&j| j != o && !(this.improvement_bound(rm, j) <= tol)).collect::<Vec<usize>>()
            })
            .collect();
        if kept.is_empty() {
            return None;
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
        Some(if !soa.is_empty() && lanes(&[]).is_some() {
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
                            let v = this.fast_dyn(&mut Scratch::new(), j, rm, a_t, b_t);
                            (sane(v), j)
                        })
                        .fold((f64::INFINITY, usize::MAX), total_min),
                })
                .into_iter()
                .fold((f64::INFINITY, usize::MAX), total_min)
        })
    }

    /// D: evaluate in order of decreasing improvement bound; stop when no remaining
    /// candidate can beat the best found (exact, not a heuristic).
    fn best_bounded_d(&self, i: usize, o: usize, pp: &PointProducts, rm: &Removal) -> (f64, usize) {
        let cands = &self.p.groups[self.p.point_group[i]];
        let (a_t, b_t) = (&pp.a_t, &pp.b_t);
        let this = self;
        let tol = self.tol();
        // bound > tol needs tr d_j above a threshold (the bound grows with it):
        // compute the bound (a logarithm) only for candidates that pass it
        let r = self.p.r;
        let rr = r * r;
        let x_min = ((tol - (self.value - rm.value_minus)) / r as f64).exp_m1() / rm.bound_c * (1.0 - 1e-9);
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
                .map_init(|| Box::new(Scratch::new()), |s, &(_, j)| (sane(this.exchange_value_fast(s, j, rm, a_t, b_t)), j))
                .reduce(|| (f64::INFINITY, usize::MAX), total_min);
            best = total_min(best, b);
        }
        best
    }

    /// Exchange point i for candidate j: low-rank update of the per-candidate blocks (with
    /// the old F^-1), then the exact F, F^-1 of the new design; false (and nothing changed)
    /// when the update or the new F is singular.
    fn exchange(&mut self, i: usize, j: usize, pp: &PointProducts) -> bool {
        let Some(upd) = self.update_terms(j, pp) else {
            return false;
        };
        self.apply_update(&upd);
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

    /// The terms of the rank-2r update for exchanging the point (products `pp`) with
    /// candidate j: with P = F^-1 U, Q = F^-1 W F^-1 U, X = S^-1, R = U^T Q, the columns
    /// w = [P V, [P Q] E] and the weights L, M of X = V L V^T and G = E M E^T,
    /// G = [[-X R X, X], [X, 0]]. None when S is singular.
    fn update_terms(&self, j: usize, pp: &PointProducts) -> Option<BlockUpdate> {
        let (r, k) = (self.p.r, self.p.k);
        let PointProducts { a_t, d_o, b_t, e_o } = pp;
        // Low-rank update of the per-candidate blocks, with the old F^-1.
        let p = 2 * r;
        let mut s = Scratch::new();
        self.capacitance(&mut s, j, a_t, d_o, b_t, e_o);
        let e_pair: Vec<f64> = s.g[..p * p].to_vec();
        let Some(_) = lu_in_place(&mut s.s[..p * p], &mut s.piv[..p], p) else {
            return None;
        };
        let mut x = vec![0.0; p * p];
        lu_inverse(&s.s[..p * p], &s.piv[..p], p, &mut x);
        let bj = self.p.block(j);
        let mut pt = vec![0.0; p * k]; // U^T F^-1
        mul_ab(bj, &self.finv, r, k, &mut pt[..r * k]);
        pt[r * k..].copy_from_slice(a_t);
        let mut qt = vec![0.0; p * k]; // U^T F^-1 W F^-1
        if self.needs_e() {
            mul_ab(bj, &self.fwf, r, k, &mut qt[..r * k]);
            qt[r * k..].copy_from_slice(b_t);
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
        Some(BlockUpdate { w, q, lam, gam })
    }

    /// d' = d - y X y^T and e' = e - [y z] G [y z]^T for every candidate (y = B P, z = B Q):
    /// sums of weighted rank-one terms per candidate, by the lane kernels or by hand.
    fn apply_update(&mut self, upd: &BlockUpdate) {
        let r = self.p.r;
        let p = 2 * r;
        let needs_e = self.needs_e();
        let pe = 2 * p;
        let BlockUpdate { w, q, lam, gam } = upd;
        let (w, q) = (&w[..], *q);
        let (lam, gam) = (&lam[..], &gam[..]);
        if !self.soa.is_empty() && soa_kernel(r, q) {
            let soa = self.soa;
            self.for_candidate_chunks(|first, dch, ech, bt| {
                soa_update(soa, first, r, w, lam, gam, dch, ech, bt);
            });
        } else {
            self.for_candidate_products(w, q, |prod, _first, dch, ech, bt| {
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
    }

    /// Visit point i (K, E): screen by first-order eigenvalue perturbation, then exact.
    pub(super) fn visit_spectral(&mut self, i: usize) -> bool {
        let o = self.design[i];
        let mut screened = self.screen_spectral(i, o);
        let top = EXACT_TOP.min(screened.len());
        if top == 0 {
            return false;
        }
        let best = self.best_of_screened(o, &mut screened, top);
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

    /// Screening values of the zone's candidates for exchanging point i (block o): the
    /// extreme eigenvalues of F perturbed to first order, from h_q = |B_j v_q|^2 over the
    /// lowest (and, for K, highest) eigenvectors v_q; one blocked product, or the lanes.
    fn screen_spectral(&self, i: usize, o: usize) -> Vec<(f64, usize)> {
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
        if !vs.is_empty() {
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
        }
    }

    /// The exact K or E value of the `top` best-screened candidates; the best of them.
    fn best_of_screened(&self, o: usize, screened: &mut Vec<(f64, usize)>, top: usize) -> (f64, usize) {
        let (r, k) = (self.p.r, self.p.k);
        let c = self.c;
        let cmp = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
        if screened.len() > top {
            screened.select_nth_unstable_by(top - 1, cmp);
            screened.truncate(top);
        }
        let ob = self.p.block(o);
        let f = &self.f;
        screened
            .par_iter()
            .map(|&(_, j)| {
                let mut g = f.clone();
                gram_add(&mut g, ob, r, k, -1.0);
                gram_add(&mut g, self.p.block(j), r, k, 1.0);
                let ev = sym_eigenvalues(&g, k);
                (sane(spectral_value(c, ev[0], ev[k - 1])), j)
            })
            .reduce(|| (f64::INFINITY, usize::MAX), total_min)
    }
}
