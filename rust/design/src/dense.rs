//! Small dense linear algebra on row-major slices: the k x k information matrix
//! and the (2r) x (2r) capacitance matrices of the low-rank updates.

use nalgebra::{DMatrix, SymmetricEigen};

/// `f += sign * b^T b` for an r x k block `b` (row-major) and a k x k matrix `f`.
pub fn gram_add(f: &mut [f64], b: &[f64], r: usize, k: usize, sign: f64) {
    for row in b.chunks_exact(k).take(r) {
        for a in 0..k {
            let ra = sign * row[a];
            if ra == 0.0 {
                continue;
            }
            let fa = &mut f[a * k..(a + 1) * k];
            for (fb, &rb) in fa.iter_mut().zip(row) {
                *fb += ra * rb;
            }
        }
    }
}

/// Inverse and log-determinant of a symmetric positive definite k x k matrix
/// (Cholesky); `None` when it is not numerically positive definite.
pub fn spd_inverse(a: &[f64], k: usize) -> Option<(Vec<f64>, f64)> {
    let mut l = vec![0.0; k * k];
    let mut logdet = 0.0;
    for j in 0..k {
        let mut s = a[j * k + j];
        for p in 0..j {
            s -= l[j * k + p] * l[j * k + p];
        }
        if !(s > 0.0) || !s.is_finite() {
            return None;
        }
        let d = s.sqrt();
        logdet += 2.0 * d.ln();
        l[j * k + j] = d;
        for i in j + 1..k {
            let mut s = a[i * k + j];
            for p in 0..j {
                s -= l[i * k + p] * l[j * k + p];
            }
            l[i * k + j] = s / d;
        }
    }
    // Invert L (lower triangular), then A^-1 = L^-T L^-1.
    let mut li = vec![0.0; k * k];
    for j in 0..k {
        li[j * k + j] = 1.0 / l[j * k + j];
        for i in j + 1..k {
            let mut s = 0.0;
            for p in j..i {
                s -= l[i * k + p] * li[p * k + j];
            }
            li[i * k + j] = s / l[i * k + i];
        }
    }
    let mut inv = vec![0.0; k * k];
    for i in 0..k {
        for j in 0..=i {
            let mut s = 0.0;
            for p in i..k {
                s += li[p * k + i] * li[p * k + j];
            }
            inv[i * k + j] = s;
            inv[j * k + i] = s;
        }
    }
    Some((inv, logdet))
}

/// LU factorisation with partial pivoting of an n x n matrix in place.
/// Returns the determinant, or `None` for an exactly singular pivot.
pub fn lu_in_place(a: &mut [f64], piv: &mut [usize], n: usize) -> Option<f64> {
    let mut det = 1.0;
    for (i, p) in piv.iter_mut().enumerate().take(n) {
        *p = i;
    }
    for c in 0..n {
        let mut best = c;
        let mut big = a[c * n + c].abs();
        for r in c + 1..n {
            let v = a[r * n + c].abs();
            if v > big {
                big = v;
                best = r;
            }
        }
        if big == 0.0 || !big.is_finite() {
            return None;
        }
        if best != c {
            for j in 0..n {
                a.swap(c * n + j, best * n + j);
            }
            piv.swap(c, best);
            det = -det;
        }
        let d = a[c * n + c];
        det *= d;
        for r in c + 1..n {
            let f = a[r * n + c] / d;
            a[r * n + c] = f;
            if f != 0.0 {
                for j in c + 1..n {
                    a[r * n + j] -= f * a[c * n + j];
                }
            }
        }
    }
    Some(det)
}

/// Inverse from an LU factorisation made by [`lu_in_place`].
pub fn lu_inverse(lu: &[f64], piv: &[usize], n: usize, out: &mut [f64]) {
    for col in 0..n {
        // Solve A x = e_col: P A = L U, so L U x = P e_col.
        let x = &mut out[..];
        let mut y = [0.0f64; MAX_P];
        for i in 0..n {
            let mut s = if piv[i] == col { 1.0 } else { 0.0 };
            for j in 0..i {
                s -= lu[i * n + j] * y[j];
            }
            y[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = y[i];
            for j in i + 1..n {
                s -= lu[i * n + j] * y[j];
            }
            y[i] = s / lu[i * n + i];
        }
        for i in 0..n {
            x[i * n + col] = y[i];
        }
    }
}

/// Cholesky inverse and log-determinant of a small (r <= MAX_R) SPD matrix into `inv`;
/// `None` when a pivot is not positive.
pub fn small_spd_inverse(a: &[f64], r: usize, inv: &mut [f64]) -> Option<f64> {
    let mut l = [0.0f64; MAX_R * MAX_R];
    let mut logdet = 0.0;
    for j in 0..r {
        let mut s = a[j * r + j];
        for p in 0..j {
            s -= l[j * r + p] * l[j * r + p];
        }
        if !(s > 0.0) {
            return None;
        }
        let d = s.sqrt();
        logdet += 2.0 * d.ln();
        l[j * r + j] = d;
        for i in j + 1..r {
            let mut s = a[i * r + j];
            for p in 0..j {
                s -= l[i * r + p] * l[j * r + p];
            }
            l[i * r + j] = s / d;
        }
    }
    let mut li = [0.0f64; MAX_R * MAX_R];
    for j in 0..r {
        li[j * r + j] = 1.0 / l[j * r + j];
        for i in j + 1..r {
            let mut s = 0.0;
            for p in j..i {
                s -= l[i * r + p] * li[p * r + j];
            }
            li[i * r + j] = s / l[i * r + i];
        }
    }
    for i in 0..r {
        for j in 0..=i {
            let mut s = 0.0;
            for p in i..r {
                s += li[p * r + i] * li[p * r + j];
            }
            inv[i * r + j] = s;
            inv[j * r + i] = s;
        }
    }
    Some(logdet)
}

/// tr(A^-1 E) for a small (r <= MAX_R) SPD matrix A and any r x r E (Cholesky solves);
/// `None` when a pivot is not positive.
pub fn small_spd_trace_solve(a: &[f64], e: &[f64], r: usize) -> Option<f64> {
    small_spd_trace_solves(a, [e], r).map(|t| t[0])
}

/// [`small_spd_trace_solve`] for several E with one factorisation of A.
pub fn small_spd_trace_solves<const N: usize>(
    a: &[f64],
    es: [&[f64]; N],
    r: usize,
) -> Option<[f64; N]> {
    match r {
        1 => trace_solves::<1, N>(a, es),
        2 => trace_solves::<2, N>(a, es),
        3 => trace_solves::<3, N>(a, es),
        4 => trace_solves::<4, N>(a, es),
        5 => trace_solves::<5, N>(a, es),
        6 => trace_solves::<6, N>(a, es),
        7 => trace_solves::<7, N>(a, es),
        _ => trace_solves::<MAX_R, N>(a, es),
    }
}

#[inline(always)]
fn trace_solves<const R: usize, const N: usize>(a: &[f64], es: [&[f64]; N]) -> Option<[f64; N]> {
    let mut l = [[0.0f64; R]; R];
    let mut inv_d = [0.0f64; R];
    for j in 0..R {
        let mut s = a[j * R + j];
        for p in 0..j {
            s -= l[j][p] * l[j][p];
        }
        if !(s > 0.0) {
            return None;
        }
        let d = s.sqrt();
        l[j][j] = d;
        inv_d[j] = 1.0 / d;
        for i in j + 1..R {
            let mut s = a[i * R + j];
            for p in 0..j {
                s -= l[i][p] * l[j][p];
            }
            l[i][j] = s * inv_d[j];
        }
    }
    let mut out = [0.0; N];
    for (e, t) in es.iter().zip(out.iter_mut()) {
        for q in 0..R {
            // x = A^-1 e[:, q]; accumulate x[q]
            let mut y = [0.0f64; R];
            for a_ in 0..R {
                let mut v = e[a_ * R + q];
                for u in 0..a_ {
                    v -= l[a_][u] * y[u];
                }
                y[a_] = v * inv_d[a_];
            }
            for a_ in (0..R).rev() {
                let mut v = y[a_];
                for u in a_ + 1..R {
                    v -= l[u][a_] * y[u];
                }
                y[a_] = v * inv_d[a_];
            }
            *t += y[q];
        }
    }
    Some(out)
}

/// Largest number of rows a design point may contribute.
pub const MAX_R: usize = 8;
/// Largest size of an exchange capacitance matrix (2 * MAX_R).
pub const MAX_P: usize = 2 * MAX_R;

/// Eigenvalues (ascending) and eigenvectors (column j of the k x k row-major
/// result belongs to eigenvalue j) of a symmetric matrix.
pub fn sym_eig(a: &[f64], k: usize) -> (Vec<f64>, Vec<f64>) {
    let m = DMatrix::from_row_slice(k, k, a);
    let eig = SymmetricEigen::new(m);
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let vals = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let mut vecs = vec![0.0; k * k];
    for (c, &i) in order.iter().enumerate() {
        for r in 0..k {
            vecs[r * k + c] = eig.eigenvectors[(r, i)];
        }
    }
    (vals, vecs)
}

/// Eigenvalues of a symmetric matrix, ascending.
pub fn sym_eigenvalues(a: &[f64], k: usize) -> Vec<f64> {
    let m = DMatrix::from_row_slice(k, k, a);
    let mut v: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
    v.sort_by(|a, b| a.total_cmp(b));
    v
}

/// `out (m x p) = a (m x n) * b^T` where `b` is p x n; all row-major.
pub fn mul_abt(a: &[f64], b: &[f64], m: usize, n: usize, p: usize, out: &mut [f64]) {
    for i in 0..m {
        let ai = &a[i * n..(i + 1) * n];
        for j in 0..p {
            let bj = &b[j * n..(j + 1) * n];
            out[i * p + j] = dot(ai, bj);
        }
    }
}

/// `out (m x n) = a (m x n) * s` for a symmetric n x n matrix `s`.
pub fn mul_ab(a: &[f64], s: &[f64], m: usize, n: usize, out: &mut [f64]) {
    for i in 0..m {
        let ai = &a[i * n..(i + 1) * n];
        let oi = &mut out[i * n..(i + 1) * n];
        oi.iter_mut().for_each(|v| *v = 0.0);
        for (q, &aq) in ai.iter().enumerate() {
            if aq == 0.0 {
                continue;
            }
            for (o, &sv) in oi.iter_mut().zip(&s[q * n..(q + 1) * n]) {
                *o += aq * sv;
            }
        }
    }
}

#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let chunks = a.len() / 4;
    for c in 0..chunks {
        let i = 4 * c;
        s[0] += a[i] * b[i];
        s[1] += a[i + 1] * b[i + 1];
        s[2] += a[i + 2] * b[i + 2];
        s[3] += a[i + 3] * b[i + 3];
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for i in 4 * chunks..a.len() {
        t += a[i] * b[i];
    }
    t
}

/// `out (m x q) = a (m x k) * w (k x q)`, all row-major, for small q: the
/// skinny products of the exchange, without the packing a general GEMM does. Uses
/// AVX2 + FMA when the processor has them; each output is one fixed sequence of
/// operations, so the result does not depend on threads or chunking.
pub fn skinny_mul(a: &[f64], m: usize, k: usize, w: &[f64], q: usize, out: &mut [f64]) {
    assert!(a.len() >= m * k);
    skinny_rows(&|i| &a[i * k..(i + 1) * k], m, k, w, q, out);
}

/// As [`skinny_mul`] with row i of the left factor given by `row(i)` (k values each).
pub fn skinny_rows<'a>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    out: &mut [f64],
) {
    assert!(w.len() >= k * q && out.len() >= m * q);
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the feature was detected at run time.
            unsafe { skinny_avx512(row, m, k, w, q, out) };
            return;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the features were detected at run time.
            unsafe { skinny_fma(row, m, k, w, q, out) };
            return;
        }
    }
    skinny_dispatch::<false>(row, m, k, w, q, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn skinny_fma<'a>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    out: &mut [f64],
) {
    skinny_dispatch::<true>(row, m, k, w, q, out);
}

/// AVX-512 kernel: column slabs of up to 24 (3 vectors of 8), 8 rows at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn skinny_avx512<'a>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    out: &mut [f64],
) {
    let mut c0 = 0;
    while c0 < q {
        let qc = (q - c0).min(24);
        match qc.div_ceil(8) {
            1 => avx512_body::<1, 8>(row, m, k, w, q, c0, qc, out),
            2 => avx512_body::<2, 8>(row, m, k, w, q, c0, qc, out),
            _ => avx512_body::<3, 8>(row, m, k, w, q, c0, qc, out),
        }
        c0 += qc;
    }
}

/// Columns c0 .. c0 + qc (at most 8 NV) of the product, MR rows per register tile.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
unsafe fn avx512_body<'a, const NV: usize, const MR: usize>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    c0: usize,
    qc: usize,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let nr = 8 * NV;
    let mut wp = vec![0.0f64; k * nr];
    for t in 0..k {
        wp[t * nr..t * nr + qc].copy_from_slice(&w[t * q + c0..t * q + c0 + qc]);
    }
    let mut i = 0;
    while i < m {
        let mr = (m - i).min(MR);
        let rows: [&[f64]; MR] = std::array::from_fn(|ii| &row(i + ii.min(mr - 1))[..k]);
        let mut acc = [[_mm512_setzero_pd(); NV]; MR];
        for t in 0..k {
            let wt: [__m512d; NV] =
                std::array::from_fn(|v| _mm512_loadu_pd(wp.as_ptr().add(t * nr + 8 * v)));
            for ii in 0..MR {
                let x = _mm512_set1_pd(*rows[ii].get_unchecked(t));
                for v in 0..NV {
                    acc[ii][v] = _mm512_fmadd_pd(x, wt[v], acc[ii][v]);
                }
            }
        }
        for ii in 0..mr {
            let o = out[(i + ii) * q + c0..(i + ii) * q + c0 + qc].as_mut_ptr();
            for v in 0..NV {
                let n = qc.saturating_sub(8 * v).min(8);
                // SAFETY: lanes below n are inside this row's qc outputs.
                if n == 8 {
                    _mm512_storeu_pd(o.add(8 * v), acc[ii][v]);
                } else {
                    let mut tile = [0.0f64; 8];
                    _mm512_storeu_pd(tile.as_mut_ptr(), acc[ii][v]);
                    for c in 0..n {
                        *o.add(8 * v + c) = tile[c];
                    }
                }
            }
        }
        i += mr;
    }
}

#[inline(always)]
fn skinny_dispatch<'a, const FMA: bool>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    out: &mut [f64],
) {
    // column slabs of at most 16 (more accumulators than registers would spill)
    let mut c0 = 0;
    while c0 < q {
        let qc = (q - c0).min(16);
        if qc <= 4 {
            skinny_body::<FMA, 4, 8>(row, m, k, w, q, c0, qc, out);
        } else if qc <= 8 {
            skinny_body::<FMA, 8, 4>(row, m, k, w, q, c0, qc, out);
        } else {
            skinny_body::<FMA, 16, 2>(row, m, k, w, q, c0, qc, out);
        }
        c0 += qc;
    }
}

/// Register-blocked kernel for output columns c0 .. c0 + qc: MR rows at a time against
/// those columns of w padded to NR.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn skinny_body<'a, const FMA: bool, const NR: usize, const MR: usize>(
    row: &(dyn Fn(usize) -> &'a [f64] + Sync),
    m: usize,
    k: usize,
    w: &[f64],
    q: usize,
    c0: usize,
    qc: usize,
    out: &mut [f64],
) {
    let mut wp = vec![0.0f64; k * NR];
    for t in 0..k {
        wp[t * NR..t * NR + qc].copy_from_slice(&w[t * q + c0..t * q + c0 + qc]);
    }
    let fma = |x: f64, y: f64, s: f64| if FMA { x.mul_add(y, s) } else { s + x * y };
    let mut i = 0;
    while i + MR <= m {
        let rows: [&[f64]; MR] = std::array::from_fn(|ii| &row(i + ii)[..k]);
        let mut acc = [[0.0f64; NR]; MR];
        for t in 0..k {
            #[allow(clippy::unwrap_used, reason = "a slice of exactly NR values always converts to [f64; NR]")]
            let wt: &[f64; NR] = wp[t * NR..(t + 1) * NR].try_into().unwrap();
            for (acc_i, r_i) in acc.iter_mut().zip(rows.iter()) {
                let x = r_i[t];
                for c in 0..NR {
                    acc_i[c] = fma(x, wt[c], acc_i[c]);
                }
            }
        }
        for (ii, acc_i) in acc.iter().enumerate() {
            out[(i + ii) * q + c0..(i + ii) * q + c0 + qc].copy_from_slice(&acc_i[..qc]);
        }
        i += MR;
    }
    while i < m {
        let r_i = &row(i)[..k];
        let mut acc = [0.0f64; NR];
        for t in 0..k {
            let x = r_i[t];
            for c in 0..NR {
                acc[c] = fma(x, wp[t * NR + c], acc[c]);
            }
        }
        out[i * q + c0..i * q + c0 + qc].copy_from_slice(&acc[..qc]);
        i += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_solve_matches_the_inverse() {
        let a = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let e = [1.0, 0.3, -0.2, 0.5, 2.0, 0.1, 0.0, -0.4, 0.7];
        let mut inv = [0.0; 9];
        small_spd_inverse(&a, 3, &mut inv).unwrap();
        let want: f64 = (0..3)
            .map(|i| (0..3).map(|j| inv[i * 3 + j] * e[j * 3 + i]).sum::<f64>())
            .sum();
        let got = small_spd_trace_solve(&a, &e, 3).unwrap();
        assert!(
            (got - want).abs() < 1e-14 * want.abs().max(1.0),
            "{got} vs {want}"
        );
        assert!(small_spd_trace_solve(&[-1.0], &[1.0], 1).is_none());
    }

    #[test]
    fn skinny_products_match_the_naive_product() {
        // m not a multiple of the row blocking, q on both sides of 8, k not a multiple of 4
        for &(m, k, q) in &[
            (7usize, 5usize, 3usize),
            (9, 32, 6),
            (10, 33, 12),
            (1, 1, 16),
            (17, 32, 18),
            (3, 7, 30),
        ] {
            let a: Vec<f64> = (0..m * k)
                .map(|i| ((i * 37 % 101) as f64 - 50.0) / 7.0)
                .collect();
            let w: Vec<f64> = (0..k * q)
                .map(|i| ((i * 53 % 89) as f64 - 44.0) / 9.0)
                .collect();
            let mut naive = vec![0.0; m * q];
            for i in 0..m {
                for c in 0..q {
                    naive[i * q + c] = (0..k).map(|t| a[i * k + t] * w[t * q + c]).sum();
                }
            }
            let mut fast = vec![0.0; m * q];
            skinny_mul(&a, m, k, &w, q, &mut fast);
            let mut plain = vec![0.0; m * q];
            skinny_dispatch::<false>(&|i| &a[i * k..(i + 1) * k], m, k, &w, q, &mut plain);
            for t in 0..m * q {
                let tol = 1e-12 * (1.0 + naive[t].abs()) * k as f64;
                assert!((fast[t] - naive[t]).abs() < tol, "{m}x{k}x{q} [{t}]");
                assert!((plain[t] - naive[t]).abs() < tol, "{m}x{k}x{q} [{t}]");
            }
        }
    }

    #[test]
    fn spd_inverse_and_logdet() {
        let a = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let (inv, logdet) = spd_inverse(&a, 3).unwrap();
        let mut prod = [0.0; 9];
        mul_ab(&a, &inv, 3, 3, &mut prod);
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((prod[i * 3 + j] - want).abs() < 1e-12);
            }
        }
        let mut lu = a;
        let mut piv = [0; 3];
        let det = lu_in_place(&mut lu, &mut piv, 3).unwrap();
        assert!((det.ln() - logdet).abs() < 1e-12);
        let mut inv2 = [0.0; 9];
        lu_inverse(&lu, &piv, 3, &mut inv2);
        for i in 0..9 {
            assert!((inv[i] - inv2[i]).abs() < 1e-12);
        }
        assert!(spd_inverse(&[1.0, 2.0, 2.0, 1.0], 2).is_none());
    }

    #[test]
    fn eigen_sorted() {
        let (vals, vecs) = sym_eig(&[2.0, 1.0, 1.0, 2.0], 2);
        assert!((vals[0] - 1.0).abs() < 1e-12 && (vals[1] - 3.0).abs() < 1e-12);
        // first eigenvector ~ (1, -1)/sqrt 2
        assert!((vecs[0] + vecs[2]).abs() < 1e-12);
    }
}
