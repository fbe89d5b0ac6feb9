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
    lane_values::<R>(&c, &f, &dj, &ej, x.qi, x.qeq, x.value_minus)
}

/// Per lane, the R x R product `c m` of the lanes' matrices `c` with one shared row-major
/// matrix `m`.
#[inline(always)]
fn times_matrix<const R: usize>(c: &[[V; R]; R], m: &[f64]) -> [[V; R]; R] {
    let mut out = [[Z; R]; R];
    for a in 0..R {
        for q in 0..R {
            let mut v = Z;
            for t in 0..R {
                let s = m[t * R + q];
                for l in 0..LANES {
                    v[l] += c[a][t][l] * s;
                }
            }
            out[a][q] = v;
        }
    }
    out
}

/// Per lane, the lower triangle of P = I + B F_-^-1 B^T = I + d + (c Qi) c^T, from the
/// lanes' `dj` (d), `cq` (c Qi) and `c`.
#[inline(always)]
fn exchanged_p<const R: usize>(dj: &[[V; R]; R], cq: &[[V; R]; R], c: &[[V; R]; R]) -> [[V; R]; R] {
    let mut pm = [[Z; R]; R];
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
    pm
}

/// Per lane, the Cholesky factor L (P = L L^T) of the lower triangle `pm`, in place. Returns
/// the lanes where P is not positive definite (a pivot not above 0, replaced by 1 to go on).
#[inline(always)]
fn cholesky_lanes<const R: usize>(pm: &mut [[V; R]; R]) -> [bool; LANES] {
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
    bad
}

/// Per lane, e- = e_j + f cQ^T + cQ f^T + c (Qi e_O Qi) c^T, from `ej`, `f`, `cq` (c Qi),
/// `cqe` (c Qi e_O Qi) and `c`.
#[inline(always)]
fn exchanged_e<const R: usize>(
    ej: &[[V; R]; R],
    f: &[[V; R]; R],
    cq: &[[V; R]; R],
    cqe: &[[V; R]; R],
    c: &[[V; R]; R],
) -> [[V; R]; R] {
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
    em
}

/// Per lane, tr(P^-1 e-) with P = L L^T: column q of L^-T L^-1 e- by forward then back
/// substitution, summing its q-th entry.
#[inline(always)]
fn trace_solve<const R: usize>(pm: &[[V; R]; R], em: &[[V; R]; R]) -> V {
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
    t
}

/// [`exchange_values`] from the lane-layout c = B F^-1 O^T, f = B F^-1 W F^-1 O^T, d and e.
#[inline(always)]
fn lane_values<const R: usize>(
    c: &[[V; R]; R],
    f: &[[V; R]; R],
    dj: &[[V; R]; R],
    ej: &[[V; R]; R],
    qi: &[f64],
    qeq: &[f64],
    value_minus: f64,
) -> V {
    let cq = times_matrix::<R>(c, qi); // c Qi
    let mut pm = exchanged_p::<R>(dj, &cq, c); // I + B F_-^-1 B^T
    let bad = cholesky_lanes::<R>(&mut pm);
    let cqe = times_matrix::<R>(c, qeq);
    let em = exchanged_e::<R>(ej, f, &cq, &cqe, c);
    let t = trace_solve::<R>(&pm, &em);
    let mut out = Z;
    for l in 0..LANES {
        let v = value_minus - t[l];
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
    /// The same values candidate by candidate (n_cand x stride, zero-padded to a multiple
    /// of [`LANES`]), for gathering scattered candidates.
    rows: Vec<f64>,
    stride: usize,
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
        let stride = width.div_ceil(LANES) * LANES;
        let mut rows = vec![0.0; n_cand * stride];
        for j in 0..n_cand {
            let (g, l) = (j / LANES, j % LANES);
            let mut i = 0;
            for (a, ca) in cols.iter().enumerate() {
                for &t in ca {
                    let v = blocks[(j * r + a) * k + t];
                    data[(g * width + i) * LANES + l] = v;
                    rows[j * stride + i] = v;
                    i += 1;
                }
            }
        }
        Self {
            data,
            cols,
            width,
            rows,
            stride,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
}

/// One row of the lane products: `acc[c] = sum_t b_t * w[t * width + c]` for `c < width`
/// (`width <= N`), where `b_t` are the eight lanes' values of kept column `t`, read in order
/// from `*at` (which moves past them). Shared by the AVX-512 kernels below.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn lane_row_products<const N: usize>(
    at: &mut *const f64,
    cols: &[usize],
    w: &[f64],
    width: usize,
) -> [std::arch::x86_64::__m512d; N] {
    use std::arch::x86_64::*;
    let mut acc = [_mm512_setzero_pd(); N];
    for &t in cols {
        let b = _mm512_loadu_pd(*at);
        *at = at.add(LANES);
        let wt = w.as_ptr().add(t * width);
        for col in 0..width {
            acc[col] = _mm512_fmadd_pd(b, _mm512_set1_pd(*wt.add(col)), acc[col]);
        }
    }
    acc
}

/// The visit of the A/I exchange over the candidates `js` (scattered, none the visited
/// point): B_j [F^-1 O^T, F^-1 W F^-1 O^T] with w = [F^-1 O^T, F^-1 W F^-1 O^T] (k x 2R), from the
/// regrouped blocks, eight candidates at a time, then [`exchange_values`]; the best
/// (value, candidate), lowest index on ties. `None`: no AVX-512 here.
#[allow(clippy::too_many_arguments)]
pub fn best_exchange<const R: usize>(
    soa: &Soa,
    js: &[usize],
    w: &[f64],
    d: &[f64],
    e: &[f64],
    qi: &[f64],
    qeq: &[f64],
    value_minus: f64,
) -> Option<(f64, usize)> {
    #[cfg(target_arch = "x86_64")]
    {
        if wide() && soa.cols.len() == R {
            // SAFETY: the feature was detected at run time.
            return Some(unsafe {
                best_exchange_avx512::<R>(soa, js, w, d, e, qi, qeq, value_minus)
            });
        }
    }
    let _ = (soa, js, w, d, e, qi, qeq, value_minus);
    None
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
unsafe fn best_exchange_avx512<const R: usize>(
    soa: &Soa,
    js: &[usize],
    w: &[f64],
    d: &[f64],
    e: &[f64],
    qi: &[f64],
    qeq: &[f64],
    value_minus: f64,
) -> (f64, usize) {
    use std::arch::x86_64::*;
    let (rr, sd, q2) = (R * R, soa.stride, 2 * R);
    assert!(soa.cols.iter().flatten().all(|&t| w.len() >= (t + 1) * q2));
    assert!(js
        .iter()
        .all(|&j| (j + 1) * sd <= soa.rows.len() && (j + 1) * rr <= d.len().min(e.len())));
    let mut buf = vec![0.0f64; sd * LANES];
    let mut best = (f64::INFINITY, usize::MAX);
    let fetch = |j: usize| {
        let p = soa.rows.as_ptr().add(j * sd);
        for at in (0..sd).step_by(8) {
            _mm_prefetch(p.add(at) as *const i8, _MM_HINT_T0);
        }
        _mm_prefetch(d.as_ptr().add(j * rr) as *const i8, _MM_HINT_T0);
        _mm_prefetch(e.as_ptr().add(j * rr) as *const i8, _MM_HINT_T0);
    };
    for &j in js.iter().take(LANES) {
        fetch(j);
    }
    for (g, grp) in js.chunks(LANES).enumerate() {
        for &j in js.iter().skip((g + 1) * LANES).take(LANES) {
            fetch(j);
        }
        let m = grp.len();
        let src: [*const f64; LANES] =
            std::array::from_fn(|l| soa.rows.as_ptr().add(grp[l.min(m - 1)] * sd));
        for i0 in (0..sd).step_by(LANES) {
            transpose8(src.map(|p| p.add(i0)), buf.as_mut_ptr().add(i0 * LANES));
        }
        let mut dj = [[Z; R]; R];
        let mut ej = [[Z; R]; R];
        for l in 0..LANES {
            let j = grp[l.min(m - 1)];
            for a in 0..R {
                for c in 0..R {
                    dj[a][c][l] = d[j * rr + a * R + c];
                    ej[a][c][l] = e[j * rr + a * R + c];
                }
            }
        }
        let mut y = [[Z; 2 * MAX_LANE_R]; R];
        let mut at = buf.as_ptr();
        for a in 0..R {
            let acc = lane_row_products::<{ 2 * MAX_LANE_R }>(&mut at, &soa.cols[a], w, q2);
            for col in 0..q2 {
                _mm512_storeu_pd(y[a][col].as_mut_ptr(), acc[col]);
            }
        }
        let c: [[V; R]; R] = std::array::from_fn(|a| std::array::from_fn(|q| y[a][q]));
        let f: [[V; R]; R] = std::array::from_fn(|a| std::array::from_fn(|q| y[a][R + q]));
        let v = lane_values::<R>(&c, &f, &dj, &ej, qi, qeq, value_minus);
        for (l, &j) in grp.iter().enumerate() {
            let x = if v[l].is_nan() { f64::INFINITY } else { v[l] };
            if x.total_cmp(&best.0).then(j.cmp(&best.1)).is_lt() {
                best = (x, j);
            }
        }
    }
    best
}

/// out[c * 8 + l] = rows[l][c] for an 8 x 8 block (rows: 8 values each).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn transpose8(rows: [*const f64; LANES], out: *mut f64) {
    use std::arch::x86_64::*;
    let r: [__m512d; 8] = std::array::from_fn(|l| _mm512_loadu_pd(rows[l]));
    let lo = |a: usize, b: usize| _mm512_unpacklo_pd(r[a], r[b]);
    let hi = |a: usize, b: usize| _mm512_unpackhi_pd(r[a], r[b]);
    let (t0, t1, t2, t3) = (lo(0, 1), hi(0, 1), lo(2, 3), hi(2, 3));
    let (t4, t5, t6, t7) = (lo(4, 5), hi(4, 5), lo(6, 7), hi(6, 7));
    // 128-bit lanes (0, 2) / (1, 3) of the two operands
    let even = |a: __m512d, b: __m512d| _mm512_shuffle_f64x2::<0x88>(a, b);
    let odd = |a: __m512d, b: __m512d| _mm512_shuffle_f64x2::<0xDD>(a, b);
    let (s0, s1, s2, s3) = (even(t0, t2), odd(t0, t2), even(t4, t6), odd(t4, t6));
    let (s4, s5, s6, s7) = (even(t1, t3), odd(t1, t3), even(t5, t7), odd(t5, t7));
    let cols = [
        even(s0, s2),
        even(s4, s6),
        even(s1, s3),
        even(s5, s7),
        odd(s0, s2),
        odd(s4, s6),
        odd(s1, s3),
        odd(s5, s7),
    ];
    for (c, v) in cols.into_iter().enumerate() {
        _mm512_storeu_pd(out.add(c * LANES), v);
    }
}

/// Largest block height of the lane kernels.
const MAX_LANE_R: usize = 3;

/// The first-order screening of K and E (see `Run::visit_spectral`): with
/// h_q = |B_j w_q|^2 (sum over the rows), the estimates base_q + h_q - h_o_q give the
/// smallest eigenvalue (the first `s_lo`) and the largest (the others, and `hi0`).
pub struct Screen<'a> {
    pub base: &'a [f64],
    pub h_o: &'a [f64],
    pub s_lo: usize,
    pub hi0: f64,
    /// K: sqrt(l_max / l_min); else (E) 1 / l_min. Not positive or NaN: INFINITY.
    pub ratio: bool,
}

/// [`Screen`] values of the candidates first.. of `out` (`first` a multiple of [`LANES`]),
/// with w (k x s) from the regrouped blocks: the same products and sums as the row kernel.
/// False (nothing done): no kernel here.
pub fn soa_screen(
    soa: &Soa,
    first: usize,
    r: usize,
    w: &[f64],
    sc: &Screen,
    out: &mut [f64],
) -> bool {
    let s = sc.base.len();
    #[cfg(target_arch = "x86_64")]
    {
        if !wide() || first % LANES != 0 || soa.cols.len() != r {
            return false;
        }
        // SAFETY (all arms): the feature was detected at run time.
        unsafe {
            match (r, s) {
                (3, 6) => soa_screen_avx512::<3, 6>(soa, first, w, sc, out),
                (3, 4) => soa_screen_avx512::<3, 4>(soa, first, w, sc, out),
                (2, 6) => soa_screen_avx512::<2, 6>(soa, first, w, sc, out),
                (2, 4) => soa_screen_avx512::<2, 4>(soa, first, w, sc, out),
                (1, 6) => soa_screen_avx512::<1, 6>(soa, first, w, sc, out),
                (1, 4) => soa_screen_avx512::<1, 4>(soa, first, w, sc, out),
                _ => return false,
            }
        }
        true
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (soa, first, r, w, s, sc, out);
        false
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn soa_screen_avx512<const R: usize, const S: usize>(
    soa: &Soa,
    first: usize,
    w: &[f64],
    sc: &Screen,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let n = out.len();
    assert!(sc.h_o.len() >= S && sc.s_lo <= S);
    assert!(soa.cols.iter().flatten().all(|&t| w.len() >= (t + 1) * S));
    let g0 = first / LANES;
    assert!(soa.data.len() >= (g0 + n.div_ceil(LANES)) * soa.width * LANES);
    let mut t0 = 0;
    while t0 < n {
        let m = (n - t0).min(LANES);
        let g = g0 + t0 / LANES;
        let mut at = soa.data.as_ptr().add(g * soa.width * LANES);
        let mut hs = [[-0.0f64; LANES]; S];
        for _a in 0..R {
            let acc = lane_row_products::<S>(&mut at, &soa.cols[_a], w, S);
            for q in 0..S {
                let mut y = Z;
                _mm512_storeu_pd(y.as_mut_ptr(), acc[q]);
                for l in 0..LANES {
                    hs[q][l] += y[l] * y[l];
                }
            }
        }
        let mut lo = [f64::INFINITY; LANES];
        let mut hi = [sc.hi0; LANES];
        for q in 0..S {
            for l in 0..LANES {
                let est = sc.base[q] + hs[q][l] - sc.h_o[q];
                if q < sc.s_lo {
                    lo[l] = lo[l].min(est);
                } else {
                    hi[l] = hi[l].max(est);
                }
            }
        }
        for l in 0..m {
            let v = if !(lo[l] > 0.0) {
                f64::INFINITY
            } else if sc.ratio {
                (hi[l] / lo[l]).sqrt()
            } else {
                1.0 / lo[l]
            };
            out[t0 + l] = if v.is_nan() { f64::INFINITY } else { v };
        }
        t0 += m;
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
            let acc = lane_row_products::<Q>(&mut at, &soa.cols[a], w, Q);
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

    /// Blocks (n x 3 x k) with some columns zero for every candidate, as a machine model gives.
    fn sparse_blocks(rng: &mut ChaCha8Rng, n: usize, k: usize) -> Vec<f64> {
        (0..n * 3 * k)
            .map(|i| {
                let (a, t) = ((i / k) % 3, i % k);
                if (a + t) % 4 == 0 {
                    0.0
                } else {
                    rng.random_range(-1.0..1.0)
                }
            })
            .collect()
    }

    #[test]
    fn lane_group_kernels_match_the_row_products() {
        if !wide() {
            return; // the lane-group kernels need AVX-512; the row path is used instead
        }
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (n, k) = (21, 13); // groups of 8 with a remainder; rows not a multiple of 8
        let blocks = sparse_blocks(&mut rng, n, k);
        let soa = Soa::new(&blocks, n, 3, k);
        let row_product = |j: usize, a: usize, w: &[f64], q: usize, col: usize| {
            (0..k).fold(0.0, |s: f64, t| {
                blocks[(j * 3 + a) * k + t].mul_add(w[t * q + col], s)
            })
        };
        // visit: scattered candidates against exchange_values on the row products
        let w: Vec<f64> = (0..k * 6).map(|_| rng.random_range(-0.3..0.3)).collect();
        let d: Vec<f64> = (0..n).flat_map(|_| spd(&mut rng)).collect();
        let e: Vec<f64> = (0..n).flat_map(|_| spd(&mut rng)).collect();
        let mut qi = spd(&mut rng);
        for a in 0..3 {
            qi[a * 3 + a] += 1.0;
        }
        let qeq = spd(&mut rng);
        let js = [20usize, 3, 17, 5, 9, 0, 11, 14, 2, 19, 7];
        let best = best_exchange::<3>(&soa, &js, &w, &d, &e, &qi, &qeq, 50.0).unwrap();
        let cf: Vec<Vec<f64>> = js
            .iter()
            .map(|&j| {
                (0..18)
                    .map(|i| row_product(j, i / 6, &w, 6, i % 6))
                    .collect()
            })
            .collect();
        let mut want = (f64::INFINITY, usize::MAX);
        for g in 0..js.len().div_ceil(LANES) {
            let at = |l: usize| (g * LANES + l).min(js.len() - 1);
            let x = ExchangeIn {
                cf: std::array::from_fn(|l| &cf[at(l)][..]),
                d: std::array::from_fn(|l| &d[js[at(l)] * 9..js[at(l)] * 9 + 9]),
                e: std::array::from_fn(|l| &e[js[at(l)] * 9..js[at(l)] * 9 + 9]),
                qi: &qi,
                qeq: &qeq,
                value_minus: 50.0,
            };
            let v = exchange_values::<3>(&x);
            for l in 0..LANES.min(js.len() - g * LANES) {
                let c = (v[l], js[g * LANES + l]);
                if c.0.total_cmp(&want.0).then(c.1.cmp(&want.1)).is_lt() {
                    want = c;
                }
            }
        }
        assert!(best.1 == want.1 && (best.0 - want.0).abs() <= 1e-12 * want.0.abs());
        // update: the lane-group products against the row-product update
        let (lam, gam) = ([0.5, -0.2, 0.1, 0.3, -0.4, 0.2], [0.1; 12]);
        let w: Vec<f64> = (0..k * 18).map(|_| rng.random_range(-0.3..0.3)).collect();
        let prod: Vec<f64> = (0..n * 3 * 18)
            .map(|i| row_product(i / 54, (i / 18) % 3, &w, 18, i % 18))
            .collect();
        let (mut d1, mut e1, mut b1) = (d.clone(), e.clone(), vec![[0.0; 3]; n]);
        let u = RankUpdate {
            prod: &prod,
            q: 18,
            lam: &lam,
            gam: &gam,
        };
        rank_update::<3>(&u, &mut d1, &mut e1, &mut b1);
        let (mut d2, mut e2, mut b2) = (d.clone(), e.clone(), vec![[0.0; 3]; n]);
        assert!(soa_update(
            &soa, 0, 3, &w, &lam, &gam, &mut d2, &mut e2, &mut b2
        ));
        for i in 0..n * 9 {
            assert!((d1[i] - d2[i]).abs() <= 1e-13 && (e1[i] - e2[i]).abs() <= 1e-13);
        }
        // spectral screening: K ratio and E inverse from the same squared projections
        let w: Vec<f64> = (0..k * 6).map(|_| rng.random_range(-0.3..0.3)).collect();
        let (base, h_o) = ([0.5, 0.6, 0.7, 0.8, 5.0, 6.0], [0.1; 6]);
        for ratio in [true, false] {
            let sc = Screen {
                base: &base,
                h_o: &h_o,
                s_lo: 4,
                hi0: 6.5,
                ratio,
            };
            let mut got = vec![0.0; n];
            assert!(soa_screen(&soa, 0, 3, &w, &sc, &mut got));
            for j in 0..n {
                let est = |q: usize| {
                    let h: f64 = (0..3).map(|a| row_product(j, a, &w, 6, q).powi(2)).sum();
                    base[q] + h - h_o[q]
                };
                let lo = (0..4).map(est).fold(f64::INFINITY, f64::min);
                let hi = (4..6).map(est).fold(6.5, f64::max);
                let want = if ratio { (hi / lo).sqrt() } else { 1.0 / lo };
                assert!(
                    (got[j] - want).abs() <= 1e-12 * want,
                    "{} vs {want}",
                    got[j]
                );
            }
        }
    }
}
