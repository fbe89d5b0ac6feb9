//! The value of an exchange: the capacitance S (2r x 2r), exact values (A, D, I), the
//! improvement bound used to skip candidates, and the lane kernels' dispatch.

use super::*;


pub(super) fn total_min(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    match a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)) {
        std::cmp::Ordering::Greater => b,
        _ => a,
    }
}

pub(super) fn sane(v: f64) -> f64 {
    if v.is_nan() {
        f64::INFINITY
    } else {
        v
    }
}

/// The R x R product `c m` with `m` row-major (the one-candidate twin of the lanes'
/// `times_matrix`: same operations, same order).
pub(super) fn times_matrix<const R: usize>(c: &[[f64; R]; R], m: &[f64]) -> [[f64; R]; R] {
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
pub(super) fn spectral_value(c: Criterion, lmin: f64, lmax: f64) -> f64 {
    if !(lmin > 0.0) {
        return f64::INFINITY;
    }
    match c {
        Criterion::K => (lmax / lmin).sqrt(),
        _ => 1.0 / lmin,
    }
}

/// [`Run::bound_terms`] of one candidate from its d_j and e_j (r x r).
pub(super) fn bound_terms_of(dj: &[f64], ej: &[f64], r: usize) -> [f64; 3] {
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
pub(super) fn bound_terms_chunk(d: &[f64], e: &[f64], bt: &mut [[f64; 3]], r: usize) {
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

impl<'p, 'a> Run<'p, 'a> {

    /// Build S = C + U^T F^-1 U for exchanging O (point) with B (candidate j),
    /// and (A, I) the matrix E = U^T F^-1 W F^-1 U, into the scratch.
    pub(super) fn capacitance(
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
    pub(super) fn exchange_value(
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
    pub(super) fn removal(&self, d_o: &[f64], e_o: &[f64]) -> Option<Removal> {
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
    pub(super) fn improvement_bound(&self, rm: &Removal, j: usize) -> f64 {
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
    pub(super) fn exchange_value_fast(
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
    pub(super) fn exchange_value_cf(
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
    pub(super) fn fast_r<const R: usize>(
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
    pub(super) fn best_of_lanes<const R: usize>(
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
    pub(super) fn fast_dyn(&self, s: &mut Scratch, j: usize, rm: &Removal, a_t: &[f64], b_t: &[f64]) -> f64 {
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
}
