//! Blocked products of the candidates' blocks with a few columns (the visits' and updates' GEMMs).

use super::*;

/// Candidates per blocked matrix product.
pub(super) const GEMM_CHUNK: usize = 256;

/// Products with at most this many columns use [`skinny_mul`] (a GEMM's packing costs more).
pub(super) const SKINNY_Q: usize = 24;

/// `out (m x q) = a (m x k) * w (k x q)`, all row-major.
pub(super) fn gemm(a: &[f64], m: usize, k: usize, w: &[f64], q: usize, out: &mut [f64]) {
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
    pub(super) fn products<T, F>(&self, members: &[usize], w: &[f64], q: usize, body: F) -> Vec<T>
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
    pub(super) fn gather(&self, chunk: &[usize]) -> std::borrow::Cow<'_, [f64]> {
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
    pub(super) fn products_chunks<T, F>(&self, members: &[usize], w: &[f64], q: usize, body: F) -> Vec<T>
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
pub(super) const PREFETCH_AHEAD: usize = 6;

/// Hint the processor to bring `x` into cache (scattered candidate blocks live in L3).
#[inline(always)]
pub(super) fn prefetch(x: &[f64]) {
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
