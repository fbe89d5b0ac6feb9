//! The per-candidate small algebra of the A/I exchange, eight candidates at a time
//! (one value of each candidate per SIMD lane). Every lane does exactly the operations,
//! in the same order, as the one-candidate code in `exchange.rs`, so the results are
//! bit-identical to it and independent of how the candidates are grouped.

/// Candidates per group.
pub const LANES: usize = 8;
/// One value for each candidate of a group.
pub type V = [f64; LANES];

const Z: V = [0.0; LANES];

/// Whether the AVX-512 build of the lane kernels can run here.
pub fn wide() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Inputs of the exchange value of a group: per lane, `cf` (R x 2R: B [F^-1 O^T, F^-1 W F^-1 O^T]),
/// `d` and `e` (R x R: B F^-1 B^T, B F^-1 W F^-1 B^T).
pub struct ExchangeIn<'a> {
    pub cf: [&'a [f64]; LANES],
    pub d: [&'a [f64]; LANES],
    pub e: [&'a [f64]; LANES],
    /// (I - O F^-1 O^T)^-1 and Qi e_O Qi, R x R.
    pub qi: &'a [f64],
    pub qeq: &'a [f64],
    pub value_minus: f64,
}

/// A/I criterion after each lane's exchange (see `Run::fast_r`); INFINITY where not positive definite.
pub fn exchange_values<const R: usize>(x: &ExchangeIn) -> V {
    #[cfg(target_arch = "x86_64")]
    {
        if wide() {
            // SAFETY: the feature was detected at run time.
            return unsafe { exchange_values_avx512::<R>(x) };
        }
    }
    exchange_values_body::<R>(x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn exchange_values_avx512<const R: usize>(x: &ExchangeIn) -> V {
    exchange_values_body::<R>(x)
}

#[inline(always)]
fn exchange_values_body<const R: usize>(x: &ExchangeIn) -> V {
    let mut c = [[Z; R]; R]; // B F^-1 O^T
    let mut f = [[Z; R]; R]; // B F^-1 W F^-1 O^T
    let mut dj = [[Z; R]; R];
    let mut ej = [[Z; R]; R];
    for l in 0..LANES {
        for a in 0..R {
            for q in 0..R {
                c[a][q][l] = x.cf[l][a * 2 * R + q];
                f[a][q][l] = x.cf[l][a * 2 * R + R + q];
                dj[a][q][l] = x.d[l][a * R + q];
                ej[a][q][l] = x.e[l][a * R + q];
            }
        }
    }
    let mut cq = [[Z; R]; R]; // c Qi
    for a in 0..R {
        for q in 0..R {
            let mut v = Z;
            for t in 0..R {
                let s = x.qi[t * R + q];
                for l in 0..LANES {
                    v[l] += c[a][t][l] * s;
                }
            }
            cq[a][q] = v;
        }
    }
    let mut pm = [[Z; R]; R]; // I + B F_-^-1 B^T
    for a in 0..R {
        for q in 0..=a {
            let mut v = dj[a][q];
            for t in 0..R {
                for l in 0..LANES {
                    v[l] += cq[a][t][l] * c[q][t][l];
                }
            }
            let one = if a == q { 1.0 } else { 0.0 };
            for l in 0..LANES {
                pm[a][q][l] = v[l] + one;
            }
        }
    }
    let mut bad = [false; LANES];
    for a in 0..R {
        let mut v = pm[a][a];
        for t in 0..a {
            for l in 0..LANES {
                v[l] -= pm[a][t][l] * pm[a][t][l];
            }
        }
        for l in 0..LANES {
            if !(v[l] > 0.0) {
                bad[l] = true;
                v[l] = 1.0;
            }
            pm[a][a][l] = v[l].sqrt();
        }
        for q in a + 1..R {
            let mut w = pm[q][a];
            for t in 0..a {
                for l in 0..LANES {
                    w[l] -= pm[q][t][l] * pm[a][t][l];
                }
            }
            for l in 0..LANES {
                pm[q][a][l] = w[l] / pm[a][a][l];
            }
        }
    }
    let mut cqe = [[Z; R]; R];
    for a in 0..R {
        for q in 0..R {
            let mut v = Z;
            for t in 0..R {
                let s = x.qeq[t * R + q];
                for l in 0..LANES {
                    v[l] += c[a][t][l] * s;
                }
            }
            cqe[a][q] = v;
        }
    }
    // e- = e_j + f cQ^T + cQ f^T + c (Qi e_O Qi) c^T
    let mut em = [[Z; R]; R];
    for a in 0..R {
        for q in 0..R {
            let mut v = ej[a][q];
            for t in 0..R {
                for l in 0..LANES {
                    v[l] += f[a][t][l] * cq[q][t][l]
                        + cq[a][t][l] * f[q][t][l]
                        + cqe[a][t][l] * c[q][t][l];
                }
            }
            em[a][q] = v;
        }
    }
    let mut t = Z;
    for q in 0..R {
        let mut y = [Z; R];
        for a in 0..R {
            let mut v = em[a][q];
            for u in 0..a {
                for l in 0..LANES {
                    v[l] -= pm[a][u][l] * y[u][l];
                }
            }
            for l in 0..LANES {
                y[a][l] = v[l] / pm[a][a][l];
            }
        }
        for a in (0..R).rev() {
            let mut v = y[a];
            for u in a + 1..R {
                for l in 0..LANES {
                    v[l] -= pm[u][a][l] * y[u][l];
                }
            }
            for l in 0..LANES {
                y[a][l] = v[l] / pm[a][a][l];
            }
        }
        for l in 0..LANES {
            t[l] += y[q][l];
        }
    }
    let mut out = Z;
    for l in 0..LANES {
        let v = x.value_minus - t[l];
        out[l] = if !bad[l] && v > 0.0 { v } else { f64::INFINITY };
    }
    out
}

/// The low-rank update of the per-candidate blocks (see `Run::visit_algebraic`) for the
/// candidates of a chunk: with y (the first `lam.len()` columns of each candidate's r x q
/// product rows) and h (the next `gam.len()` columns),
/// d -= y diag(lam) y^T and e -= h diag(gam) h^T; then each candidate's bound terms.
pub struct RankUpdate<'a> {
    pub prod: &'a [f64],
    pub q: usize,
    pub lam: &'a [f64],
    pub gam: &'a [f64],
}

/// Columns of a product row handled by [`rank_update`].
pub const MAX_Q: usize = 48;

/// Apply [`RankUpdate`] to `d` and `e` (R x R per candidate) and refresh `bt`
/// (see `bound_terms_of` in `exchange.rs`). `e` and `bt` may be empty (D).
pub fn rank_update<const R: usize>(
    u: &RankUpdate,
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) {
    assert!(u.q <= MAX_Q && u.lam.len() + u.gam.len() <= u.q);
    #[cfg(target_arch = "x86_64")]
    {
        if wide() {
            // SAFETY: the feature was detected at run time.
            return unsafe { rank_update_avx512::<R>(u, d, e, bt) };
        }
    }
    rank_update_body::<R>(u, d, e, bt)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn rank_update_avx512<const R: usize>(
    u: &RankUpdate,
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) {
    rank_update_body::<R>(u, d, e, bt)
}

#[inline(always)]
fn rank_update_body<const R: usize>(
    u: &RankUpdate,
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) {
    let rr = R * R;
    let n = d.len() / rr;
    let q = u.q;
    let (p, pe) = (u.lam.len(), u.gam.len());
    let mut y = [[Z; MAX_Q]; R];
    let mut t0 = 0;
    while t0 < n {
        let m = (n - t0).min(LANES);
        for l in 0..LANES {
            let t = t0 + l.min(m - 1);
            for a in 0..R {
                let row = &u.prod[(t * R + a) * q..(t * R + a + 1) * q];
                for (col, &v) in row[..p + pe].iter().enumerate() {
                    y[a][col][l] = v;
                }
            }
        }
        let e_g = if e.is_empty() {
            &mut [][..]
        } else {
            &mut e[t0 * rr..(t0 + m) * rr]
        };
        let bt_g = if bt.is_empty() {
            &mut [][..]
        } else {
            &mut bt[t0..t0 + m]
        };
        group_update::<R>(&y, u.lam, u.gam, &mut d[t0 * rr..(t0 + m) * rr], e_g, bt_g);
        t0 += m;
    }
}

/// The update of one group of at most [`LANES`] candidates (d, e: R x R each, e and bt
/// empty for D) from its product rows y (lane layout: y[a][column]).
#[inline(always)]
fn group_update<const R: usize>(
    y: &[[V; MAX_Q]; R],
    lam: &[f64],
    gam: &[f64],
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) {
    let rr = R * R;
    let m = d.len() / rr;
    let (p, pe) = (lam.len(), gam.len());
    let with_e = !e.is_empty();
    let mut dj = [[Z; R]; R];
    let mut ej = [[Z; R]; R];
    for l in 0..m {
        for a in 0..R {
            for c in 0..R {
                dj[a][c][l] = d[l * rr + a * R + c];
                if with_e {
                    ej[a][c][l] = e[l * rr + a * R + c];
                }
            }
        }
    }
    for a in 0..R {
        for c in 0..=a {
            let mut v = [-0.0; LANES];
            for col in 0..p {
                for l in 0..LANES {
                    v[l] += lam[col] * y[a][col][l] * y[c][col][l];
                }
            }
            for l in 0..LANES {
                dj[a][c][l] -= v[l];
            }
            if c != a {
                for l in 0..LANES {
                    dj[c][a][l] -= v[l];
                }
            }
            if with_e {
                let mut v = [-0.0; LANES];
                for col in 0..pe {
                    for l in 0..LANES {
                        v[l] += gam[col] * y[a][p + col][l] * y[c][p + col][l];
                    }
                }
                for l in 0..LANES {
                    ej[a][c][l] -= v[l];
                }
                if c != a {
                    for l in 0..LANES {
                        ej[c][a][l] -= v[l];
                    }
                }
            }
        }
    }
    for l in 0..m {
        for a in 0..R {
            for c in 0..R {
                d[l * rr + a * R + c] = dj[a][c][l];
                if with_e {
                    e[l * rr + a * R + c] = ej[a][c][l];
                }
            }
        }
    }
    if with_e {
        let b = bound_terms_body::<R>(&dj, &ej);
        bt.copy_from_slice(&b[..m]);
    }
}

/// The candidate blocks regrouped for [`soa_update`]: for each group of [`LANES`]
/// candidates, row a, each column t that is not zero for every candidate, the group's
/// values side by side (zero past the last candidate). Columns that are zero throughout
/// (common: a tracker row does not see every parameter) are left out.
#[derive(Debug, Clone, Default)]
pub struct Soa {
    data: Vec<f64>,
    /// Kept columns of each row.
    cols: Vec<Vec<usize>>,
    /// Kept columns over all rows (values per candidate).
    width: usize,
}

impl Soa {
    pub fn new(blocks: &[f64], n_cand: usize, r: usize, k: usize) -> Self {
        let cols: Vec<Vec<usize>> = (0..r)
            .map(|a| {
                (0..k)
                    .filter(|&t| (0..n_cand).any(|j| blocks[(j * r + a) * k + t] != 0.0))
                    .collect()
            })
            .collect();
        let width: usize = cols.iter().map(Vec::len).sum();
        let groups = n_cand.div_ceil(LANES);
        let mut data = vec![0.0; groups * width * LANES];
        for j in 0..n_cand {
            let (g, l) = (j / LANES, j % LANES);
            let mut at = g * width;
            for (a, ca) in cols.iter().enumerate() {
                for &t in ca {
                    data[at * LANES + l] = blocks[(j * r + a) * k + t];
                    at += 1;
                }
            }
        }
        Self { data, cols, width }
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
}

/// Whether [`soa_update`] has a kernel for blocks of r rows and q product columns here.
pub fn soa_kernel(r: usize, q: usize) -> bool {
    wide()
        && matches!(
            (r, q),
            (3, 18) | (3, 6) | (2, 12) | (2, 4) | (1, 6) | (1, 2)
        )
}

/// [`rank_update`] for the candidates from `first` (a multiple of [`LANES`]) on, with the
/// products B w (w: k x q, q = `lam.len() + gam.len()`) computed here from the regrouped
/// blocks `soa`, one group per pass (no product rows stored). The products use the same
/// fused multiply-adds in the same order as the skinny kernel, so the results are the same.
/// Returns false (nothing done) when no kernel for this r and q exists or AVX-512 is missing.
#[allow(clippy::too_many_arguments)]
pub fn soa_update(
    soa: &Soa,
    first: usize,
    r: usize,
    w: &[f64],
    lam: &[f64],
    gam: &[f64],
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        if !wide() || first % LANES != 0 {
            return false;
        }
        let q = lam.len() + gam.len();
        // SAFETY (all arms): the feature was detected at run time.
        unsafe {
            match (r, q) {
                (3, 18) => soa_update_avx512::<3, 18>(soa, first, w, lam, gam, d, e, bt),
                (3, 6) => soa_update_avx512::<3, 6>(soa, first, w, lam, gam, d, e, bt),
                (2, 12) => soa_update_avx512::<2, 12>(soa, first, w, lam, gam, d, e, bt),
                (2, 4) => soa_update_avx512::<2, 4>(soa, first, w, lam, gam, d, e, bt),
                (1, 6) => soa_update_avx512::<1, 6>(soa, first, w, lam, gam, d, e, bt),
                (1, 2) => soa_update_avx512::<1, 2>(soa, first, w, lam, gam, d, e, bt),
                _ => return false,
            }
        }
        true
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (soa, first, r, w, lam, gam, d, e, bt);
        false
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
unsafe fn soa_update_avx512<const R: usize, const Q: usize>(
    soa: &Soa,
    first: usize,
    w: &[f64],
    lam: &[f64],
    gam: &[f64],
    d: &mut [f64],
    e: &mut [f64],
    bt: &mut [[f64; 3]],
) {
    use std::arch::x86_64::*;
    let rr = R * R;
    let n = d.len() / rr;
    assert!(soa.cols.len() == R && Q <= MAX_Q);
    assert!(soa.cols.iter().flatten().all(|&t| w.len() >= (t + 1) * Q));
    let g0 = first / LANES;
    assert!(soa.data.len() >= (g0 + n.div_ceil(LANES)) * soa.width * LANES);
    let mut y = [[Z; MAX_Q]; R];
    let mut t0 = 0;
    while t0 < n {
        let m = (n - t0).min(LANES);
        let g = g0 + t0 / LANES;
        let mut at = soa.data.as_ptr().add(g * soa.width * LANES);
        for a in 0..R {
            let mut acc = [_mm512_setzero_pd(); Q];
            for &t in &soa.cols[a] {
                let b = _mm512_loadu_pd(at);
                at = at.add(LANES);
                let wt = w.as_ptr().add(t * Q);
                for col in 0..Q {
                    acc[col] = _mm512_fmadd_pd(b, _mm512_set1_pd(*wt.add(col)), acc[col]);
                }
            }
            for col in 0..Q {
                _mm512_storeu_pd(y[a][col].as_mut_ptr(), acc[col]);
            }
        }
        let e_g = if e.is_empty() {
            &mut [][..]
        } else {
            &mut e[t0 * rr..(t0 + m) * rr]
        };
        let bt_g = if bt.is_empty() {
            &mut [][..]
        } else {
            &mut bt[t0..t0 + m]
        };
        group_update::<R>(&y, lam, gam, &mut d[t0 * rr..(t0 + m) * rr], e_g, bt_g);
        t0 += m;
    }
}

/// Bound terms of each candidate of `d` and `e` (R x R each; see `bound_terms_of`).
pub fn bound_terms<const R: usize>(d: &[f64], e: &[f64], bt: &mut [[f64; 3]]) {
    #[cfg(target_arch = "x86_64")]
    {
        if wide() {
            // SAFETY: the feature was detected at run time.
            return unsafe { bound_terms_avx512::<R>(d, e, bt) };
        }
    }
    bound_terms_slice::<R>(d, e, bt)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn bound_terms_avx512<const R: usize>(d: &[f64], e: &[f64], bt: &mut [[f64; 3]]) {
    bound_terms_slice::<R>(d, e, bt)
}

#[inline(always)]
fn bound_terms_slice<const R: usize>(d: &[f64], e: &[f64], bt: &mut [[f64; 3]]) {
    let rr = R * R;
    let n = d.len() / rr;
    let mut t0 = 0;
    while t0 < n {
        let m = (n - t0).min(LANES);
        let mut dj = [[Z; R]; R];
        let mut ej = [[Z; R]; R];
        for l in 0..LANES {
            let t = t0 + l.min(m - 1);
            for a in 0..R {
                for c in 0..R {
                    dj[a][c][l] = d[t * rr + a * R + c];
                    ej[a][c][l] = e[t * rr + a * R + c];
                }
            }
        }
        let b = bound_terms_body::<R>(&dj, &ej);
        bt[t0..t0 + m].copy_from_slice(&b[..m]);
        t0 += m;
    }
}

/// Per lane: [sqrt(tr((I + d)^-1 e)), t / (1 + t) with t = tr d, tr((I + d)^-1 d)],
/// [INFINITY, 1, 1] where I + d is not positive definite (the same operations as
/// `dense::small_spd_trace_solves`).
#[inline(always)]
fn bound_terms_body<const R: usize>(dj: &[[V; R]; R], ej: &[[V; R]; R]) -> [[f64; 3]; LANES] {
    let mut lo = [[Z; R]; R];
    let mut inv_d = [Z; R];
    let mut bad = [false; LANES];
    for j in 0..R {
        let mut s = dj[j][j];
        for l in 0..LANES {
            s[l] += 1.0;
        }
        for p in 0..j {
            for l in 0..LANES {
                s[l] -= lo[j][p][l] * lo[j][p][l];
            }
        }
        for l in 0..LANES {
            if !(s[l] > 0.0) {
                bad[l] = true;
                s[l] = 1.0;
            }
            let dd = s[l].sqrt();
            lo[j][j][l] = dd;
            inv_d[j][l] = 1.0 / dd;
        }
        for i in j + 1..R {
            let mut s = dj[i][j];
            for p in 0..j {
                for l in 0..LANES {
                    s[l] -= lo[i][p][l] * lo[j][p][l];
                }
            }
            for l in 0..LANES {
                lo[i][j][l] = s[l] * inv_d[j][l];
            }
        }
    }
    let mut tr = [Z; 2];
    for (k, m) in [ej, dj].into_iter().enumerate() {
        for q in 0..R {
            let mut y = [Z; R];
            for a in 0..R {
                let mut v = m[a][q];
                for u in 0..a {
                    for l in 0..LANES {
                        v[l] -= lo[a][u][l] * y[u][l];
                    }
                }
                for l in 0..LANES {
                    y[a][l] = v[l] * inv_d[a][l];
                }
            }
            for a in (0..R).rev() {
                let mut v = y[a];
                for u in a + 1..R {
                    for l in 0..LANES {
                        v[l] -= lo[u][a][l] * y[u][l];
                    }
                }
                for l in 0..LANES {
                    y[a][l] = v[l] * inv_d[a][l];
                }
            }
            for l in 0..LANES {
                tr[k][l] += y[q][l];
            }
        }
    }
    let mut out = [[0.0; 3]; LANES];
    for l in 0..LANES {
        let mut t = 0.0;
        for a in 0..R {
            t += dj[a][a][l];
        }
        let t = t.max(0.0);
        out[l] = if bad[l] {
            [f64::INFINITY, 1.0, 1.0]
        } else {
            [tr[0][l].max(0.0).sqrt(), t / (1.0 + t), tr[1][l].max(0.0)]
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dense::small_spd_trace_solves;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random symmetric positive semi-definite 3 x 3 matrix (G G^T).
    fn spd(rng: &mut ChaCha8Rng) -> Vec<f64> {
        let g: Vec<f64> = (0..9).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut m = vec![0.0; 9];
        for a in 0..3 {
            for b in 0..3 {
                m[a * 3 + b] = (0..3).map(|t| g[a * 3 + t] * g[b * 3 + t]).sum();
            }
        }
        m
    }

    #[test]
    fn bound_terms_match_the_one_candidate_solves() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 13; // a full group and a partial one
        let (d, e): (Vec<f64>, Vec<f64>) = (
            (0..n).flat_map(|_| spd(&mut rng)).collect(),
            (0..n).flat_map(|_| spd(&mut rng)).collect(),
        );
        let mut bt = vec![[0.0; 3]; n];
        bound_terms::<3>(&d, &e, &mut bt);
        let mut generic = vec![[0.0; 3]; n];
        bound_terms_slice::<3>(&d, &e, &mut generic);
        for t in 0..n {
            let (dj, ej) = (&d[t * 9..(t + 1) * 9], &e[t * 9..(t + 1) * 9]);
            let mut pm = dj.to_vec();
            for a in 0..3 {
                pm[a * 3 + a] += 1.0;
            }
            let [a, tau] = small_spd_trace_solves(&pm, [ej, dj], 3).unwrap();
            let tr = dj[0] + dj[4] + dj[8];
            assert_eq!(bt[t], [a.sqrt(), tr / (1.0 + tr), tau]);
            assert_eq!(bt[t], generic[t]);
        }
    }

    #[test]
    fn exchange_values_match_the_direct_formula() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let cf: Vec<Vec<f64>> = (0..LANES)
            .map(|_| (0..18).map(|_| rng.random_range(-0.5..0.5)).collect())
            .collect();
        let d: Vec<Vec<f64>> = (0..LANES).map(|_| spd(&mut rng)).collect();
        let e: Vec<Vec<f64>> = (0..LANES).map(|_| spd(&mut rng)).collect();
        let mut qi = spd(&mut rng);
        for a in 0..3 {
            qi[a * 3 + a] += 1.0;
        }
        let qeq = spd(&mut rng);
        let x = ExchangeIn {
            cf: std::array::from_fn(|l| &cf[l][..]),
            d: std::array::from_fn(|l| &d[l][..]),
            e: std::array::from_fn(|l| &e[l][..]),
            qi: &qi,
            qeq: &qeq,
            value_minus: 100.0,
        };
        let v = exchange_values::<3>(&x);
        assert_eq!(v, exchange_values_body::<3>(&x));
        for l in 0..LANES {
            let c = |a: usize, q: usize| cf[l][a * 6 + q];
            let f = |a: usize, q: usize| cf[l][a * 6 + 3 + q];
            // P = I + d + c Qi c^T, e- = e + f Qi c^T + c Qi f^T + c Qeq c^T
            let mut p = vec![0.0; 9];
            let mut em = [0.0; 9];
            for a in 0..3 {
                for b in 0..3 {
                    let mut pv = d[l][a * 3 + b] + if a == b { 1.0 } else { 0.0 };
                    let mut ev = e[l][a * 3 + b];
                    for s in 0..3 {
                        for t in 0..3 {
                            pv += c(a, s) * qi[s * 3 + t] * c(b, t);
                            ev += f(a, s) * qi[s * 3 + t] * c(b, t)
                                + c(a, s) * qi[s * 3 + t] * f(b, t)
                                + c(a, s) * qeq[s * 3 + t] * c(b, t);
                        }
                    }
                    p[a * 3 + b] = pv;
                    em[a * 3 + b] = ev;
                }
            }
            let [t] = small_spd_trace_solves(&p, [&em[..]], 3).unwrap();
            let want = 100.0 - t;
            let want = if want > 0.0 { want } else { f64::INFINITY };
            assert!(
                (v[l] - want).abs() <= 1e-12 * want.abs(),
                "{} vs {want}",
                v[l]
            );
        }
    }
}
